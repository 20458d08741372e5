"""The k-induction harness every time-multiplexed core shares (the Izhikevich and LIF cores: the
sweep issue, pipeline tags, memories and bookkeeping of :mod:`cuneate.hdl.lib.bookkeeping`),
against the block's one-step reference, for every input sequence of every length.

**What is proven.** The core beside a reference written against the documented contract:

* *sweeps*: a tick starts a sweep when none is being issued or in its last issuing cycle,
  otherwise it is ignored and sets ``overrun``; the sweep fetches neurons ``0 .. N-1``, one per
  cycle; the update fetched in cycle ``f`` leaves on ``upd_*`` in cycle ``f + L`` (``L`` the
  pipeline's latency), in index order;
* *host writes*: a write to a host memory (current, set, weights) in cycle ``c`` is in the
  memory from ``c + 1`` (where the core registers it on its way to the RAM, the memory seen
  is the RAM with that pending write over it); an update sees the memories as they are in
  its fetch cycle;
* *each update of the tracked neuron* ``t`` (any neuron: ``t`` is a free constant) equals one
  step of the block's stage functions, composed combinationally, from the state its previous
  update produced (or the memory's initial contents), the current and set the host wrote, and
  the block's other inputs as fetched;
* *bookkeeping*: ``sweep_done``, ``sweep_count``, ``sweep_number``, per-sweep clamp counters,
  sticky clamp flags, ``overrun``.

**Why the induction step closes** - the invariants asserted in every cycle:

* the contract's sweep model counts at most ``N`` neurons left (its counter is wider than that),
  and the issue counter agrees with it (issuing, address, sweep number; the increment and
  end test it keeps beside the address);
* each stage's tag (valid, index, sweep; the core's ``tags``) holds the fetch of ``k - 1``
  cycles before, for every stage ``k`` of the core's own tag list (``L`` is its last stage);
* every tracked memory word of ``t`` equals the reference's copy: the host memories the host's
  writes, the state the reference's last result from the cycle its write-back lands (with the
  result leaving, or ``state_write_lag`` cycles later for a core that registers the write),
  so this holds in every cycle, an update of ``t`` in flight or not;
* the bookkeeping counters equal the reference's.

The data registers between the stages need no invariant: they are a function of the last ``L``
cycles, so an induction of ``L + 1`` steps determines them.

**The tracked neuron.** The memories are not abstracted: they are the design's, with any
initial contents. The properties speak of one neuron ``t``, a free constant, so a proof holds
for every ``t`` at once. The sweep model, the tags and the bookkeeping do not depend on ``t``.
See docs/formal.md for why a proof at one ``N`` speaks for every ``N`` the configuration
accepts.

**Binding to the core.** The harness instantiates the block's core (with an external tick,
which it drives freely: every tick sequence, an internal divider's among them), drives its
ports and reads what the core records when elaborated (:class:`~cuneate.hdl.lib.bookkeeping
.SweepCore`: the issue counter, the tags, the memories, the pending registered writes, the
sweep counters); to read the tracked neuron's words it adds an asynchronous read port to each
memory, through a subclass of the core. The **mutants** are subclasses overriding one of the
core's documented hooks (``memory_write``: the state write-back skipped; ``stage_register``: a
stage register one neuron late; ``pipeline_tags``: the write-back stage's index one off), or a
wiring of the harness (``late_host_write``: the host's writes reach the core a cycle after the
reference takes them).
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

from amaranth import Array, ClockDomain, Elaboratable, Module, Mux, Signal
from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import Fragment

from .formal import UninterpretedProducts, assert_all, assume_all, delay_line, faulty_write

__all__ = ["SweepCoreProof", "MUTANTS"]

#: faults a harness can build into its core (never into the product): a state write-back
#: skipped (whenever the solver chooses), a stage register holding the previous neuron's
#: value, host writes landing one cycle late, the write-back addressed one neuron off
MUTANTS = ("skipped_write", "stage_off_by_one", "late_host_write", "tag_off_by_one")


class _SkippedWrite:
    """The state memory's write enable gated by a free bit: a write-back skipped whenever the
    solver chooses."""

    def memory_write(self, m, name, port):
        port = super().memory_write(m, name, port)
        return faulty_write(m, port, skip=AnySeq(1)) if name == "state_mem" else port


class _StageOffByOne:
    """The stage register ``OFF_BY_ONE`` (name, stage) one cycle late: the previous neuron's."""

    OFF_BY_ONE = None

    def stage_register(self, m, name, value, stage):
        r = super().stage_register(m, name, value, stage)
        if (name, stage) != self.OFF_BY_ONE:
            return r
        return super().stage_register(m, f"{name}_late", r, stage)


