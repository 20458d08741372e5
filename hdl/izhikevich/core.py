"""The Izhikevich core's RTL: a time-multiplexed, pipelined Amaranth component built from the
datapath's stage functions (:mod:`cuneate.hdl.izhikevich.datapath`), one pipeline register after
each, and its Verilog.

Latency 5 cycles (fetch, registered read, operands and first multipliers, second multipliers,
update and write-back), then one neuron update per clock; formats from
:class:`~cuneate.hdl.izhikevich.config.IzhikevichConfig`.
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import Out

from ..flow.verilog import write_block, verilog_text
from ..lib.bookkeeping import (core_memories, core_ports, pipeline_tags, registrar,
                               sweep_bookkeeping, sweep_issue)
from ..lib.tick import tick_strobe
from .config import CLAMP_KINDS, IzhikevichConfig
from . import datapath

__all__ = ["IzhikevichCore", "izhikevich_verilog", "generate_izhikevich"]


class IzhikevichCore(wiring.Component):
    """Time-multiplexed Izhikevich core: one neuron update per clock, 5-stage pipeline.

    Pipeline (a neuron's index enters at cycle t; its result is on ``upd_*`` at t+5):

    1. **Fetch** - the sweep counter addresses the state (v, u), current and set-select RAMs
       (synchronous read).
    2. **Read** - the RAM outputs are registered (no logic after the block RAM).
    3. **Operands, multiply 1** - ``w = v + 62.5`` and ``v`` rounded to multiplier width, then
       ``(A dt) w`` and ``b v``; ``dt I - dt u`` by shifts (or ``I - u`` rounded and
       multiplied by ``dt`` when dt is not a power of two).
    4. **Multiply 2** - ``((A dt) w) w`` and ``(a dt)(b v - u)``; meanwhile
       ``v + dt (I - u) + dt (C - B^2/4A)`` is summed.
    5. **Update** - add the products into ``v'`` and ``u'`` (rounding as a carry-in),
       threshold, reset, saturate; write back to the state RAM and register the outputs.

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
    """

    def __init__(self, config: IzhikevichConfig | None = None, **kwargs):
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        sig = core_ports(cfg, CLAMP_KINDS, {"upd_v": Out(cfg.V.shape()),
                                            "upd_u": Out(cfg.U.shape())})
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        N = cfg.n_neurons
        m = Module()
        V, U = cfg.V, cfg.U

        def pack(v, u):
            return (v & ((1 << V.width) - 1)) | ((u & ((1 << U.width) - 1)) << V.width)

        init_state = [pack(int(v), int(u)) for v, u in zip(cfg.v_init_raw, cfg.u_init_raw)]
        st_rd, st_wr, cur_rd, sel_rd = core_memories(m, self, cfg, V.width + U.width,
                                                     init_state)

        # --- sweep control and pipeline tags ----------------------------------------------
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        issue = sweep_issue(m, self, N, tick, cfg.sweep_number_width)
        for port in (st_rd, cur_rd, sel_rd):
            m.d.comb += [port.addr.eq(issue.addr), port.en.eq(1)]
        tags = pipeline_tags(m, N, cfg.sweep_number_width, issue)
        t3, t5 = tags[3], tags[5]
        reg = registrar(m)

        # --- stage 2: the RAM outputs go straight into registers -------------------------
        v3 = reg("v", st_rd.data[:V.width].as_signed(), 3)
        u3 = reg("u", st_rd.data[V.width:].as_signed(), 3)
        i3, sel3 = reg("i", cur_rd.data, 3), reg("sel", sel_rd.data, 3)
        # what an update starts from, for the formal harness (hdl/izhikevich/formal.py)
        self.probes = {"valid": t3[0], "index": t3[1], "v": v3, "u": u3, "i": i3, "sel": sel3}
        # --- stage 3: operands and the first multipliers ----------------------------------
        # the stage functions are looked up in their module at elaboration, so a fault
        # injected there (tests) reaches the RTL and not the twin
        s2 = datapath.operands(cfg, v3, u3, i3, sel3)
        wq3, vq3, x3 = s2["wq"], s2["vq"], s2["x"]
        s3 = datapath.multiply1(cfg, wq3, vq3, x3, u3, sel3)
        v4, u4, i4, sel4, wq4 = (reg(n, x, 4) for n, x in
                                 (("v", v3), ("u", u3), ("i", i3), ("sel", sel3), ("wq", wq3)))
        q4, bvp4, x4 = reg("q", s3["q"], 4), reg("bvp", s3["bvp"], 4), reg("x", s3["x"], 4)
        uy4 = reg("uy", s3["uy"], 4)
        fi4 = reg("flag_current", s2["i_flag"], 4)
        # --- stage 4 ----------------------------------------------------------------------
        s4 = datapath.multiply2(cfg, q4, bvp4, uy4, wq4, v4, u4, x4, sel4)
        i5, sel5 = reg("i", i4, 5), reg("sel", sel4, 5)
        p5, m5 = reg("p", s4["p"], 5), reg("m", s4["m"], 5)
        sums5 = [reg(n, s4[n], 5) for n in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh")]
        fi5, fy5 = reg("flag_current", fi4, 5), reg("flag_y", s4["y_flag"], 5)
        # --- stage 5 ----------------------------------------------------------------------
        s5 = datapath.update_state(cfg, *sums5, p5, m5, sel5)
        v_out = Signal(V.shape())
        u_out = Signal(U.shape())
        spike = Signal()
        clamp = Signal(len(CLAMP_KINDS))
        flags = {"v_low": s5["v_low"], "u_high": s5["u_high"], "u_low": s5["u_low"],
                 "current": fi5, "y": fy5}
        m.d.comb += [v_out.eq(s5["v"]), u_out.eq(s5["u"]), spike.eq(s5["spike"] & t5[0]),
                     clamp.eq(Mux(t5[0], Cat(*(flags[k] for k in CLAMP_KINDS)), 0))]
        m.d.comb += [st_wr.addr.eq(t5[1]), st_wr.data.eq(Cat(v_out, u_out)),
                     st_wr.en.eq(t5[0])]
        m.d.sync += [self.upd_valid.eq(t5[0]), self.upd_index.eq(t5[1]), self.upd_v.eq(v_out),
                     self.upd_u.eq(u_out), self.upd_current.eq(i5), self.upd_spike.eq(spike),
                     self.upd_clamp.eq(clamp)]

        # --- bookkeeping from the registered outputs (off the datapath's critical path) -----
        sweep_bookkeeping(m, self, N, cfg.sweep_number_width, t5, CLAMP_KINDS,
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
