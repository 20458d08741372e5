"""The learning cuneate layer's RTL: afferent spikes in, Izhikevich CNs with a lumped
inhibitory interneuron, every synapse learning with AIDP, and its Verilog.

Per tick ``T`` (configuration :class:`~cuneate.hdl.plasticity.config.PlasticityConfig`)::

    s      = the afferent spikes stamped with T,  s_late = those stamped T - latency
    g H    = the interneuron's inhibition (as fetched);   H' = trace(H + popcount(s))
    for each CN j:
        I_j  = round(E_j) - g H,   Z_j = clamp(I_j) - theta           (E_j as fetched)
        for each synapse m (afferent i = src[j, m]):  integrate(s_i, s_late_i, Z_j)
        a_j  = sum_m w_jm s_i,     E_j' = trace(E_j + a_j)
        v', u', spike = the Izhikevich update with current I_j

A window's end (``learn``, with ``learn_apply``): for each CN, the sum of its synapses' drives
(``read`` operations), then a ``learn`` operation on each synapse. The synapse operations are
the learning stage's (:class:`~cuneate.hdl.plasticity.stage.SynapseStage`), the CN update the
Izhikevich core's stage functions, the traces the shared ones (:mod:`cuneate.hdl.lib.synapses`).

Input spikes arrive as events (``in_valid``, ``in_source``) at any cycle and wait in a pending
vector; the next tick stamps them (two events of one source before a tick are one spike,
counted in ``merged_count``). Schedule of a tick (taken while idle; a tick that arrives while
one is processed sets ``tick_overrun`` and is counted): the stamp, two interneuron cycles, then
per CN its state fetch, one synapse per cycle, the last synapse's fetch and four update cycles
(``upd_*``, ``spike_*`` in the cycle after the fourth): ``3 + M (K + 6)`` cycles. A window's end
is requested by a ``learn`` strobe (it waits, pending, for the layer to be idle; a second request
while one is pending or running is counted in ``learn_overrun_count``) and takes ``M (2 K + 1)``
cycles (``M K`` without ``learn_apply``), ``learn_done`` in the cycle after.

Host access, while the layer is idle: ``w_wr_*`` writes a synapse's weight (its calcium and
drive restart from 0), ``w_rd_*`` reads one (``w_rd_resp_*`` two cycles after the request is
taken); each is taken (``*_ready``) when no synapse operation is in flight. Clamps: per kind
(:data:`~cuneate.hdl.plasticity.config.CLAMP_KINDS`) counted in ``clamp_count_<kind>`` and
sticky in ``clamp_flags`` (``clamp_clear``).
"""

from __future__ import annotations

from types import SimpleNamespace

from amaranth import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..flow.synth import synthesize_flows
from ..flow.verilog import verilog_text, write_block
from ..izhikevich import multiply1, multiply2, operands, update_state
from ..lib.datapath import lookup
from ..lib.synapses import trace_products, trace_update
from ..lib.tick import tick_strobe
from . import datapath as dp
from .config import (CLAMP_KINDS, CN_CLAMP_KINDS, OPS, SYNAPSE_CLAMP_KINDS,
                     PlasticityConfig)
from .stage import COUNTER_BITS, SynapseStage, pack, unpack

__all__ = ["LearningLayer", "learning_verilog", "generate_learning", "synth_resources",
           "COUNTER_BITS"]