class _TagOffByOne:
    """The last stage's index one high: the write-back addressed one neuron off."""

    def pipeline_tags(self, m, issue, last_stage):
        tags = dict(super().pipeline_tags(m, issue, last_stage))
        valid, idx, swp = tags[last_stage]
        bad = Signal.like(idx, name="mutant_idx")
        m.d.comb += bad.eq(idx + 1)
        tags[last_stage] = (valid, bad, swp)
        return tags


_FAULTS = {"skipped_write": _SkippedWrite, "stage_off_by_one": _StageOffByOne,
           "tag_off_by_one": _TagOffByOne}


def _watched(core: type, names) -> type:
    """``core`` with an asynchronous read port on every bank of each memory of ``names``
    (``watch``: ``{name: [port of each bank]}``), added through the memories it records."""
    class Watched(core):
        def elaborate(self, platform):
            m = super().elaborate(platform)
            self.watch = {name: [bank.read_port(domain="comb") for bank in self.memories[name]]
                          for name in names}
            return m
    Watched.__name__ = f"Watched{core.__name__}"
    return Watched


class SweepCoreProof(Elaboratable):
    """Harness of a core built on :class:`~cuneate.hdl.lib.bookkeeping.SweepCore`; a block
    subclasses it with its core class and its one-step :meth:`reference`.

    Parameters
    ----------
    cfg
        The block's configuration (any tick source: the harness proves the core with an
        external tick and drives it freely, which covers the divider's ticks).
    mutant
        ``None`` or one of :data:`MUTANTS`: the fault built into the core for this run.
    core
        The core class to prove (default :attr:`core_class`): a subclass of it with a fault
        of its own (a test of the proof).
    """

    #: the block's core
    core_class: type = None
    clamp_kinds: tuple = ()
    #: host-written memories of every core and their write ports
    host_memories = {"cur_mem": "i_wr", "sel_mem": "sel_wr"}
    #: memories the pipeline writes back (each word is a result of the reference)
    state_memories = ("state_mem",)
    #: the stage register a ``stage_off_by_one`` mutant delays (name, stage)
    off_by_one_register = None

    def __init__(self, cfg, mutant: str | None = None, core: type | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.cfg, self.mutant = cfg, mutant
        self.core_cls = core or self.core_class
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]
        self.latency = None

    @property
    def induction_depth(self) -> int:
        """The k of the k-induction: the core's latency (read from its tags when elaborated)
        + 2, the data registers between the stages needing L + 1 cycles of history."""
        return self.latency + 2

    # --- what a block provides --------------------------------------------------------------
    def core_config(self):
        """The configuration of the core the harness elaborates: ``cfg`` with an external
        tick."""
        return dataclasses.replace(self.cfg, tick_source="external")

    def host_write_ports(self) -> dict:
        """``{memory: port prefix}`` of the host-written memories this core has."""
        return dict(self.host_memories)

    def read_only_memories(self) -> tuple:
        """Per-neuron memories neither the host nor the pipeline writes (LIF: fixed weights);
        their tracked word is whatever the memory starts with."""
        return ()

    def fetched_inputs(self, m, core, fetch) -> dict:
        """Inputs of an update besides the tracked memories' words, as the contract gives
        them in the fetch cycle (LIF: the tick's input spikes)."""
        return {}

    def reference(self, words: dict, inputs: dict) -> dict:
        """One update, combinational, from the tracked memories' ``words`` and ``inputs``:
        ``{"words": {state memory: next word}, "ports": {upd port: expected value}}``."""
        raise NotImplementedError

    # --- the harness ---------------------------------------------------------------------------
    def _make_core(self):
        cls = self.core_cls
        fault = _FAULTS.get(self.mutant)
        if fault is not None:
            cls = type(f"{fault.__name__[1:]}{cls.__name__}", (fault, cls),
                       {"OFF_BY_ONE": self.off_by_one_register})
        names = (*self.state_memories, *self.host_write_ports(), *self.read_only_memories())
        return _watched(cls, names)(self.core_config())

    def _host_writes(self, m, core, N) -> dict:
        """The host's writes, free (addresses in range, set indices valid): ``{memory: (en,
        addr, data)}`` as the reference takes them; the core's ports are driven with them
        (``late_host_write``: the current's a cycle later)."""
        writes = {}
        for name, prefix in self.host_write_ports().items():
            ports = [getattr(core, f"{prefix}_{x}") for x in ("en", "addr", "data")]
            free = [Signal.like(p, name=f"host_{prefix}_{x}")
                    for p, x in zip(ports, ("en", "addr", "data"))]
            m.d.comb += [f.eq(AnySeq(len(f))) for f in free]
            assume_all(m, [free[1] < N])
            wire = free
            if self.mutant == "late_host_write" and prefix == "i_wr":
                wire = [delay_line(m, f, 1, f"mutant_{f.name}")[1] for f in free]
            m.d.comb += [p.eq(w) for p, w in zip(ports, wire)]
            writes[name] = tuple(free)
        assume_all(m, [writes["sel_mem"][2] < len(self.cfg.param_sets)])
        return writes

    def _seen(self, m, core, t) -> dict:
        """Each watched memory's word at the tracked neuron ``t``: read in the bank that holds
        it (hdl/lib/banked.py), a host memory's with a write registered on its way to the RAM
        (read at the fetch) over it."""
        seen = {}
        for name, ports in core.watch.items():
            if len(ports) == 1:
                m.d.comb += ports[0].addr.eq(t)
                seen[name] = ports[0].data
                continue
            banks = core.memories[name]
            lo = (banks[0].depth - 1).bit_length()
            for port in ports:
                m.d.comb += port.addr.eq(t[:lo])
            word = Signal.like(ports[0].data, name=f"seen_{name}")
            m.d.comb += word.eq(Array(p.data for p in ports)[t[lo:]])
            seen[name] = word
        for name in self.host_write_ports():
            if name in core.pending_writes:
                en, addr, data = core.pending_writes[name]
                word = Signal.like(seen[name], name=f"seen_{name}_pending")
                m.d.comb += word.eq(Mux(en & (addr == t), data, seen[name]))
                seen[name] = word
        return seen

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        m.domains.sync = self.cd
        N = cfg.n_neurons
        self.products = UninterpretedProducts()
        t = Signal(range(N), name="tracked")
        m.d.comb += t.eq(AnyConst(range(N)))
        assume_all(m, [t < N])

        core = self._make_core()
        with self.products.role("design"):
            m.submodules.core = Fragment.get(core, platform)
        self.latency = max(core.tags)           # fetch in f, stage k in f + k - 1, out f + L
        tick = Signal(name="tick")
        m.d.comb += [tick.eq(AnySeq(1)), core.tick.eq(tick)]
        for name in ("clamp_clear", "spike_ready"):
            m.d.comb += getattr(core, name).eq(AnySeq(1))
        writes = self._host_writes(m, core, N)
        model = self._sweep_model(m, core, tick)
        flight = [model.dv[k] & (model.di[k] == t) for k in range(self.latency + 1)]
        self._tracked_neuron(m, core, writes, self._seen(m, core, t), t, flight)
        self._bookkeeping(m, core, model)
        return m

    def _sweep_model(self, m, core, tick):
        """The contract's sweeps, the issue counter and every stage's tag against them."""
        cfg, N, L = self.cfg, self.cfg.n_neurons, self.latency
        issue = core.issue
        left = Signal(range(N + 1), name="ref_left")
        overrun = Signal(name="ref_overrun")
        number = Signal(cfg.sweep_number_width, name="ref_sweep_no")
        started = Signal(name="ref_started")
        start = tick & (left <= 1)
        self.sweep_start = start
        with m.If(start):
            m.d.sync += [left.eq(N), started.eq(1), number.eq(Mux(started, number + 1, 0))]
        with m.Else():
            with m.If(left > 0):
                m.d.sync += left.eq(left - 1)
            with m.If(tick):
                m.d.sync += overrun.eq(1)
        fetch_valid = Signal(name="ref_fetch_valid")
        fetch_idx = Signal(range(N), name="ref_fetch_idx")
        m.d.comb += [fetch_valid.eq(left > 0), fetch_idx.eq(N - left)]
        dv = delay_line(m, fetch_valid, L, "ref_valid")
        di = delay_line(m, fetch_idx, L, "ref_idx")
        dn = delay_line(m, number, L, "ref_no")
        assert_all(m, [(left <= N, "sweep model: at most N neurons left"),
                       (issue.issuing == fetch_valid, "issue: busy as the sweep model"),
                       (~fetch_valid | (issue.addr == fetch_idx), "issue: neuron fetched"),
                       (issue.started == started, "issue: first sweep"),
                       (issue.sweep_no == number, "issue: sweep number"),
                       (issue.inc == issue.addr + 1, "issue: the address's increment"),
                       (issue.at_last == (issue.addr == N - 1), "issue: the last address")])
        for k, (valid, idx, swp) in sorted(core.tags.items()):
            assert_all(m, [(valid == dv[k - 1], f"stage {k}: valid"),
                           (~valid | (idx == di[k - 1]), f"stage {k}: neuron"),
                           (~valid | (swp == dn[k - 1]), f"stage {k}: sweep")])
        assert_all(m, [(core.upd_valid == dv[L], "update timing"),
                       (~dv[L] | (core.upd_index == di[L]), "update order")])
        return SimpleNamespace(dv=dv, di=di, dn=dn, overrun=overrun)

    def _tracked_neuron(self, m, core, writes, seen, t, flight):
        """Every memory word of the tracked neuron equals the reference's copy; each of its
        updates equals the reference's step."""
        L = self.latency
        primed = Signal(name="ref_primed")      # step 0: the reference takes the memories' words
        m.d.sync += primed.eq(1)
        words = {}
        for name, data in seen.items():
            r = Signal.like(data, name=f"ref_{name}")
            now = Signal.like(data, name=f"ref_{name}_now")
            m.d.comb += now.eq(Mux(primed, r, data))
            words[name] = (r, now)
            assert_all(m, [(data == now, f"memory {name}: tracked word")])
        held = {name: Signal.like(now, name=f"held_{name}") for name, (_, now) in words.items()}
        extra = self.fetched_inputs(m, core, flight[0])
        held_in = {}
        for name, value in extra.items():
            h = Signal.like(value, name=f"held_{name}")
            with m.If(flight[0]):
                m.d.sync += h.eq(value)
            held_in[name] = h
        with self.products.role("reference"):
            exp = self.reference(held, held_in)
        self.products.constrain(m, flight[0])
        for name, (en, addr, data) in writes.items():
            r, now = words[name]
            m.d.sync += r.eq(Mux(en & (addr == t), data, now))
        for name in self.read_only_memories():
            r, now = words[name]
            m.d.sync += r.eq(now)
        # the write-back is issued from the last stage (fetched L - 1 cycles ago) and lands at
        # the end of that cycle, or ``state_write_lag`` cycles later (a registered write)
        lag = getattr(core, "state_write_lag", 0)
        lands = flight[L - 1 + lag]
        for name in self.state_memories:
            r, now = words[name]
            m.d.sync += r.eq(Mux(lands, exp["words"][name], now))
        # the update takes the memories as they are in its fetch cycle; a core whose memories
        # sample at the end of the fetch (``state_sample_lag`` = 1: read from the fetch's
        # registered address) also sees a write-back landing then (in a reachable state the
        # tracked neuron's own write lands earlier: n_neurons > depth)
        fetched = {n: words[n][1] for n in held}
        if getattr(core, "state_sample_lag", 0):
            fetched.update({n: Mux(lands, exp["words"][n], words[n][1])
                            for n in self.state_memories})
        with m.If(flight[0]):
            m.d.sync += [held[n].eq(fetched[n]) for n in held]
        checks = [(~flight[L] | core.upd_valid & (core.upd_index == t), "tracked update leaves")]
        checks += [(~flight[L] | (getattr(core, port) == value), f"tracked update: {port}")
                   for port, value in exp["ports"].items()]
        assert_all(m, checks)

    def _bookkeeping(self, m, core, model):
        """The sweep counters, the sticky clamp flags and ``overrun`` against the reference's
        count of the updates leaving."""
        cfg, N, L = self.cfg, self.cfg.n_neurons, self.latency
        done = Signal(name="ref_sweep_done")
        count = Signal(range(N + 1), name="ref_count")
        total = Signal(range(N + 1), name="ref_total")
        last_no = Signal(cfg.sweep_number_width, name="ref_last_no")
        last = core.upd_valid & (core.upd_index == N - 1)
        m.d.sync += done.eq(last)
        kinds = self.clamp_kinds
        counts = [Signal(range(N + 1), name=f"ref_clamps_{k}") for k in kinds]
        totals = [Signal(range(N + 1), name=f"ref_clamps_total_{k}") for k in kinds]
        with m.If(last):
            m.d.sync += [count.eq(0), total.eq(count + core.upd_spike), last_no.eq(model.dn[L])]
            m.d.sync += [c.eq(0) for c in counts]
            m.d.sync += [tt.eq(c + core.upd_clamp[i]) for i, (c, tt) in
                         enumerate(zip(counts, totals))]
        with m.Elif(core.upd_valid):
            m.d.sync += count.eq(count + core.upd_spike)
            m.d.sync += [c.eq(c + core.upd_clamp[i]) for i, c in enumerate(counts)]
        sticky = Signal(len(kinds), name="ref_clamp_flags")
        m.d.sync += sticky.eq(Mux(core.clamp_clear, 0, sticky) | core.upd_clamp)
        checks = [(core.sweep_done == done, "sweep_done"),
                  (core.sweep_count == total, "sweep_count"),
                  (core.counters.spikes == count, "spike count so far"),
                  (core.clamp_flags == sticky, "clamp_flags"),
                  (core.overrun == model.overrun, "overrun"),
                  (core.sweep_number == last_no, "sweep_number")]
        for k, c, tt in zip(kinds, counts, totals):
            checks += [(getattr(core, f"sweep_clamps_{k}") == tt, f"sweep_clamps_{k}"),
                       (core.counters.clamps[k] == c, f"clamp count {k} so far")]
        assert_all(m, checks)
