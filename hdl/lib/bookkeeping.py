"""RTL every time-multiplexed core shares: the sweep issue counter, the pipeline tags, per-sweep
spike and clamp counters, sticky clamp flags and the spike FIFO.

The Izhikevich and LIF cores issue one neuron per clock from a tick; each update leaves the
pipeline on the core's ``upd_*`` probe ports, from which the bookkeeping below counts spikes and
clamps per sweep, keeps sticky clamp flags and queues spikes for the host. The port names are
the contract of both cores (see :class:`cuneate.hdl.izhikevich.IzhikevichCore`):

``busy``, ``overrun``
    a sweep is being issued; a tick arrived while one was (ignored, sticky flag).
``sweep_done``, ``sweep_count``, ``sweep_number``, ``sweep_clamps_<kind>``
    pulse in the cycle after the last update of a sweep left the pipeline, with that sweep's
    spike count, number and clamp counts per kind.
``clamp_flags``, ``clamp_clear``
    sticky clamp flags (bit per kind); a clamp in the clearing cycle keeps its flag set.
``spike_valid``, ``spike_ready``, ``spike_index``, ``spike_sweep``, ``spike_overflow``
    the spike FIFO; a spike that finds it full is dropped and sets the sticky overflow flag.

Both cores derive from :class:`SweepCore`: its methods are the hooks through which a proof
harness builds its faults, its attributes what the harness reads after elaboration.
"""

from __future__ import annotations

from types import SimpleNamespace

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .banked import prefetched_memory

__all__ = ["SweepCore", "SweepIssue", "sweep_issue", "pipeline_tags", "sweep_bookkeeping",
           "SweepCounters", "CoreMemories", "core_memories", "core_ports"]


class SweepCore(wiring.Component):
    """Base of the time-multiplexed cores (the Izhikevich and LIF cores).

    **Hooks.** A core forms its pipeline tags (:meth:`pipeline_tags`), its stage registers
    (:meth:`stage_register`) and its state memory's write (:meth:`memory_write`) through these
    methods; a subclass may override them - the faults a proof must catch
    (:mod:`cuneate.hdl.lib.core_proof`). The product's cores use them as written here.

    **What a core records** when elaborated, for a proof harness (nothing else reads them):
    ``issue`` (:class:`SweepIssue`), ``tags`` (``{stage: (valid, index, sweep)}`` as the core
    uses them), ``memories`` (``{name: [Memory of each bank]}`` of every per-neuron memory),
    ``pending_writes`` (``{name: (en, addr, data)}`` of a write registered on its way to a
    RAM) and ``counters`` (:class:`SweepCounters`).
    """

    #: data registers without a reset (their validity travels in the tags)
    DATA_RESET_LESS = False

    def pipeline_tags(self, m: Module, issue: SweepIssue, last_stage: int) -> dict:
        """The tags of stages 2 .. ``last_stage`` (:func:`pipeline_tags`)."""
        return pipeline_tags(m, self.cfg.n_neurons, self.cfg.sweep_number_width, issue,
                             last_stage)

    def stage_register(self, m: Module, name: str, value, stage: int) -> Signal:
        """The pipeline register ``<name><stage>`` loaded with ``value`` every cycle."""
        s = Signal(value.shape(), name=f"{name}{stage}", reset_less=self.DATA_RESET_LESS)
        m.d.sync += s.eq(value)
        return s

    def memory_write(self, m: Module, name: str, port):
        """The write port (``addr``, ``data``, ``en``) through which the pipeline writes the
        memory ``name``: ``port`` itself."""
        return port


