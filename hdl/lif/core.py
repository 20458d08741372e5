"""The LIF core's RTL: a time-multiplexed, pipelined Amaranth component built from the datapath's
stage functions (:mod:`cuneate.hdl.lif.datapath`) and the synaptic traces
(:mod:`cuneate.hdl.lib.synapses`), and its Verilog.

Latency 5 cycles, then one neuron update per clock; formats from
:class:`~cuneate.hdl.lif.config.LifConfig`.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal, signed
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..flow.verilog import verilog_text, write_block
from ..lib.bookkeeping import (SweepCore, core_memories, core_ports, sweep_bookkeeping,
                               sweep_issue)
from ..lib.synapses import trace_products, trace_update
from ..lib.tick import tick_strobe
from .config import CLAMP_KINDS, LifConfig
from .datapath import gather_input, leak_operand, leak_product, update_state
from .twin import LifTwin

__all__ = ["LifCore", "lif_verilog", "generate_lif"]


class LifCore(SweepCore):
    """Time-multiplexed LIF core: one neuron update per clock, 5-stage pipeline.

    Latency: a neuron's index is issued at cycle t; its update is on ``upd_*`` at t + 5.

    1. **Fetch** - the sweep counter addresses the state (``v``, refractory counter), current,
       set-select and weight RAMs (synchronous read); the tick's input spike vector is tagged
       onto the neuron.
    2. **Read** - the RAM outputs are registered.
    3. **Input, operand** - ``D = clamp(I) + sum w x`` (adder tree over the fan-in, width from
       the fan-in) and the leak operand ``v - v_rest - D`` (or ``v``), rounded to ``X``.
    4. **Leak** - ``k x`` (one multiplier) or ``x >> s`` (no multiplier).
    5. **Update** - subtract, refractory hold, threshold, reset, flagged floor clamp; write
       back; outputs registered.

    Input spikes: ``in_valid``/``in_source`` set a source's bit in the pending vector; each
    tick moves the pending vector into the active one (used by every neuron of that sweep;
    with ``input_delays`` source ``i`` comes from the pending vector of ``d_i`` ticks before,
    through a shift register of pending vectors) and clears it, so a spike arriving during
    tick t acts on the sweep of tick t + 1. Several
    spikes of one source in one tick count once and set the sticky ``in_merged`` flag. Other
    ports are those of
    :class:`cuneate.hdl.izhikevich.IzhikevichCore` (``i_wr_*``, ``sel_wr_*``, spike stream,
    ``upd_*`` probe with ``upd_ref``, ``upd_acc``, sweep counters, sticky clamp flags). With
    ``weights_writable``, ``w_wr_en/w_wr_addr/w_wr_data`` write a neuron's whole weight row
    (same rules as the current writes; the accepted input range is then proven for any weights
    of the format).

    After elaboration the core records what a proof harness reads (:class:`~cuneate.hdl.lib
    .bookkeeping.SweepCore`: ``issue``, ``tags``, ``memories``, ``pending_writes``,
    ``counters``) and, with input sources, ``input_spikes`` (``pending``, ``active``: the
    tick's pending and active spike vectors).

    **Hooks** besides :class:`~cuneate.hdl.lib.bookkeeping.SweepCore`'s: the datapath stages
    :meth:`gather_input`, :meth:`update_state` and :meth:`trace_update` (the datapath's
    functions); a subclass replaces one - a fault the proof must catch
    (:mod:`cuneate.hdl.lif.formal_core`).
    """

    #: the ports' meanings the blocks' shared ones lack, for the Verilog's header
    PORT_MEANINGS = {"upd_ref": "the update's refractory count",
                     "upd_acc": "the update's weighted input sum (weight LSBs)"}

    def __init__(self, config: LifConfig | None = None, **kwargs):
        self.cfg = cfg = config or LifConfig(**kwargs)
        N, F = cfg.n_neurons, cfg.n_inputs
        extra = {"upd_acc": Out(signed(cfg.acc_bits))}
        for t in cfg.traces:
            extra[f"upd_{t.name}"] = Out(t.T.shape())
        if F:
            extra.update(in_valid=In(1), in_source=In(range(F)), in_merged=Out(1))
            if cfg.weights_writable:
                extra.update(w_wr_en=In(1), w_wr_addr=In(range(N)),
                             w_wr_data=In(F * cfg.W.width))
        sig = core_ports(cfg, CLAMP_KINDS, {"upd_v": Out(cfg.V.shape()),
                                            "upd_ref": Out(max(1, cfg.ref_bits))}, extra)
        super().__init__(sig)

    @staticmethod
    def gather_input(cfg: LifConfig, I, x, w, traces=None):
        """Stage 3: :func:`~cuneate.hdl.lif.datapath.gather_input`."""
        return gather_input(cfg, I, x, w, traces)

    @staticmethod
    def update_state(cfg: LifConfig, v, d, D, ref, sel):
        """Stage 5: :func:`~cuneate.hdl.lif.datapath.update_state`."""
        return update_state(cfg, v, d, D, ref, sel)

    @staticmethod
    def trace_update(cfg: LifConfig, ys, ps):
        """Stage 5's traces: :func:`~cuneate.hdl.lib.synapses.trace_update`."""
        return trace_update(cfg, ys, ps)

    def elaborate(self, platform):
        cfg = self.cfg
        N, F, V, R = cfg.n_neurons, cfg.n_inputs, cfg.V, cfg.ref_bits
        m = Module()
        init_state = [int(v) & ((1 << V.width) - 1) for v in cfg.v_init_raw]
        mems = core_memories(m, self, cfg, V.width + R, init_state)
        self.memories, self.pending_writes = dict(mems.banks), mems.pending
        st_rd, cur_rd, sel_rd = mems.state, mems.current, mems.set
        st_wr = self.memory_write(m, "state_mem", mems.state_write)
        rd_ports = [st_rd, cur_rd, sel_rd]
        wb = cfg.W.width
        if F:
            rows = [LifTwin.pack_weights(cfg, row) for row in cfg.weights_raw]
            m.submodules.weight_mem = w_mem = Memory(shape=wb * F, depth=N, init=rows)
            self.memories["weight_mem"] = [w_mem]
            w_rd = w_mem.read_port()
            rd_ports.append(w_rd)
            if cfg.weights_writable:
                w_wr = w_mem.write_port()
                m.d.comb += [w_wr.addr.eq(self.w_wr_addr), w_wr.data.eq(self.w_wr_data),
                             w_wr.en.eq(self.w_wr_en)]
        TW = [t.T.width for t in cfg.traces]
        if cfg.traces:
            m.submodules.trace_mem = tr_mem = Memory(shape=sum(TW), depth=N, init=[])
            self.memories["trace_mem"] = [tr_mem]
            tr_rd, tr_wr = tr_mem.read_port(), tr_mem.write_port()
            tr_wr = self.memory_write(m, "trace_mem", tr_wr)
            rd_ports.append(tr_rd)

        # --- sweep control -----------------------------------------------------------------
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        self.issue = issue = sweep_issue(m, self, N, tick, cfg.sweep_number_width)
        start = issue.start
        for port in rd_ports:
            m.d.comb += [port.addr.eq(issue.addr), port.en.eq(1)]

        # --- input spikes: pending -> active on each sweep start ------------------------------
        active = Signal(max(1, F))
        if F:
            pending = Signal(F)
            event = Mux(self.in_valid, Const(1, F) << self.in_source, 0)
            with m.If(start):
                m.d.sync += [active.eq(self._delayed(m, pending, start)), pending.eq(event)]
            with m.Else():
                m.d.sync += pending.eq(pending | event)
                # a second spike of a source within one tick merges with the first: flagged
                with m.If(self.in_valid & pending.bit_select(self.in_source, 1)):
                    m.d.sync += self.in_merged.eq(1)
            self.input_spikes = SimpleNamespace(pending=pending, active=active)

        # --- pipeline tags --------------------------------------------------------------------
        self.tags = tags = self.pipeline_tags(m, issue, 5)
        t5 = tags[5]

        def reg(name, value, stage):
            return self.stage_register(m, name, value, stage)

        x2 = reg("x", active, 2)
        # --- stage 2: RAM outputs registered -------------------------------------------------
        v3 = reg("v", st_rd.data[:V.width].as_signed(), 3)
        ref3 = reg("ref", st_rd.data[V.width:] if R else Const(0, 1), 3)
        i3, sel3, x3 = reg("i", cur_rd.data, 3), reg("sel", sel_rd.data, 3), reg("x", x2, 3)
        w3 = reg("w", w_rd.data, 3) if F else None
        # --- stage 3: total input and leak operand -------------------------------------------
        ws = [w3[wb * i: wb * (i + 1)].as_signed() for i in range(F)]
        tr3 = None
        if cfg.traces:
            offs = np.cumsum([0] + TW)
            tr3 = [reg(f"tr_{t.name}", tr_rd.data[offs[j]:offs[j + 1]].as_signed(), 3)
                   for j, t in enumerate(cfg.traces)]
        g = self.gather_input(cfg, i3, [x3[i] for i in range(F)], ws, tr3)
        xop = leak_operand(cfg, v3, g["d"], sel3)
        v4, ref4, sel4, i4 = (reg(n, s, 4) for n, s in
                              (("v", v3), ("ref", ref3), ("sel", sel3), ("i", i3)))
        d4, acc4, x4 = reg("d", g["d"], 4), reg("acc", g["acc"], 4), reg("xop", xop, 4)
        fcur4, fin4 = reg("flag_current", g["current"], 4), reg("flag_input", g["input"], 4)
        # --- stage 4: the leak product --------------------------------------------------------
        p = leak_product(cfg, x4, sel4)
        v5, ref5, sel5, i5, d5, acc5 = (reg(n, s, 5) for n, s in
                                        (("v", v4), ("ref", ref4), ("sel", sel4), ("i", i4),
                                         ("d", d4), ("acc", acc4)))
        p5 = reg("p", p, 5)
        ys4 = [reg(f"y_{t.name}", y, 4) for t, y in zip(cfg.traces, g["ys"])]
        # the trace products are formed in stage 4 from the registered ys
        if cfg.traces:
            tp5 = [reg(f"tp_{t.name}", q, 5) for t, q in zip(cfg.traces,
                                                             trace_products(cfg, ys4))]
            ys5 = [reg(f"y_{t.name}", y, 5) for t, y in zip(cfg.traces, ys4)]
            tr_new = self.trace_update(cfg, ys5, tp5)
            tr_out = [Signal(t.T.shape(), name=f"{t.name}_out") for t in cfg.traces]
            m.d.comb += [o.eq(v) for o, v in zip(tr_out, tr_new)]
            m.d.comb += [tr_wr.addr.eq(t5[1]), tr_wr.data.eq(Cat(*tr_out)),
                         tr_wr.en.eq(t5[0])]
            m.d.sync += [getattr(self, f"upd_{t.name}").eq(o)
                         for t, o in zip(cfg.traces, tr_out)]
        fcur5, fin5 = reg("flag_current", fcur4, 5), reg("flag_input", fin4, 5)
        # --- stage 5: update, write back ------------------------------------------------------
        s5 = self.update_state(cfg, v5, p5, d5, ref5, sel5)
        v_out = Signal(V.shape())
        ref_out = Signal(max(1, R))
        spike = Signal()
        clamp = Signal(len(CLAMP_KINDS))
        flags = {"current": fcur5, "input": fin5, "v_low": s5["v_low"]}
        m.d.comb += [v_out.eq(s5["v"]), ref_out.eq(s5["ref"]), spike.eq(s5["spike"] & t5[0]),
                     clamp.eq(Mux(t5[0], Cat(*(flags[k] for k in CLAMP_KINDS)), 0))]
        m.d.comb += [st_wr.addr.eq(t5[1]),
                     st_wr.data.eq(Cat(v_out, ref_out[:R]) if R else v_out),
                     st_wr.en.eq(t5[0])]
        m.d.sync += [self.upd_valid.eq(t5[0]), self.upd_index.eq(t5[1]), self.upd_v.eq(v_out),
                     self.upd_ref.eq(ref_out), self.upd_current.eq(i5),
                     self.upd_acc.eq(acc5), self.upd_spike.eq(spike), self.upd_clamp.eq(clamp)]

        # --- bookkeeping ------------------------------------------------------------------------
        self.counters = sweep_bookkeeping(m, self, N, cfg.sweep_number_width, t5, CLAMP_KINDS,
                                          cfg.spike_fifo_depth)
        return m


    def _delayed(self, m: Module, pending, start):
        """The active vector of a starting sweep: source ``i`` from ``input_delays[i]`` ticks
        ago (a shift register of ``max_input_delay`` pending vectors, advanced on each sweep
        start), or ``pending`` itself without delays."""
        cfg = self.cfg
        if not cfg.max_input_delay:
            return pending
        hist = [Signal(cfg.n_inputs, name=f"in_hist{j}") for j in range(cfg.max_input_delay)]
        with m.If(start):
            m.d.sync += [h.eq(prev) for h, prev in zip(hist, [pending] + hist[:-1])]
        taps = [pending] + hist
        return Cat(*[taps[d][i] for i, d in enumerate(cfg.input_delays)])


def lif_verilog(config: LifConfig, name: str = "lif_core") -> str:
    """Verilog text of the core (no source locations: the same config gives the same bytes)."""
    return verilog_text(LifCore(config), name)


def generate_lif(out, config: LifConfig, name: str = "lif_core") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json`` (formats, constants and their errors,
    latency, ports, resources hint); returns the paths."""
    return write_block(out, LifCore(config), config.to_dict(), name)
