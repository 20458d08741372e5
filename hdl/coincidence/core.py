"""The coincidence detector's RTL (cuneate neurons): delayed afferent spikes, bi-exponential
PSPs and Izhikevich targets, and its Verilog.

Per tick ``T`` and target ``t`` (configuration: :class:`~cuneate.hdl.coincidence.config
.CoincidenceConfig`)::

    a_t   = sum_s  J w[t, s] * x_s(T - delay[t, s])          (input spikes, from the history)
    I_t   = x_d - x_r                                        (traces as fetched)
    x'    = y - k y,   y = x + a_t,   k = 1 - exp(-dt/tau)   (decay and rise trace)
    v', u', spike  = the Izhikevich core's update with current I_t

so a spike of source ``s`` stamped with tick ``T`` adds ``J w (exp(-j dt/tau_d) - exp(-j dt/
tau_r))`` to the current of tick ``T + delay + j`` - the golden PSP of
:mod:`cuneate.golden.coincidence` (unnormalized) sampled on the tick grid, 0 at lag 0.

Input spikes arrive as events (``in_valid``, ``in_source``) at any cycle and are collected in a
pending bit vector; the next tick stamps them (an event on the tick cycle itself belongs to the
tick after). Two events of one source before one tick are one spike: the second is counted in
``merged_count`` (afferents spike at most once per tick; nothing is dropped silently). The
history is a ring of ``max_delay_ticks`` words of ``n_sources`` bits in block RAM; delays and
weights are a ROM of ``n_targets x n_sources`` words; each target's state (v, u, x_d, x_r) is one
block-RAM word.

Schedule of a tick (a multi-cycle datapath, one target at a time): on the tick the pending
word is written to history slot ``T mod D``; per target, one (source) input per cycle is read
from the ROM, then from the history (two read latencies), and accumulated; then four update
cycles: (1) ``I``, ``y`` and the Izhikevich operands, (2) the trace products and multipliers 1
and 3, (3) the trace updates and multipliers 2 and 4, (4) threshold, reset and clamps, write
back, ``upd_*`` and the spike event (``spike_valid``, ``spike_target``, ``spike_tick``) on the
next cycle. A tick needs ``n_targets (n_sources + 8) + 2`` cycles; a tick that arrives while
one is processed sets ``tick_overrun`` and is counted, never silently lost.

All arithmetic is written once: :func:`accumulate` and :func:`psp_current`
(:mod:`cuneate.hdl.coincidence.datapath`), the trace stages of :mod:`cuneate.hdl.lib.synapses`
and the Izhikevich stages of :mod:`cuneate.hdl.izhikevich.datapath` - each runs on NumPy ints
(twin) and Amaranth values (RTL).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..flow.synth import synthesize_flows
from ..flow.verilog import verilog_text, write_block
from ..izhikevich import multiply1, multiply2, operands, update_state
from ..lib.datapath import lookup
from ..lib.fsm import wait_states
from ..lib.synapses import trace_products, trace_update
from ..lib.tick import tick_strobe
from .config import CLAMP_KINDS, CoincidenceConfig
from .datapath import accumulate, clamp_bits_hdl, history_slot, psp_current

__all__ = ["synth_resources", "CoincidenceDetector", "coincidence_verilog", "generate_coincidence",
           "COUNTER_BITS"]

COUNTER_BITS = 32


def _pack(fields) -> int:
    """Pack ``(raw, width)`` pairs (first at the LSB) into one unsigned word."""
    word, pos = 0, 0
    for raw, width in fields:
        word |= (int(raw) & ((1 << width) - 1)) << pos
        pos += width
    return word


class CoincidenceDetector(wiring.Component):
    """The coincidence detector as RTL (see the module docstring for the schedule).

    Ports: ``tick`` (external tick), ``in_valid`` / ``in_source`` (input spike events, one per
    cycle), ``spike_valid`` / ``spike_target`` / ``spike_tick`` (one cycle per output spike),
    ``upd_*`` (every target update: ``upd_target``, ``upd_v``, ``upd_u``, ``upd_xd``,
    ``upd_xr``, ``upd_a``, ``upd_i``, ``upd_spike``, ``upd_clamp``, ``upd_tick``), ``busy``,
    ``tick_count``, ``merged_count``, ``overrun_count``, ``tick_overrun`` and ``clamp_flags``
    (sticky, cleared by ``clamp_clear``).

    **Hooks** (a subclass may override them: the faults a proof must catch,
    :mod:`cuneate.hdl.coincidence.formal_core`): :meth:`history_address` (the ring slot of a
    delayed tick), :meth:`memory_write` (the write port the schedule drives) and
    :meth:`update_state` (the Izhikevich update stage). After
    elaboration the detector records, for a proof harness, ``memories`` (``{name: Memory}``:
    ``dw_mem``, ``hist_mem``, ``state_mem``) and ``schedule`` (the registers ``target``,
    ``slot`` and ``pending``: the target processed, the ring slot of the tick, the pending
    input spikes).
    """

    #: the ports' meanings, for the Verilog's header
    PORT_MEANINGS = {
        "spike_valid": "a target spiked (one cycle)", "spike_target": "the target",
        "spike_tick": "its tick", "upd_target": "the updated target",
        "upd_xd": "the PSP's decay trace (raw)", "upd_xr": "the PSP's rise trace (raw)",
        "upd_a": "the input sum of its delayed spikes", "upd_i": "its PSP current (raw)",
        "upd_tick": "the tick of the update", "tick_count": "ticks", "merged_count":
        "input events merged (two of a source in one tick)", "overrun_count": "ticks ignored",
        "tick_overrun": "sticky: a tick came before the last was done"}

    def __init__(self, config: CoincidenceConfig):
        self.cfg = cfg = config
        M, S = cfg.n_targets, cfg.n_sources
        iz = cfg.iz
        sig = {
            "tick": In(1), "in_valid": In(1), "in_source": In(range(max(2, S))),
            "spike_valid": Out(1), "spike_target": Out(range(max(2, M))),
            "spike_tick": Out(COUNTER_BITS),
            "upd_valid": Out(1), "upd_target": Out(range(max(2, M))),
            "upd_v": Out(iz.V.shape()), "upd_u": Out(iz.U.shape()),
            "upd_xd": Out(cfg.traces[0].T.shape()), "upd_xr": Out(cfg.traces[1].T.shape()),
            "upd_a": Out(unsigned(cfg.acc_bits)), "upd_i": Out(iz.I.shape()),
            "upd_spike": Out(1), "upd_clamp": Out(len(CLAMP_KINDS)),
            "upd_tick": Out(COUNTER_BITS),
            "busy": Out(1), "tick_count": Out(COUNTER_BITS), "merged_count": Out(COUNTER_BITS),
            "overrun_count": Out(COUNTER_BITS), "tick_overrun": Out(1),
            "clamp_flags": Out(len(CLAMP_KINDS)), "clamp_clear": In(1),
        }
        super().__init__(sig)

    @staticmethod
    def delay_weight_rom(cfg: CoincidenceConfig) -> list:
        """The delay/weight ROM's words: target ``t``, source ``s`` at ``t S + s``, the delay
        in the low ``history_addr_bits``, the weight above."""
        db, wb = cfg.history_addr_bits, cfg.W.width
        return [_pack([(cfg.delays[t, s], db), (cfg.weights_raw[t, s], wb)])
                for t in range(cfg.n_targets) for s in range(cfg.n_sources)]

    def history_address(self, slot, delay):
        """The history slot of the tick ``delay`` ticks before the one in ``slot``
        (:func:`~cuneate.hdl.coincidence.datapath.history_slot`)."""
        return history_slot(slot, delay, self.cfg.max_delay_ticks)

    def memory_write(self, m: Module, name: str, port):
        """The write port (``addr``, ``data``, ``en``) through which the schedule writes the
        memory ``name``: ``port`` itself."""
        return port

    @staticmethod
    def update_state(cfg, vb_sh, vb_th, vb_lo, u_sh, ud_sh, p, m, sel):
        """The update stage: :func:`~cuneate.hdl.izhikevich.datapath.update_state`."""
        return update_state(cfg, vb_sh, vb_th, vb_lo, u_sh, ud_sh, p, m, sel)

    def elaborate(self, platform):
        cfg, iz = self.cfg, self.cfg.iz
        M, S, D = cfg.n_targets, cfg.n_sources, cfg.max_delay_ticks
        m = Module()
        # ---- memories
        db, wb = cfg.history_addr_bits, cfg.W.width
        m.submodules.dw_mem = dw_mem = Memory(shape=unsigned(db + wb), depth=M * S,
                                              init=self.delay_weight_rom(cfg))
        m.submodules.hist_mem = hist_mem = Memory(shape=unsigned(S), depth=D, init=[])
        TD, TR = cfg.traces[0].T, cfg.traces[1].T
        widths = [iz.V.width, iz.U.width, TD.width, TR.width]
        init = [_pack(zip((iz.v_init_raw[t], iz.u_init_raw[t], 0, 0), widths))
                for t in range(M)]
        m.submodules.state_mem = st_mem = Memory(shape=unsigned(sum(widths)), depth=M,
                                                 init=init)
        self.memories = {"dw_mem": dw_mem, "hist_mem": hist_mem, "state_mem": st_mem}
        dw_rd = dw_mem.read_port()
        hist_rd, hist_wr = hist_mem.read_port(), hist_mem.write_port()
        st_rd, st_wr = st_mem.read_port(), st_mem.write_port()
        hist_wr = self.memory_write(m, "hist_mem", hist_wr)
        st_wr = self.memory_write(m, "state_mem", st_wr)

        # ---- tick source
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))

        # ---- pending input spikes
        pending = Signal(S)
        onehot = Signal(S)
        m.d.comb += onehot.eq(Mux(self.in_valid, Const(1, S) << self.in_source, 0))
        ticks = Signal(COUNTER_BITS)
        slot = Signal(range(D))
        m.d.comb += [self.tick_count.eq(ticks), hist_wr.addr.eq(slot), hist_wr.data.eq(pending)]
        idle = Signal()
        take = Signal()
        m.d.comb += take.eq(tick & idle)
        with m.If(take):
            m.d.sync += pending.eq(onehot)
        with m.Else():
            m.d.sync += pending.eq(pending | onehot)
            with m.If(self.in_valid & (pending.bit_select(self.in_source, 1))):
                m.d.sync += self.merged_count.eq(self.merged_count + 1)
        m.d.comb += hist_wr.en.eq(take)
        with m.If(tick & ~idle):
            m.d.sync += [self.tick_overrun.eq(1), self.overrun_count.eq(self.overrun_count + 1)]

        # ---- input accumulation: A (ROM address) -> B (history address) -> C (accumulate)
        tgt = Signal(range(max(2, M)))
        src = Signal(range(S + 1))
        issuing = Signal()
        vB, sB, lastB = Signal(), Signal(range(max(2, S))), Signal()
        vC, sC, lastC, wC = Signal(), Signal(range(max(2, S))), Signal(), Signal(wb)
        acc = Signal(cfg.acc_bits)
        self.schedule = SimpleNamespace(target=tgt, slot=slot, pending=pending)
        m.d.comb += [dw_rd.addr.eq(tgt * S + src), st_rd.addr.eq(tgt)]
        m.d.sync += [vB.eq(issuing), sB.eq(src), lastB.eq(src == S - 1)]
        d_B = dw_rd.data[:db]
        w_B = dw_rd.data[db:]
        m.d.comb += hist_rd.addr.eq(self.history_address(slot, d_B))
        m.d.sync += [vC.eq(vB), sC.eq(sB), lastC.eq(lastB), wC.eq(w_B)]
        bit_C = hist_rd.data.bit_select(sC, 1)
        with m.If(vC):
            m.d.sync += acc.eq(accumulate(acc, bit_C, wC))

        # ---- target state as fetched
        word = st_rd.data
        pos = np.cumsum([0] + widths)
        v0 = word[pos[0]:pos[1]].as_signed()
        u0 = word[pos[1]:pos[2]].as_signed()
        xd0 = word[pos[2]:pos[3]].as_signed()
        xr0 = word[pos[3]:pos[4]].as_signed()
        sel = lookup(cfg.target_sets_, tgt)

        def reg(name, value):
            s = Signal(value.shape(), name=name)
            m.d.sync += s.eq(value)
            return s

        # the update cycles: every register below loads in the cycle of its stage
        i1, ys = psp_current(cfg, xd0, xr0, acc)
        s2 = operands(iz, v0, u0, i1, sel)
        r_i = reg("r_i", s2["i"])
        r_ys = [reg(f"r_y{k}", y) for k, y in enumerate(ys)]
        r2 = {k: reg(f"r2_{k}", s2[k]) for k in ("wq", "vq", "x", "i_flag")}
        r_v, r_u, r_a = reg("r_v", v0), reg("r_u", u0), reg("r_a", acc)
        ps = trace_products(cfg.tview, r_ys)
        s3 = multiply1(iz, r2["wq"], r2["vq"], r2["x"], r_u, sel)
        r_ps = [reg(f"r_p{k}", p) for k, p in enumerate(ps)]
        r3 = {k: reg(f"r3_{k}", s3[k]) for k in ("q", "bvp", "uy", "x")}
        r_ys3 = [reg(f"r_y3{k}", y) for k, y in enumerate(r_ys)]
        r_wq3 = reg("r_wq3", r2["wq"])
        r_v3, r_u3 = reg("r_v3", r_v), reg("r_u3", r_u)
        r_if3, r_i3, r_a3 = reg("r_if3", r2["i_flag"]), reg("r_i3", r_i), reg("r_a3", r_a)
        xs = trace_update(cfg.tview, r_ys3, r_ps)
        s4 = multiply2(iz, r3["q"], r3["bvp"], r3["uy"], r_wq3, r_v3, r_u3, r3["x"], sel)
        r4 = {k: reg(f"r4_{k}", s4[k]) for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh",
                                                 "p", "m", "y_flag")}
        r_xs = [reg(f"r_x{k}", x) for k, x in enumerate(xs)]
        r_if4, r_i4, r_a4 = reg("r_if4", r_if3), reg("r_i4", r_i3), reg("r_a4", r_a3)
        out = self.update_state(iz, *(r4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh",
                                                 "p", "m")), sel)
        flags = dict(out, current=r_if4, y=r4["y_flag"])
        clamp = clamp_bits_hdl(flags)
        v_new, u_new = Signal(iz.V.shape()), Signal(iz.U.shape())
        m.d.comb += [v_new.eq(out["v"]), u_new.eq(out["u"])]

        # ---- control
        m.d.comb += [idle.eq(0), issuing.eq(0), st_wr.en.eq(0)]
        m.d.sync += [self.upd_valid.eq(0), self.spike_valid.eq(0)]
        with m.If(self.clamp_clear):
            m.d.sync += self.clamp_flags.eq(0)
        with m.FSM():
            with m.State("IDLE"):
                m.d.comb += idle.eq(1)
                with m.If(tick):
                    m.d.sync += [tgt.eq(0), src.eq(0), acc.eq(0)]
                    m.next = "ACC"
            with m.State("ACC"):
                with m.If(src < S):
                    m.d.comb += issuing.eq(1)
                    m.d.sync += src.eq(src + 1)
                with m.If(vC & lastC):
                    m.next = "U1"
            wait_states(m, "U1", "U2", "U3", "U4")
            with m.State("U4"):
                m.d.comb += [st_wr.en.eq(1), st_wr.addr.eq(tgt),
                             st_wr.data.eq(Cat(v_new, u_new, r_xs[0], r_xs[1]))]
                m.d.sync += [
                    self.upd_valid.eq(1), self.upd_target.eq(tgt), self.upd_v.eq(v_new),
                    self.upd_u.eq(u_new), self.upd_xd.eq(r_xs[0]), self.upd_xr.eq(r_xs[1]),
                    self.upd_a.eq(r_a4), self.upd_i.eq(r_i4), self.upd_spike.eq(out["spike"]),
                    self.upd_clamp.eq(clamp), self.upd_tick.eq(ticks),
                    self.spike_valid.eq(out["spike"]), self.spike_target.eq(tgt),
                    self.spike_tick.eq(ticks)]
                with m.If(~self.clamp_clear):
                    m.d.sync += self.clamp_flags.eq(self.clamp_flags | clamp)
                with m.If(tgt == M - 1):
                    m.d.sync += [ticks.eq(ticks + 1), slot.eq(Mux(slot == D - 1, 0, slot + 1))]
                    m.next = "IDLE"
                with m.Else():
                    m.d.sync += [tgt.eq(tgt + 1), src.eq(0), acc.eq(0)]
                    m.next = "ACC"
        m.d.comb += self.busy.eq(~idle)
        return m


def coincidence_verilog(cfg: CoincidenceConfig, name: str = "coincidence_detector",
                        lowered: bool = False, top: CoincidenceDetector | None = None) -> str:
    """Verilog of the detector (deterministic bytes); ``lowered`` gives the yosys-lowered
    netlist that Icarus 11 simulates correctly (see
    :func:`cuneate.hdl.flow.verilog.lowered_verilog`). ``top``: an instance to convert."""
    return verilog_text(top or CoincidenceDetector(cfg), name, lowered)


def generate_coincidence(out, config: CoincidenceConfig,
                         name: str = "coincidence_detector") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json`` (formats, constants and their errors,
    latency, ports, resources hint: multipliers and memories); returns the paths."""
    return write_block(out, CoincidenceDetector(config), config.to_dict(), name)


def synth_resources(cfg, flows=("ecp5", "xc6s"), workdir=None) -> dict:
    """Synthesis figures (cell counts, no fmax) of the block built from ``cfg`` per flow."""
    return synthesize_flows(coincidence_verilog(cfg), "coincidence_detector", flows, workdir)