def core_ports(cfg, clamp_kinds, state_ports: dict, extra: dict | None = None) -> dict:
    """The ports every core has (host writes, spike stream, the ``upd_*`` probe, sweep
    counters, sticky clamp flags, ``overrun``, ``busy``, per-kind clamp counters and, with an
    external tick, ``tick``), with the block's ``state_ports`` (its ``upd_<state>`` outputs,
    after ``upd_index``) and ``extra`` ports."""
    N = cfg.n_neurons
    sig = {
        "i_wr_en": In(1), "i_wr_addr": In(range(N)), "i_wr_data": In(cfg.I.shape()),
        "sel_wr_en": In(1), "sel_wr_addr": In(range(N)), "sel_wr_data": In(cfg.sel_bits),
        "spike_valid": Out(1), "spike_ready": In(1), "spike_index": Out(range(N)),
        "spike_sweep": Out(cfg.sweep_number_width), "spike_overflow": Out(1),
        "upd_valid": Out(1), "upd_index": Out(range(N)), **state_ports,
        "upd_current": Out(cfg.I.shape()), "upd_spike": Out(1),
        "upd_clamp": Out(len(clamp_kinds)),
        "clamp_flags": Out(len(clamp_kinds)), "clamp_clear": In(1),
        "sweep_done": Out(1), "sweep_count": Out(range(N + 1)),
        "sweep_number": Out(cfg.sweep_number_width), "overrun": Out(1), "busy": Out(1),
    }
    sig.update(extra or {})
    for k in clamp_kinds:
        sig[f"sweep_clamps_{k}"] = Out(range(N + 1))
    if cfg.tick_source == "external":
        sig["tick"] = In(1)
    return sig


class CoreMemories:
    """What :func:`core_memories` built: the state's read port and write port (``state``,
    ``state_write``: ``addr``, ``data``, ``en``), the current's and the set's read ports
    (``current``, ``set``), ``banks`` (``{name: [Memory of each bank]}``) and ``pending``
    (``{name: (en, addr, data)}`` of each write registered on its way to the RAM)."""

    def __init__(self, state, state_write, current, set_, banks, pending):
        self.state, self.state_write, self.current, self.set = state, state_write, current, set_
        self.banks, self.pending = banks, pending


def core_memories(m: Module, core, cfg, state_width: int, state_init: list,
                  state_attrs: dict | None = None, prefetch=None,
                  host_write_register: bool = False) -> CoreMemories:
    """The per-neuron memories every core has: the state (``state_width`` bits, ``state_init``,
    ``state_attrs`` for synthesis), the host-written current and the parameter-set index, with
    the host write ports (``i_wr_*``, ``sel_wr_*``) wired (:class:`CoreMemories`).

    ``prefetch`` (the issue's :attr:`SweepIssue.next_addr`): the memories are
    :func:`~cuneate.hdl.lib.banked.prefetched_memory` banks in ``cfg.bram_shapes``, read one
    cycle ahead and registered beside the block RAM, each with a write bypass (an update sees
    the memories as they are in its fetch cycle); the read ports returned then carry only
    ``data``, valid in the cycle a synchronous read at the fetch would have it. The state's
    write is registered before its RAM and lands a cycle after it is issued, at the latest
    with the neuron's next read, a cycle ahead of its next fetch: ``n_neurons >= depth + 1``
    (the core sets ``state_write_lag = 1``).

    ``prefetch`` may also be the issue's registered :attr:`SweepIssue.addr` (a read at the
    fetch, addressed from a register: the words come a cycle later) with
    ``host_write_register``: the host's writes are then registered before their RAMs too, so
    that the memories sample and take writes a cycle later than with ``next_addr`` and an
    update still sees them as they are in its fetch cycle."""
    N = cfg.n_neurons
    if prefetch is not None:
        shapes = cfg.bram_shapes
        st = prefetched_memory(m, "state_mem", state_width, N, state_init, prefetch, shapes,
                               bypass=True, write_register=True, attrs=state_attrs)
        cur = prefetched_memory(m, "cur_mem", cfg.I.shape(), N, [], prefetch, shapes,
                                bypass=True, write_register=host_write_register)
        sel = prefetched_memory(m, "sel_mem", cfg.sel_bits, N, cfg.neuron_sets, prefetch,
                                shapes, bypass=True, write_register=host_write_register)
        m.d.comb += [
            cur.wr_addr.eq(core.i_wr_addr), cur.wr_data.eq(core.i_wr_data),
            cur.wr_en.eq(core.i_wr_en),
            sel.wr_addr.eq(core.sel_wr_addr), sel.wr_data.eq(core.sel_wr_data),
            sel.wr_en.eq(core.sel_wr_en),
        ]
        st_wr = SimpleNamespace(addr=st.wr_addr, data=st.wr_data, en=st.wr_en)
        mems = {"state_mem": st, "cur_mem": cur, "sel_mem": sel}
        return CoreMemories(SimpleNamespace(data=st.data), st_wr,
                            SimpleNamespace(data=cur.data), SimpleNamespace(data=sel.data),
                            {name: mem.banks for name, mem in mems.items()},
                            {name: mem.pending for name, mem in mems.items()
                             if mem.pending is not None})
    m.submodules.state_mem = state_mem = Memory(shape=state_width, depth=N, init=state_init,
                                                attrs=state_attrs)
    m.submodules.cur_mem = cur_mem = Memory(shape=cfg.I.shape(), depth=N, init=[])
    m.submodules.sel_mem = sel_mem = Memory(shape=cfg.sel_bits, depth=N, init=cfg.neuron_sets)
    st_rd, st_wr = state_mem.read_port(), state_mem.write_port()
    cur_rd, cur_wr = cur_mem.read_port(), cur_mem.write_port()
    sel_rd, sel_wr = sel_mem.read_port(), sel_mem.write_port()
    m.d.comb += [
        cur_wr.addr.eq(core.i_wr_addr), cur_wr.data.eq(core.i_wr_data),
        cur_wr.en.eq(core.i_wr_en),
        sel_wr.addr.eq(core.sel_wr_addr), sel_wr.data.eq(core.sel_wr_data),
        sel_wr.en.eq(core.sel_wr_en),
    ]
    return CoreMemories(st_rd, st_wr, cur_rd, sel_rd,
                        {"state_mem": [state_mem], "cur_mem": [cur_mem], "sel_mem": [sel_mem]},
                        {})