class LearningLayer(wiring.Component):
    """The learning layer as RTL (see the module docstring)."""

    #: the layer's own ports, for the Verilog header
    PORT_MEANINGS = {
        "tick": "start a tick (external tick)",
        "in_source": "its afferent (stamped by the next tick)",
        "learn": "request a window's end", "learn_apply": "with learn: apply the steps",
        "learn_done": "pulse: the window's end finished",
        "w_wr_valid": "host weight write strobe", "w_wr_addr": "synapse written (CN * K + m)",
        "w_wr_data": "its weight, raw (calcium and drive restart)",
        "w_wr_ready": "the write is taken (layer idle)",
        "w_rd_valid": "host weight read strobe", "w_rd_addr": "synapse read (CN * K + m)",
        "w_rd_ready": "the read is taken (layer idle)",
        "w_rd_resp_valid": "the read's answer", "w_rd_resp_data": "the weight, raw",
        "spike_valid": "a CN spiked", "spike_target": "the CN", "spike_tick": "its tick",
        "upd_target": "its CN",
        "syn_upd_valid": "a synapse operation leaves the stage",
        "syn_upd_op": "its operation (integrate, read, learn, write)",
        "syn_upd_addr": "its synapse (CN * K + m)",
        "syn_upd_w": "its weight after it (raw)", "syn_upd_cd": "its decay calcium (raw)",
        "syn_upd_cr": "its rise calcium (raw)", "syn_upd_l": "its learning drive (raw)",
        "syn_upd_clamp": "the synapse clamps that acted in it (one bit per kind)",
        "tick_count": "ticks taken", "learn_count": "window ends taken",
        "merged_count": "input spikes merged (two of a source in one tick)",
        "overrun_count": "ticks that came while one was processed",
        "tick_overrun": "sticky: a tick came while one was processed",
        "learn_overrun_count": "window ends requested while one was pending or running",
        "hazard_count": "synapse operations issued within the stage's write-back latency",
    } | {f"clamp_count_{k}": f"{k} clamps counted" for k in CLAMP_KINDS}

    def __init__(self, config: PlasticityConfig):
        self.cfg = cfg = config
        M, K, S = cfg.n_targets, cfg.n_synapses, cfg.n_sources
        iz = cfg.iz
        n = M * K
        sig = {
            "tick": In(1), "in_valid": In(1), "in_source": In(range(max(2, S))),
            "learn": In(1), "learn_apply": In(1), "learn_done": Out(1),
            "w_wr_valid": In(1), "w_wr_addr": In(range(max(2, n))),
            "w_wr_data": In(cfg.W.shape()), "w_wr_ready": Out(1),
            "w_rd_valid": In(1), "w_rd_addr": In(range(max(2, n))), "w_rd_ready": Out(1),
            "w_rd_resp_valid": Out(1), "w_rd_resp_data": Out(cfg.W.shape()),
            "spike_valid": Out(1), "spike_target": Out(range(max(2, M))),
            "spike_tick": Out(COUNTER_BITS),
            "upd_valid": Out(1), "upd_target": Out(range(max(2, M))),
            "upd_v": Out(iz.V.shape()), "upd_u": Out(iz.U.shape()),
            "upd_e": Out(cfg.exc.T.shape()), "upd_i": Out(cfg.I_full.shape()),
            "upd_inh": Out(cfg.I_full.shape()), "upd_a": Out(unsigned(self._acc_bits())),
            "upd_spike": Out(1), "upd_clamp": Out(len(CN_CLAMP_KINDS)),
            "upd_tick": Out(COUNTER_BITS),
            "syn_upd_valid": Out(1), "syn_upd_op": Out(2), "syn_upd_addr": Out(range(max(2, n))),
            "syn_upd_w": Out(cfg.W.shape()), "syn_upd_cd": Out(cfg.calcium[0].T.shape()),
            "syn_upd_cr": Out(cfg.calcium[1].T.shape()), "syn_upd_l": Out(cfg.L.shape()),
            "syn_upd_clamp": Out(len(SYNAPSE_CLAMP_KINDS)),
            "busy": Out(1), "tick_count": Out(COUNTER_BITS), "learn_count": Out(COUNTER_BITS),
            "merged_count": Out(COUNTER_BITS), "overrun_count": Out(COUNTER_BITS),
            "tick_overrun": Out(1), "learn_overrun_count": Out(COUNTER_BITS),
            "hazard_count": Out(COUNTER_BITS),
            "clamp_flags": Out(len(CLAMP_KINDS)), "clamp_clear": In(1),
        }
        sig |= {f"clamp_count_{k}": Out(COUNTER_BITS) for k in CLAMP_KINDS}
        super().__init__(sig)

    def _acc_bits(self) -> int:
        cfg = self.cfg
        return max(1, int(cfg.weights_raw.shape[1] * cfg.w_max_raw).bit_length())

    def elaborate(self, platform):
        """The stages in order: memories, input spikes, interneuron, the CN being processed,
        the synapse stage's operations, the CN update, the control FSM, clamps."""
        cfg = self.cfg
        m = Module()
        m.submodules.stage = stage = SynapseStage(cfg)
        n = SimpleNamespace(stage=stage)
        self._memories(m, n)
        n.tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        self._input_spikes(m, n)
        self._interneuron(m, n)
        self._cn_fetch(m, n)
        learn_pending, learn_apply = Signal(), Signal()
        total = Signal(cfg.total_bits, name="total")
        host_rd = Signal(name="host_rd_inflight")
        n.learn_pending, n.learn_apply, n.total, n.host_rd = (learn_pending, learn_apply, total,
                                                              host_rd)
        self._stage_operations(m, n)
        self._cn_update(m, n)
        self._control(m, n)
        self._synapse_updates_and_clamps(m, n)
        return m

    def _memories(self, m, n):
        """The source table (``M K`` entries) and the CNs' state words (``v, u, E``)."""
        cfg, iz = self.cfg, self.cfg.iz
        M, K, S = cfg.n_targets, cfg.n_synapses, cfg.n_sources
        src_bits = max(1, (S - 1).bit_length())
        m.submodules.src_mem = src_mem = Memory(shape=unsigned(src_bits), depth=M * K,
                                                init=[int(x) for x in cfg.src.reshape(-1)])
        n.tf = tf = [f for _, f in cfg.target_fields]
        init = [pack((iz.v_init_raw[j], iz.u_init_raw[j], 0), tf) for j in range(M)]
        m.submodules.cn_mem = cn_mem = Memory(shape=unsigned(sum(f.width for f in tf)), depth=M,
                                              init=init)
        src_rd = src_mem.read_port()
        cn_rd, cn_wr = cn_mem.read_port(), cn_mem.write_port()
        n.src_rd, n.cn_rd, n.cn_wr = src_rd, cn_rd, cn_wr

    def _input_spikes(self, m, n):
        """Pending input spikes (merges counted), the stamp of a tick taken while idle (a tick
        while busy is an overrun), the delayed spike words."""
        S, lat = self.cfg.n_sources, self.cfg.latency_ticks
        pending, onehot = Signal(S), Signal(S)
        m.d.comb += onehot.eq(Mux(self.in_valid, Const(1, S) << self.in_source, 0))
        ticks = Signal(COUNTER_BITS)
        m.d.comb += self.tick_count.eq(ticks)
        cur, late = Signal(S, name="cur"), Signal(S, name="late")
        shift = [Signal(S, name=f"delayed{k}") for k in range(lat)]
        n_spk = Signal(range(S + 1), name="n_spk")
        idle, take = Signal(), Signal()
        n.ticks, n.cur, n.late, n.n_spk, n.idle = ticks, cur, late, n_spk, idle
        m.d.comb += take.eq(n.tick & idle)
        with m.If(take):
            m.d.sync += [pending.eq(onehot), cur.eq(pending),
                         late.eq(shift[lat - 1] if lat else pending),
                         n_spk.eq(sum(pending[i] for i in range(S)))]
            if lat:
                m.d.sync += [shift[0].eq(pending)] + [shift[k].eq(shift[k - 1])
                                                      for k in range(1, lat)]
        with m.Else():
            m.d.sync += pending.eq(pending | onehot)
            with m.If(self.in_valid & pending.bit_select(self.in_source, 1)):
                m.d.sync += self.merged_count.eq(self.merged_count + 1)
        with m.If(n.tick & ~idle):
            m.d.sync += [self.tick_overrun.eq(1), self.overrun_count.eq(self.overrun_count + 1)]

    def _interneuron(self, m, n):
        """The interneuron's inhibition and trace (its two prologue cycles' operands)."""
        cfg = self.cfg
        n.H = Signal(cfg.inh.T.shape(), name="H")
        n.inh = Signal(cfg.I_full.shape(), name="inh")
        n.inh_now, n.y_h = dp.interneuron(cfg, n.H, n.n_spk)
        (n.ph,) = trace_products(cfg.hview, [n.y_h])
        n.r_yh = Signal(n.y_h.shape(), name="r_yh")
        n.r_ph = Signal(n.ph.shape(), name="r_ph")

    def _cn_fetch(self, m, n):
        """The CN being processed: its index, synapse counter, fetched state and input sum."""
        cfg = self.cfg
        M, K = cfg.n_targets, cfg.n_synapses
        n.tgt = Signal(range(max(2, M)), name="tgt")
        n.base = Signal(range(max(2, M * K)), name="base")       # tgt * K
        n.syn_m = Signal(range(K + 1), name="syn_m")
        n.v0, n.u0, n.e0 = unpack(n.cn_rd.data, n.tf)
        m.d.comb += n.cn_rd.addr.eq(n.tgt)
        i_now, _ = dp.net_drive(cfg, n.e0, n.inh, 0)
        n.z_now = dp.main_calcium(cfg, i_now)
        n.acc = Signal(self._acc_bits(), name="acc")
        n.src_now = n.src_rd.data

    def _stage_operations(self, m, n):
        """The synapse stage's operation defaults (an integrate on the current synapse), what
        its fetches add to the CN's sum and the window's total, the host read's answer."""
        stage = n.stage
        m.d.comb += [stage.op_valid.eq(0), stage.op.eq(OPS["integrate"]),
                     stage.op_addr.eq(n.base + n.syn_m), stage.op_spike.eq(0),
                     stage.op_late.eq(0), stage.op_z.eq(n.z_now), stage.op_total.eq(n.total),
                     stage.op_apply.eq(n.learn_apply), stage.op_weight.eq(self.w_wr_data),
                     n.src_rd.addr.eq(n.base + n.syn_m + 1)]
        with m.If(stage.fetch_valid & (stage.fetch_op == OPS["integrate"])):
            m.d.sync += n.acc.eq(dp.contribution(n.acc, 1, stage.contrib))
        with m.If(stage.fetch_valid & (stage.fetch_op == OPS["read"]) & ~n.host_rd):
            m.d.sync += n.total.eq(n.total + stage.fetch_l)
        m.d.sync += [n.host_rd.eq(0), self.w_rd_resp_valid.eq(n.host_rd & stage.fetch_valid),
                     self.w_rd_resp_data.eq(stage.fetch_w)]

    def _cn_update(self, m, n):
        """The CN update's four register stages (the Izhikevich core's stage functions and the
        excitatory trace); sets ``n.v_new``, ``n.u_new``, ``n.out``, ``n.cn_clamp`` and the
        fourth stage's registers."""
        cfg, iz = self.cfg, self.cfg.iz
        sel = lookup(cfg.target_sets_, n.tgt)

        def reg(name, value):
            s = Signal(value.shape(), name=name)
            m.d.sync += s.eq(value)
            return s
        i_c, y_ec = dp.net_drive(cfg, n.e0, n.inh, n.acc)
        s2 = operands(iz, n.v0, n.u0, i_c, sel)
        r_i, r_ye = reg("r_i", s2["i"]), reg("r_ye", y_ec)
        r_ifull, r_inh = reg("r_ifull", i_c), reg("r_inh", n.inh)
        r2 = {k: reg(f"r2_{k}", s2[k]) for k in ("wq", "vq", "x", "i_flag")}
        r_v, r_u, r_a = reg("r_v", n.v0), reg("r_u", n.u0), reg("r_a", n.acc)
        (pe,) = trace_products(cfg.eview, [r_ye])
        s3 = multiply1(iz, r2["wq"], r2["vq"], r2["x"], r_u, sel)
        r_pe, r_ye3 = reg("r_pe", pe), reg("r_ye3", r_ye)
        r3 = {k: reg(f"r3_{k}", s3[k]) for k in ("q", "bvp", "uy", "x")}
        r_wq3, r_v3, r_u3 = reg("r_wq3", r2["wq"]), reg("r_v3", r_v), reg("r_u3", r_u)
        r_if3, r_a3 = reg("r_if3", r2["i_flag"]), reg("r_a3", r_a)
        r_if3b, r_inh3 = reg("r_ifull3", r_ifull), reg("r_inh3", r_inh)
        (e_new,) = trace_update(cfg.eview, [r_ye3], [r_pe])
        s4 = multiply2(iz, r3["q"], r3["bvp"], r3["uy"], r_wq3, r_v3, r_u3, r3["x"], sel)
        r4 = {k: reg(f"r4_{k}", s4[k]) for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh",
                                                 "p", "m", "y_flag")}
        n.r_e4, r_if4, n.r_a4 = reg("r_e4", e_new), reg("r_if4", r_if3), reg("r_a4", r_a3)
        n.r_i4, n.r_inh4 = reg("r_ifull4", r_if3b), reg("r_inh4", r_inh3)
        n.out = out = update_state(iz, *(r4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh",
                                                         "ud_sh", "p", "m")), sel)
        cn_flags = dict(out, current=r_if4, y=r4["y_flag"])
        n.cn_clamp = Cat(*[cn_flags[k] for k in CN_CLAMP_KINDS])
        v_new, u_new = Signal(iz.V.shape()), Signal(iz.U.shape())
        m.d.comb += [v_new.eq(out["v"]), u_new.eq(out["u"])]
        n.v_new, n.u_new = v_new, u_new

    def _control(self, m, n):
        """The learn request (overruns counted) and the FSM: idle (host port), a tick's
        states, a window end's states."""
        m.d.comb += [n.idle.eq(0), n.cn_wr.en.eq(0), self.w_wr_ready.eq(0),
                     self.w_rd_ready.eq(0)]
        m.d.sync += [self.upd_valid.eq(0), self.spike_valid.eq(0), self.learn_done.eq(0)]
        with m.If(self.learn):
            with m.If(n.learn_pending | ~n.idle):
                m.d.sync += self.learn_overrun_count.eq(self.learn_overrun_count + 1)
            with m.Else():
                m.d.sync += [n.learn_pending.eq(1), n.learn_apply.eq(self.learn_apply)]
        with m.FSM():
            self._idle_state(m, n)
            self._tick_states(m, n)
            self._learn_states(m, n)
        m.d.comb += self.busy.eq(~n.idle | n.learn_pending)

    def _idle_state(self, m, n):
        """IDLE: a tick starts, else a pending window end, else the host's write or read."""
        stage = n.stage
        with m.State("IDLE"):
            m.d.comb += n.idle.eq(1)
            with m.If(n.tick):
                m.next = "PRO1"
            with m.Elif(n.learn_pending & ~stage.busy & ~self.learn):
                m.d.sync += [n.learn_pending.eq(0), n.tgt.eq(0), n.base.eq(0), n.syn_m.eq(0),
                             n.total.eq(0)]
                m.next = "LSUM"
                with m.If(~n.learn_apply):
                    m.next = "LSTEP"
            with m.Elif(~stage.busy & ~self.learn):
                m.d.comb += [self.w_wr_ready.eq(1),
                             self.w_rd_ready.eq(~self.w_wr_valid),
                             stage.op_addr.eq(Mux(self.w_wr_valid, self.w_wr_addr,
                                                  self.w_rd_addr))]
                with m.If(self.w_wr_valid):
                    m.d.comb += [stage.op_valid.eq(1), stage.op.eq(OPS["write"])]
                with m.Elif(self.w_rd_valid):
                    m.d.comb += [stage.op_valid.eq(1), stage.op.eq(OPS["read"])]
                    m.d.sync += n.host_rd.eq(1)

    def _tick_states(self, m, n):
        """A tick: two interneuron cycles, then per CN its fetch, one synapse per cycle, the
        last synapse and the four update cycles (U4 writes the state back and reports)."""
        cfg, stage = self.cfg, n.stage
        M, K = cfg.n_targets, cfg.n_synapses
        tgt, base, syn_m = n.tgt, n.base, n.syn_m
        with m.State("PRO1"):
            m.d.sync += [n.inh.eq(n.inh_now), n.r_yh.eq(n.y_h), n.r_ph.eq(n.ph)]
            m.next = "PRO2"
        with m.State("PRO2"):
            (h_new,) = trace_update(cfg.hview, [n.r_yh], [n.r_ph])
            m.d.sync += [n.H.eq(h_new), tgt.eq(0), base.eq(0), syn_m.eq(0)]
            m.next = "FETCH"
        with m.State("FETCH"):
            m.d.comb += n.src_rd.addr.eq(base)
            m.d.sync += [syn_m.eq(0), n.acc.eq(0)]
            m.next = "ACC"
        with m.State("ACC"):
            m.d.comb += [stage.op_valid.eq(1), stage.op.eq(OPS["integrate"]),
                         stage.op_spike.eq(n.cur.bit_select(n.src_now, 1)),
                         stage.op_late.eq(n.late.bit_select(n.src_now, 1))]
            m.d.sync += syn_m.eq(syn_m + 1)
            with m.If(syn_m == K - 1):
                m.next = "LAST"
        for state, nxt in (("LAST", "U1"), ("U1", "U2"), ("U2", "U3"), ("U3", "U4")):
            with m.State(state):
                m.next = nxt
        with m.State("U4"):
            m.d.comb += [n.cn_wr.en.eq(1), n.cn_wr.addr.eq(tgt),
                         n.cn_wr.data.eq(Cat(n.v_new, n.u_new, n.r_e4))]
            m.d.sync += [
                self.upd_valid.eq(1), self.upd_target.eq(tgt), self.upd_v.eq(n.v_new),
                self.upd_u.eq(n.u_new), self.upd_e.eq(n.r_e4), self.upd_i.eq(n.r_i4),
                self.upd_inh.eq(n.r_inh4), self.upd_a.eq(n.r_a4),
                self.upd_spike.eq(n.out["spike"]), self.upd_clamp.eq(n.cn_clamp),
                self.upd_tick.eq(n.ticks), self.spike_valid.eq(n.out["spike"]),
                self.spike_target.eq(tgt), self.spike_tick.eq(n.ticks)]
            with m.If(tgt == M - 1):
                m.d.sync += n.ticks.eq(n.ticks + 1)
                m.next = "IDLE"
            with m.Else():
                m.d.sync += [tgt.eq(tgt + 1), base.eq(base + K), syn_m.eq(0)]
                m.next = "FETCH"

    def _learn_states(self, m, n):
        """A window's end, per CN: its drives read into the total (with ``learn_apply``), then
        a learn operation on each synapse."""
        cfg, stage = self.cfg, n.stage
        M, K = cfg.n_targets, cfg.n_synapses
        tgt, base, syn_m = n.tgt, n.base, n.syn_m
        with m.State("LSUM"):                   # read the CN's drives into the total
            m.d.comb += [stage.op_valid.eq(1), stage.op.eq(OPS["read"])]
            m.d.sync += syn_m.eq(syn_m + 1)
            with m.If(syn_m == K - 1):
                m.next = "LWAIT"
        with m.State("LWAIT"):                  # the last drive enters the total
            m.d.sync += syn_m.eq(0)
            m.next = "LSTEP"
        with m.State("LSTEP"):                  # the steps
            m.d.comb += [stage.op_valid.eq(1), stage.op.eq(OPS["learn"])]
            m.d.sync += syn_m.eq(syn_m + 1)
            with m.If(syn_m == K - 1):
                m.d.sync += [syn_m.eq(0), n.total.eq(0)]
                with m.If(tgt == M - 1):
                    m.d.sync += [self.learn_done.eq(1),
                                 self.learn_count.eq(self.learn_count + 1)]
                    m.next = "IDLE"
                with m.Else():
                    m.d.sync += [tgt.eq(tgt + 1), base.eq(base + K)]
                    m.next = "LSUM"
                    with m.If(~n.learn_apply):
                        m.next = "LSTEP"

    def _synapse_updates_and_clamps(self, m, n):
        """The synapse stage's updates out; every clamp (CN and synapse) sticky and counted."""
        stage = n.stage
        m.d.comb += [self.syn_upd_valid.eq(stage.upd_valid), self.syn_upd_op.eq(stage.upd_op),
                     self.syn_upd_addr.eq(stage.upd_addr), self.syn_upd_w.eq(stage.upd_w),
                     self.syn_upd_cd.eq(stage.upd_cd), self.syn_upd_cr.eq(stage.upd_cr),
                     self.syn_upd_l.eq(stage.upd_l), self.syn_upd_clamp.eq(stage.upd_clamp),
                     self.hazard_count.eq(stage.hazard_count)]
        flags = Cat(Mux(self.upd_valid, self.upd_clamp, 0), stage.upd_clamp)
        with m.If(self.clamp_clear):
            m.d.sync += self.clamp_flags.eq(0)
        with m.Else():
            m.d.sync += self.clamp_flags.eq(self.clamp_flags | flags)
        for b, k in enumerate(CLAMP_KINDS):
            cnt = getattr(self, f"clamp_count_{k}")
            with m.If(flags[b]):
                m.d.sync += cnt.eq(cnt + 1)


def learning_verilog(cfg: PlasticityConfig, name: str = "learning_layer",
                     lowered: bool = False, top: LearningLayer | None = None) -> str:
    """Verilog of the layer (deterministic bytes); ``lowered`` gives the yosys-lowered netlist
    that Icarus 11 simulates correctly."""
    return verilog_text(top or LearningLayer(cfg), name, lowered)


def generate_learning(out, config: PlasticityConfig, name: str = "learning_layer") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json``; returns the paths."""
    return write_block(out, LearningLayer(config), config.to_dict(), name)


def synth_resources(cfg, flows=("ecp5",), workdir=None) -> dict:
    """Synthesis figures (cell counts, no fmax) of the layer built from ``cfg`` per flow."""
    return synthesize_flows(learning_verilog(cfg), "learning_layer", flows, workdir)

