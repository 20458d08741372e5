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
* each stage's tag (valid, index, sweep; ``pipeline_tags``) holds the fetch of ``k - 1`` cycles
  before, for every stage ``k`` of the core's own tag list (``L`` is its last stage);
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
"""

from __future__ import annotations

import contextlib
from types import SimpleNamespace

from amaranth import Array, ClockDomain, Elaboratable, Module, Mux, Signal
from amaranth.hdl import Fragment
from amaranth.hdl._ast import AnyConst, AnySeq

from .formal import (UninterpretedProducts, assert_all, assume_all, delay_line, patched,
                     signal_named)

__all__ = ["SweepCoreProof", "MUTANTS"]

#: faults a harness can build into its core (never into the product): a state write-back
#: skipped (whenever the solver chooses), a stage register holding the previous neuron's
#: value, host writes landing one cycle late, the write-back addressed one neuron off
MUTANTS = ("skipped_write", "stage_off_by_one", "late_host_write", "tag_off_by_one")


class SweepCoreProof(Elaboratable):
    """Harness of a core built on :mod:`cuneate.hdl.lib.bookkeeping`; a block subclasses it
    with its core, its datapath files and its one-step :meth:`reference`.

    Parameters
    ----------
    cfg
        The block's configuration (any tick source: the harness drives the tick freely, which
        covers the divider's ticks).
    mutant
        ``None`` or one of :data:`MUTANTS`: the fault built into the core for this run.
    """

    #: the module whose helpers the core calls (wrapped while the core elaborates)
    core_module = None
    #: source files whose products are uninterpreted
    datapath_files: tuple = ()
    clamp_kinds: tuple = ()
    #: host-written memories of every core and their write ports
    host_memories = {"cur_mem": "i_wr", "sel_mem": "sel_wr"}
    #: memories the pipeline writes back (each word is a result of the reference)
    state_memories = ("state_mem",)
    #: the stage register a ``stage_off_by_one`` mutant delays (name, stage)
    off_by_one_register = None

    def __init__(self, cfg, mutant: str | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.cfg, self.mutant = cfg, mutant
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]
        self.latency = None

    # --- what a block provides --------------------------------------------------------------
    def make_core(self):
        raise NotImplementedError

    def host_write_ports(self, core) -> dict:
        """``{memory: port prefix}`` of the host-written memories this core has."""
        return dict(self.host_memories)

    def read_only_memories(self, core) -> tuple:
        """Per-neuron memories neither the host nor the pipeline writes (LIF: fixed weights);
        their tracked word is whatever the memory starts with."""
        return ()

    def fetched_inputs(self, m, core, frag, fetch) -> dict:
        """Inputs of an update besides the tracked memories' words, as the contract gives
        them in the fetch cycle (LIF: the tick's input spikes)."""
        return {}

    def reference(self, words: dict, inputs: dict) -> dict:
        """One update, combinational, from the tracked memories' ``words`` and ``inputs``:
        ``{"words": {state memory: next word}, "ports": {upd port: expected value}}``."""
        raise NotImplementedError

    def extra_invariants(self, m, core, frag, ref) -> None:
        """Block-specific invariants (state the block's core keeps beside the shared one)."""

    # --- the harness ---------------------------------------------------------------------------
    def _elaborate_core(self, platform, tick):
        core = self.make_core()
        core._MustUse__silence = True
        rec = SimpleNamespace(issue=None, tags=None, pending={})
        mut = self.mutant
        ns = self.core_module

        def rec_issue(orig):
            def f(*a, **k):
                rec.issue = orig(*a, **k)
                return rec.issue
            return f

        def rec_tags(orig):
            def f(m, *a, **k):
                rec.tags = orig(m, *a, **k)
                if mut == "tag_off_by_one":           # the write-back stage's index + 1
                    last = max(rec.tags)
                    valid, idx, swp = rec.tags[last]
                    bad = Signal.like(idx, name="mutant_idx")
                    m.d.comb += bad.eq(idx + 1)
                    rec.tags = dict(rec.tags)
                    rec.tags[last] = (valid, bad, swp)
                return rec.tags
            return f

        def free_tick(orig):
            return lambda m, cfg, tick_in=None: tick

        def registrar(orig):
            def f(m, *args, **kwargs):
                reg = orig(m, *args, **kwargs)

                def faulty(name, value, stage):
                    r = reg(name, value, stage)
                    if (name, stage) != self.off_by_one_register:
                        return r
                    return reg(f"{name}_late", r, stage)   # one more cycle: previous neuron
                return faulty
            return f

        def memories(orig):
            def f(m, core_, *a, **k):
                view = core_
                if mut == "late_host_write":
                    view = SimpleNamespace(**{n: getattr(core_, n) for n in
                                              ("sel_wr_en", "sel_wr_addr", "sel_wr_data")})
                    for n in ("i_wr_en", "i_wr_addr", "i_wr_data"):
                        d = Signal.like(getattr(core_, n), name=f"mutant_{n}")
                        m.d.sync += d.eq(getattr(core_, n))
                        setattr(view, n, d)
                st_rd, st_wr, cur_rd, sel_rd = orig(m, view, *a, **k)
                for name, rd in (("cur_mem", cur_rd), ("sel_mem", sel_rd)):
                    if getattr(rd, "pending", None) is not None:
                        rec.pending[name] = rd.pending
                if mut == "skipped_write":
                    skip = Signal(name="mutant_skip")
                    m.d.comb += skip.eq(AnySeq(1))
                    fake = SimpleNamespace(addr=Signal.like(st_wr.addr, name="mutant_wr_addr"),
                                           data=Signal.like(st_wr.data, name="mutant_wr_data"),
                                           en=Signal(name="mutant_wr_en"))
                    m.d.comb += [st_wr.addr.eq(fake.addr), st_wr.data.eq(fake.data),
                                 st_wr.en.eq(fake.en & ~skip)]
                    st_wr = fake
                return st_rd, st_wr, cur_rd, sel_rd
            return f

        wraps = [("sweep_issue", rec_issue), ("pipeline_tags", rec_tags),
                 ("tick_strobe", free_tick), ("core_memories", memories)]
        if mut == "stage_off_by_one":
            wraps.append(("registrar", registrar))
        with contextlib.ExitStack() as stack:
            for name, w in wraps:
                stack.enter_context(patched(ns, name, w))
            stack.enter_context(self.products.role("design"))
            core_m = core.elaborate(platform)
        return core, core_m, rec

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        m.domains.sync = self.cd
        N = cfg.n_neurons
        self.products = UninterpretedProducts(self.datapath_files)
        tick = Signal(name="tick")
        m.d.comb += tick.eq(AnySeq(1))
        t = Signal(range(N), name="tracked")
        m.d.comb += t.eq(AnyConst(range(N)))
        assume_all(m, [t < N])

        core, core_m, rec = self._elaborate_core(platform, tick)
        # one asynchronous read port at the tracked neuron on each memory (observation only);
        # a memory in banks (hdl/lib/banked.py: ``name``, ``name_1`` ...) is read in the bank
        # that holds the tracked neuron
        seen = {}
        for name in (*self.state_memories, *self.host_write_ports(core),
                     *self.read_only_memories(core)):
            banks = [core_m.submodules[name]]
            while True:
                try:
                    banks.append(core_m.submodules[f"{name}_{len(banks)}"])
                except (AttributeError, KeyError, NameError):
                    break
            ports = [bank.read_port(domain="comb") for bank in banks]
            if len(ports) == 1:
                m.d.comb += ports[0].addr.eq(t)
                seen[name] = ports[0].data
                continue
            lo = (banks[0].depth - 1).bit_length()
            for port in ports:
                m.d.comb += port.addr.eq(t[:lo])
            word = Signal.like(ports[0].data, name=f"seen_{name}")
            m.d.comb += word.eq(Array(p.data for p in ports)[t[lo:]])
            seen[name] = word
        # a host memory whose writes are registered on their way to the RAM (read at the
        # fetch, hdl/lib/banked.py): its word is the RAM's with the pending write over it
        for name, (en, addr, data) in rec.pending.items():
            word = Signal.like(seen[name], name=f"seen_{name}_pending")
            m.d.comb += word.eq(Mux(en & (addr == t), data, seen[name]))
            seen[name] = word
        frag = Fragment.get(core_m, platform)
        m.submodules.core = frag
        tags, issue = rec.tags, rec.issue
        L = self.latency = max(tags)                  # fetch in f, stage k in f + k - 1, out f + L

        # free host inputs (addresses in range, set indices valid)
        for name, prefix in self.host_write_ports(core).items():
            addr = getattr(core, f"{prefix}_addr")
            m.d.comb += [getattr(core, f"{prefix}_{x}").eq(AnySeq(len(getattr(core, f"{prefix}_{x}"))))
                         for x in ("en", "addr", "data")]
            assume_all(m, [addr < N])
        n_sets = len(cfg.param_sets)
        assume_all(m, [core.sel_wr_data < n_sets])
        for name in ("clamp_clear", "spike_ready"):
            m.d.comb += getattr(core, name).eq(AnySeq(1))

        # --- the contract's sweeps ----------------------------------------------------------
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
        core_started = signal_named(frag, "started")
        assert_all(m, [(left <= N, "sweep model: at most N neurons left"),
                       (issue.issuing == fetch_valid, "issue: busy as the sweep model"),
                       (~fetch_valid | (issue.addr == fetch_idx), "issue: neuron fetched"),
                       (core_started == started, "issue: first sweep"),
                       (issue.sweep_no == number, "issue: sweep number"),
                       (issue.inc == issue.addr + 1, "issue: the address's increment"),
                       (issue.at_last == (issue.addr == N - 1), "issue: the last address")])
        for k, (valid, idx, swp) in sorted(tags.items()):
            assert_all(m, [(valid == dv[k - 1], f"stage {k}: valid"),
                           (~valid | (idx == di[k - 1]), f"stage {k}: neuron"),
                           (~valid | (swp == dn[k - 1]), f"stage {k}: sweep")])
        assert_all(m, [(core.upd_valid == dv[L], "update timing"),
                       (~dv[L] | (core.upd_index == di[L]), "update order")])

        # --- the tracked neuron ---------------------------------------------------------------
        primed = Signal(name="ref_primed")      # step 0: the reference takes the memories' words
        m.d.sync += primed.eq(1)
        flight = [dv[k] & (di[k] == t) for k in range(L + 1)]   # fetched k cycles ago
        words = {}
        for name, data in seen.items():
            r = Signal.like(data, name=f"ref_{name}")
            now = Signal.like(data, name=f"ref_{name}_now")
            m.d.comb += now.eq(Mux(primed, r, data))
            words[name] = (r, now)
            assert_all(m, [(data == now, f"memory {name}: tracked word")])
        held = {name: Signal.like(now, name=f"held_{name}") for name, (_, now) in words.items()}
        extra = self.fetched_inputs(m, core, frag, flight[0])
        held_in = {}
        for name, value in extra.items():
            h = Signal.like(value, name=f"held_{name}")
            with m.If(flight[0]):
                m.d.sync += h.eq(value)
            held_in[name] = h
        with self.products.role("reference"):
            exp = self.reference(held, held_in)
        self.products.constrain(m, flight[0])
        for name, prefix in self.host_write_ports(core).items():
            r, now = words[name]
            en, addr, data = (getattr(core, f"{prefix}_{x}") for x in ("en", "addr", "data"))
            m.d.sync += r.eq(Mux(en & (addr == t), data, now))
        for name in self.read_only_memories(core):
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
        at_end = getattr(core, "state_sample_lag", 0)
        fetched = {n: words[n][1] for n in held}
        if at_end:
            fetched.update({n: Mux(lands, exp["words"][n], words[n][1])
                            for n in self.state_memories})
        with m.If(flight[0]):
            m.d.sync += [held[n].eq(fetched[n]) for n in held]
        checks = [(~flight[L] | core.upd_valid & (core.upd_index == t), "tracked update leaves")]
        checks += [(~flight[L] | (getattr(core, port) == value), f"tracked update: {port}")
                   for port, value in exp["ports"].items()]
        assert_all(m, checks)

        # --- bookkeeping ------------------------------------------------------------------------
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
            m.d.sync += [count.eq(0), total.eq(count + core.upd_spike), last_no.eq(dn[L])]
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
                  (signal_named(frag, "count") == count, "spike count so far"),
                  (core.clamp_flags == sticky, "clamp_flags"),
                  (core.overrun == overrun, "overrun"),
                  (core.sweep_number == last_no, "sweep_number")]
        for k, c, tt in zip(kinds, counts, totals):
            checks += [(getattr(core, f"sweep_clamps_{k}") == tt, f"sweep_clamps_{k}"),
                       (signal_named(frag, f"clamp_count_{k}") == c, f"clamp count {k} so far")]
        assert_all(m, checks)
        self.extra_invariants(m, core, frag, SimpleNamespace(start=start, tick=tick, t=t,
                                                             flight=flight))
        return m