class SweepIssue:
    """The issue counter's signals: ``start`` (a sweep starts this cycle), ``issuing``,
    ``addr`` (the neuron issued), ``sweep_no`` (the sweep's number), ``next_addr`` (what
    ``addr`` holds in the next cycle: the address a memory read one cycle ahead takes),
    ``inc`` and ``at_last`` (registers kept equal to ``addr + 1`` and ``addr == N - 1``),
    ``started`` (a sweep has started since reset: the first sweep is number 0)."""

    def __init__(self, start, issuing, addr, sweep_no, next_addr, inc=None, at_last=None,
                 started=None):
        self.start, self.issuing, self.addr, self.sweep_no = start, issuing, addr, sweep_no
        self.next_addr, self.inc, self.at_last, self.started = next_addr, inc, at_last, started


def sweep_issue(m: Module, core, n_neurons: int, tick, number_width: int) -> SweepIssue:
    """Issue neurons ``0 .. n_neurons - 1``, one per clock, from each ``tick``; a tick while a
    sweep is still being issued sets ``core.overrun`` (a tick in the last issuing cycle is on
    time). Drives ``core.busy``."""
    N = n_neurons
    issuing = Signal()
    addr = Signal(range(N))
    sweep_no = Signal(number_width)
    started = Signal()
    # addr + 1 and addr == N - 1, registered beside addr: the next address (the memories'
    # read address, a cycle ahead) is two multiplexers from registers and the tick, and so
    # are the next increment and end test (their adder and comparator work on ``inc``, a
    # register, beside the tick's multiplexers)
    inc = Signal(range(N + 1), init=1, name="addr_inc")
    at_last = Signal(init=int(N == 1), name="addr_at_last")
    last_issue = issuing & at_last
    advance = issuing & ~at_last
    start = tick & (~issuing | last_issue)
    next_addr = Signal(range(N), name="next_addr")
    m.d.comb += next_addr.eq(Mux(start, 0, Mux(advance, inc, addr)))
    m.d.sync += [addr.eq(next_addr),
                 inc.eq(Mux(start, 1, Mux(advance, inc + 1, inc))),
                 at_last.eq(Mux(start, int(N == 1), Mux(advance, inc == N - 1, at_last)))]
    with m.If(tick & ~start):
        m.d.sync += core.overrun.eq(1)
    with m.If(start):
        m.d.sync += [issuing.eq(1), started.eq(1),
                     sweep_no.eq(Mux(started, sweep_no + 1, 0))]
    with m.Elif(issuing & last_issue):
        m.d.sync += issuing.eq(0)
    m.d.comb += core.busy.eq(issuing)
    return SweepIssue(start, issuing, addr, sweep_no, next_addr, inc, at_last, started)


