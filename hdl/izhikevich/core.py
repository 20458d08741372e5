"""The Izhikevich core's RTL: a time-multiplexed, pipelined Amaranth component built from the
datapath's pipelined steps (:data:`cuneate.hdl.izhikevich.datapath.STEPS`), registered at the
cuts its depth chooses, and its Verilog.

Latency ``pipeline_stages`` cycles (5 by default: fetch, registered read, operands and first
multipliers, second multipliers, update and write-back), then one neuron update per clock;
formats from :class:`~cuneate.hdl.izhikevich.config.IzhikevichConfig`.
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib.wiring import Out

from ..flow.verilog import write_block, verilog_text
from ..lib.bookkeeping import (SweepCore, core_memories, core_ports, sweep_bookkeeping,
                               sweep_issue)
from ..lib.fixed import is_hdl
from ..lib.tick import tick_strobe
from .config import CLAMP_KINDS, IzhikevichConfig
from . import datapath

__all__ = ["IzhikevichCore", "izhikevich_verilog", "generate_izhikevich"]


class IzhikevichCore(SweepCore):
    """Time-multiplexed Izhikevich core: one neuron update per clock, a pipeline of
    ``config.pipeline_stages`` stages (5 by default, up to 9).

    Pipeline (a neuron's index enters at cycle t; its result is on ``upd_*`` at t + D, D the
    depth):

    1. **Fetch** - the sweep counter issues the neuron; its memories (state v, u; current;
       set) were addressed in the cycle before (``next_addr``), in banks of the block RAM's
       shape (:mod:`cuneate.hdl.lib.banked`), each bank's word registered beside its RAM.
       At depth 9 they are addressed now, from the fetch's register (``addr``), and the
       host's writes are registered before their RAMs: the words come a stage later
       (:data:`~cuneate.hdl.izhikevich.config.PIPELINE_READ`), the address pins start at a
       register.
    2. **Read** (2 and 3 at depth 9) - bank multiplexer and write bypass into the first
       datapath stage's registers (``v3``, ``u3``, ``i3``, ``sel3``; ``v4`` ... at depth 9);
       at depths 5-7 the operands step too, registered with them.
    3. .. D. **Datapath** - the steps of :data:`~cuneate.hdl.izhikevich.datapath.STEPS`
       (0 operands, 1 multiply 1, 2 align, 3 multiply 2, 4 sums, 5 select), with a register
       after each step listed in ``config.cuts`` (:data:`~cuneate.hdl.izhikevich.config
       .PIPELINE_CUTS`):

       ======  ===================================================  ==========================
       depth   datapath stages (operands in the read stage unless   cuts (after step)
               cut 0)
       ======  ===================================================  ==========================
       5       multiply1+align | multiply2 | sums+select            2, 3
       6       multiply1+align | multiply2 | sums | select          2, 3, 4
       7       multiply1 | align | multiply2 | sums | select        1, 2, 3, 4
       8       operands | multiply1 | align | multiply2 | sums |sel 0, 1, 2, 3, 4
       9       as 8, after two read stages                          0, 1, 2, 3, 4
       ======  ===================================================  ==========================

       Every multiplier takes registers (floors: slices, no adder in front) and is followed
       by at most one operand-wide adder (at depths 8 and 9 by none). The last stage
       registers the new state's write (it lands in the RAM a cycle later) and ``upd_*``.
       Measured out of context on the LFE5U-85F -6 with the block RAMs' and multipliers'
       registers packed (docs/architecture.md, three placement seeds each).

    **Registers and hazards.** A value computed in stage ``s`` and still read later is
    registered at each cut as ``<name><s+1>`` (reset-less: data registers; the valid bit,
    index and sweep number of each stage are the tags ``valid<s>``, ``idx<s>``, ``swp<s>``
    of :func:`~cuneate.hdl.lib.bookkeeping.pipeline_tags`, with reset). The neuron in stage
    ``s`` at cycle ``c`` is the one fetched at ``c - s + 1``; its memories are sampled at the
    end of the cycle before its fetch (at depth 9: of the fetch, every write landing a cycle
    later), a write landing then replaced by the bypass, so an update sees the memories as
    they are in its fetch cycle. Its state's write is issued in
    stage D (cycle ``fetch + D - 1``) and lands a cycle later; the next sample of that neuron,
    at the earliest ``n_neurons - 1`` cycles after its fetch (back-to-back sweeps; at depth 9
    ``n_neurons``), sees it when ``n_neurons >= D + 1`` (at depth 9 ``D``; the configuration
    refuses less, :func:`~cuneate.hdl.izhikevich.config.min_neurons`). The host writes only the
    current and set memories, which the pipeline never writes: a neuron's current and set are
    read once, at its fetch, and travel with it.

    Sweeps start on a tick (internal divider of ``clock_hz / update_hz`` cycles, or the ``tick``
    input with ``tick_source="external"``). A tick that arrives while a sweep is still being
    issued is ignored and sets the sticky ``overrun`` flag.

    Ports
    -----
    ``i_wr_en/i_wr_addr/i_wr_data``
        Host write of a neuron's input current (format ``config.I``). It lands in the current RAM
        only, which the pipeline never writes, so it cannot corrupt an update in flight; a write
        in the same cycle as that neuron's fetch is seen from the next sweep on.
    ``sel_wr_en/sel_wr_addr/sel_wr_data``
        Host write of a neuron's parameter-set index (same rules).
    ``spike_valid/spike_ready/spike_index/spike_sweep``
        Spike stream (FIFO of ``spike_fifo_depth``); when full, further spikes are dropped and
        the sticky ``spike_overflow`` flag is set - nothing is lost silently.
    ``upd_valid/upd_index/upd_v/upd_u/upd_current/upd_spike/upd_clamp``
        Every update as it leaves the pipeline (for scoreboards and probes); ``upd_current`` is
        the current as the host wrote it, ``upd_clamp`` the clamps that acted in this update
        (one bit per kind of :data:`CLAMP_KINDS`, bit 0 = ``v_low``).
    ``sweep_done/sweep_count/sweep_number``
        Pulse in the cycle after the last update of a sweep is on ``upd_*``, with the number of
        spikes in that sweep and its number.
    ``sweep_clamps_<kind>``
        With ``sweep_done``: how many updates of that sweep clamped, per kind.
    ``clamp_flags/clamp_clear``
        Sticky clamp flags (bit per kind), set by any clamp since reset; ``clamp_clear`` clears
        them (a clamp in the same cycle keeps its flag set: nothing is lost).

    Attributes
    ----------
    STEPS
        The pipelined steps the core registers at its cuts
        (:data:`~cuneate.hdl.izhikevich.datapath.STEPS`); a subclass may replace one (a fault
        a proof must catch).
    issue, tags, memories, pending_writes, counters
        After elaboration, for a proof harness (:class:`~cuneate.hdl.lib.bookkeeping
        .SweepCore`); also ``state_write_lag`` (1: the state's write lands a cycle after it
        is issued) and ``state_sample_lag`` (1 at depth 9: the memories sample at the end of
        the fetch, not of the cycle before).
    stages
        After elaboration: ``{stage: {name: register}}`` of every datapath register.
    """

    DATA_RESET_LESS = True
    STEPS = datapath.STEPS

    def __init__(self, config: IzhikevichConfig | None = None, **kwargs):
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        sig = core_ports(cfg, CLAMP_KINDS, {"upd_v": Out(cfg.V.shape()),
                                            "upd_u": Out(cfg.U.shape())})
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        N, D = cfg.n_neurons, cfg.pipeline_stages
        m = Module()
        V, U = cfg.V, cfg.U

        def pack(v, u):
            return (v & ((1 << V.width) - 1)) | ((u & ((1 << U.width) - 1)) << V.width)

        init_state = [pack(int(v), int(u)) for v, u in zip(cfg.v_init_raw, cfg.u_init_raw)]

        # --- sweep control and pipeline tags ----------------------------------------------
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        self.issue = issue = sweep_issue(m, self, N, tick, cfg.sweep_number_width)
        # the memories are read one cycle ahead of the fetch into registers beside the block
        # RAMs (hdl/lib/banked.py), a write landing with the read bypassed (n_neurons >= D + 1:
        # a neuron's registered write-back lands at the latest then)
        # (depth 9: read at the fetch from its registered address, the host's writes
        # registered too - the words come a stage later, PIPELINE_READ)
        ahead = cfg.read_stages == 1
        mems = core_memories(
            m, self, cfg, V.width + U.width, init_state, state_attrs={"no_rw_check": 1},
            prefetch=issue.next_addr if ahead else issue.addr, host_write_register=not ahead)
        self.memories, self.pending_writes = mems.banks, mems.pending
        st_rd, cur_rd, sel_rd = mems.state, mems.current, mems.set
        st_wr = self.memory_write(m, "state_mem", mems.state_write)
        self.tags = tags = self.pipeline_tags(m, issue, D)
        tD = tags[D]

        def reg(name, value, stage):
            return self.stage_register(m, name, value, stage)

        # --- stage 2 (3): the banks' registered words (bank multiplexer, host-write bypass) --
        s0 = 2 + cfg.read_stages           # the first datapath stage
        words = {"v": st_rd.data[:V.width].as_signed(), "u": st_rd.data[V.width:].as_signed(),
                 "i": cur_rd.data, "sel": sel_rd.data}
        vals = {k: reg(k, x, s0) for k, x in words.items()}
        self.state_write_lag = 1            # the state's write is registered before its RAM
        # the memories sample at the end of the fetch cycle (depth 9) or of the one before
        self.state_sample_lag = cfg.read_stages - 1
        if len(cfg.params) == 1:
            vals["sel"] = words["sel"] = 0

        steps = self.STEPS

        def live_after(k):
            live = set(datapath.CARRIED)
            for later in steps[k + 1:]:
                live.update(later.reads)
            return live

        # without a cut after the operands (depth < 8) they are formed in stage 2, from the
        # words, and registered with them: every stage-3 multiplier then takes registers
        first = 0
        if 0 not in cfg.cuts:
            step = steps[0]
            ops = step.fn(cfg, {n: words[n] for n in step.reads})
            live = live_after(0)
            vals.update({n: (reg(n, x, s0) if is_hdl(x) else x)
                         for n, x in ops.items() if n in live})
            first = 1
        self.stages = {s0: {n: x for n, x in vals.items() if is_hdl(x)}}
        # --- stages s0 .. D: the datapath steps, registered at the cuts ------------------
        stage = s0
        for k, step in enumerate(steps):
            if k < first:
                continue
            vals.update(step.fn(cfg, {n: vals[n] for n in step.reads}))
            for n in datapath.KEPT:
                if n in vals and is_hdl(vals[n]) and not isinstance(vals[n], Signal):
                    kept = Signal(vals[n].shape(), name=f"{n}_sum", attrs={"keep": 1})
                    m.d.comb += kept.eq(vals[n])
                    vals[n] = kept
            if k in cfg.cuts:
                live = live_after(k)
                stage += 1
                vals = {n: (reg(n, x, stage) if is_hdl(x) else x)
                        for n, x in vals.items() if n in live}
                self.stages[stage] = {n: x for n, x in vals.items() if is_hdl(x)}
        assert stage == D, (stage, D)
        v_out = Signal(V.shape())
        u_out = Signal(U.shape())
        spike = Signal()
        clamp = Signal(len(CLAMP_KINDS))
        flags = {"v_low": vals["v_low"], "u_high": vals["u_high"], "u_low": vals["u_low"],
                 "current": vals["i_flag"], "y": vals["y_flag"]}
        m.d.comb += [v_out.eq(vals["v_next"]), u_out.eq(vals["u_next"]),
                     spike.eq(vals["spike"] & tD[0]),
                     clamp.eq(Mux(tD[0], Cat(*(flags[k] for k in CLAMP_KINDS)), 0))]
        m.d.comb += [st_wr.addr.eq(tD[1]), st_wr.data.eq(Cat(v_out, u_out)),
                     st_wr.en.eq(tD[0])]
        m.d.sync += [self.upd_valid.eq(tD[0]), self.upd_index.eq(tD[1]), self.upd_v.eq(v_out),
                     self.upd_u.eq(u_out), self.upd_current.eq(vals["i"]),
                     self.upd_spike.eq(spike), self.upd_clamp.eq(clamp)]

        # --- bookkeeping from the registered outputs (off the datapath's critical path) -----
        self.counters = sweep_bookkeeping(m, self, N, cfg.sweep_number_width, tD, CLAMP_KINDS,
                                          cfg.spike_fifo_depth)
        return m


def izhikevich_verilog(config: IzhikevichConfig, name: str = "izhikevich_core") -> str:
    """Verilog text of the core (no source locations, so the same config gives the same bytes)."""
    return verilog_text(IzhikevichCore(config), name)


def generate_izhikevich(out: Path, n_neurons: int = 2500, clock_hz: float = 40e6,
                        update_hz: float = 16e3, config: IzhikevichConfig | None = None,
                        name: str = "izhikevich_core") -> list[Path]:
    """Write ``out/<name>.v`` and ``out/<name>.json`` (formats, constants and their errors,
    ports, pipeline depth, proven ranges, clamps); returns the paths."""
    cfg = config or IzhikevichConfig(n_neurons=n_neurons, clock_hz=clock_hz, update_hz=update_hz)
    return write_block(out, IzhikevichCore(cfg), cfg.to_dict(), name)