def pipeline_tags(m: Module, n_neurons: int, number_width: int, issue: SweepIssue,
                  last_stage: int = 5) -> dict:
    """``{stage: (valid, index, sweep)}`` registers that carry each issued neuron from stage 2
    to ``last_stage`` beside its data."""
    tags = {n: (Signal(name=f"valid{n}"), Signal(range(n_neurons), name=f"idx{n}"),
                Signal(number_width, name=f"swp{n}")) for n in range(2, last_stage + 1)}
    t2 = tags[2]
    m.d.sync += [t2[0].eq(issue.issuing), t2[1].eq(issue.addr), t2[2].eq(issue.sweep_no)]
    for n in range(2, last_stage):
        a, b = tags[n], tags[n + 1]
        m.d.sync += [b[0].eq(a[0]), b[1].eq(a[1]), b[2].eq(a[2])]
    return tags


class SweepCounters:
    """The counters of the sweep in progress :func:`sweep_bookkeeping` keeps: ``spikes`` (spikes
    so far) and ``clamps`` (``{kind: clamps so far}``)."""

    def __init__(self, spikes, clamps: dict):
        self.spikes, self.clamps = spikes, clamps


def sweep_bookkeeping(m: Module, core, n_neurons: int, number_width: int, last_tag,
                      clamp_kinds, fifo_depth: int) -> SweepCounters:
    """Per-sweep spike and clamp counters, sticky clamp flags and the spike FIFO, all fed from
    the core's registered ``upd_*`` outputs (off the datapath's critical path); ``last_tag`` is
    the last stage's ``(valid, index, sweep)``, which the core registers into ``upd_valid``
    and ``upd_index``. Returns the counters of the sweep in progress."""
    N = n_neurons
    upd_sweep = Signal(number_width)
    m.d.sync += upd_sweep.eq(last_tag[2])
    count = Signal(range(N + 1))
    # the sweep's last update on upd_*, registered beside upd_valid and upd_index from the
    # last stage's tag (the index comparison does not sit before every counter's adder)
    last = Signal(name="upd_last")
    m.d.sync += last.eq(last_tag[0] & (last_tag[1] == N - 1))
    m.d.sync += core.sweep_done.eq(last)
    with m.If(last):
        m.d.sync += [core.sweep_count.eq(count + core.upd_spike),
                     core.sweep_number.eq(upd_sweep), count.eq(0)]
    with m.Elif(core.upd_valid):
        m.d.sync += count.eq(count + core.upd_spike)
    clamps = {}
    for i, k in enumerate(clamp_kinds):
        cnt = clamps[k] = Signal(range(N + 1), name=f"clamp_count_{k}")
        with m.If(last):
            m.d.sync += [getattr(core, f"sweep_clamps_{k}").eq(cnt + core.upd_clamp[i]),
                         cnt.eq(0)]
        with m.Elif(core.upd_valid):
            m.d.sync += cnt.eq(cnt + core.upd_clamp[i])
    m.d.sync += core.clamp_flags.eq(Mux(core.clamp_clear, 0, core.clamp_flags)
                                    | core.upd_clamp)
    # spike stream
    iw = (N - 1).bit_length() or 1
    m.submodules.spike_fifo = fifo = SyncFIFOBuffered(width=iw + number_width, depth=fifo_depth)
    push = core.upd_valid & core.upd_spike
    m.d.comb += [fifo.w_data.eq(Cat(core.upd_index[:iw], upd_sweep)), fifo.w_en.eq(push),
                 core.spike_valid.eq(fifo.r_rdy), fifo.r_en.eq(core.spike_ready),
                 core.spike_index.eq(fifo.r_data[:iw]),
                 core.spike_sweep.eq(fifo.r_data[iw:])]
    with m.If(push & ~fifo.w_rdy):
        m.d.sync += core.spike_overflow.eq(1)
    return SweepCounters(count, clamps)
