"""On-chip afferent -> cuneate network: the Izhikevich core's spikes drive the coincidence
detector, with its bit-exact twin.

:class:`AfferentCuneateNetwork` holds an :class:`~cuneate.hdl.izhikevich.IzhikevichCore`
(``n_afferents`` afferent neurons, currents written by the host) and a
:class:`~cuneate.hdl.coincidence.CoincidenceDetector` whose source ``s`` is afferent neuron
``first_source + s`` (other afferents drive no detector input). Both share one tick:

* **Link.** Every afferent update leaves the core on ``upd_*`` at most one per cycle; a spike
  of a source neuron is one detector input event in that same cycle (``in_valid``,
  ``in_source``). The link has no buffer and no back-pressure, so it can neither drop nor
  duplicate an event: the detector accepts one event per cycle, the core emits at most one.
* **Sweep boundary.** A tick (external ``tick`` or the internal divider) is held in
  ``tick_pending`` until the core's previous sweep is complete (its ``sweep_done``, after the
  last update is on ``upd_*``) and the detector is idle; then the core starts sweep ``T`` and
  the detector stamps tick ``T`` in the same cycle. Every spike of sweep ``T - 1`` was an event
  before that cycle, so it is stamped with tick ``T`` - never ``T + 1``, never twice. A tick
  that arrives while one is pending is counted in ``overrun_count`` (not silently lost).

Latency, afferent update to PSP onset: the update of afferent ``s`` in sweep ``k`` (reported at
``(k + 1) dt``) is stamped with detector tick ``k + 1``, enters target ``t``'s input sum at tick
``k + 1 + delay[t, s]`` and first changes its PSP current at tick ``k + 2 + delay[t, s]`` (the
PSP kernel is 0 at lag 0). In cycles, the event reaches the detector
``PIPELINE_DEPTH + 1`` cycles after the neuron's fetch.

Output: one spike stream (``out_valid``/``out_ready``, ``out_population`` 0 = afferent,
1 = cuneate, ``out_index``, ``out_tick`` = sweep/tick number modulo ``2**sweep_number_width``;
both populations report the update of tick ``T`` as tick ``T``, i.e. at ``(T + 1) dt``).
Cuneate spikes go through a FIFO of ``cuneate_fifo_depth`` and have priority; the afferent spikes
through the core's own FIFO (``2 n_afferents`` deep). A full FIFO drops and says so
(``cuneate_overflow_count``, sticky ``afferent_overflow``).

Tick report: ``tick_open`` rises with a tick taken and falls with ``tick_done`` (one cycle),
once every spike of that tick has been handed to the output stream: the core's sweep and the
detector's update are done, :data:`REPORT_SETTLE` cycles have passed for the FIFOs' outputs
to show their last entries, and both FIFOs are empty. A consumer that takes no tick while
``busy | tick_open`` (its payload, :mod:`cuneate.hdl.network.payload`) sees every tick's
spikes before its ``tick_done`` and none of the next tick's; the FIFOs then hold one tick's
spikes at most and cannot overflow.
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from ..coincidence.core import CoincidenceDetector
from ..flow.synth import synthesize_flows
from ..flow.verilog import verilog_text, write_block
from ..izhikevich.core import IzhikevichCore
from ..lib.tick import tick_strobe
from .config import NetworkConfig

__all__ = ["synth_resources", "AfferentCuneateNetwork", "network_verilog", "generate_network",
           "COUNTER_BITS", "REPORT_SETTLE"]

COUNTER_BITS = 32
#: cycles after the core's sweep and the detector's update are done before the FIFOs' outputs
#: are trusted to show every spike written (a write reaches a buffered FIFO's output in two)
REPORT_SETTLE = 4


class AfferentCuneateNetwork(wiring.Component):
    """The network as RTL (see the module docstring).

    Ports: ``i_wr_en/i_wr_addr/i_wr_data`` (host currents of the afferents, format of the core),
    ``tick`` (external tick), ``out_valid/out_ready/out_population/out_index/out_tick`` (spike
    stream), ``tick_count``, ``link_count`` (afferent spikes passed to the detector),
    ``afferent_spike_count``, ``cuneate_spike_count``, ``overrun_count``,
    ``cuneate_overflow_count`` and ``afferent_overflow`` (sticky: the core's FIFO dropped a
    spike), ``merged_count`` (events the detector merged: 0 by construction),
    ``clamp_flags`` (core | detector, sticky; ``clamp_clear`` clears both), ``busy``,
    ``tick_open`` and ``tick_done`` (the
    tick report, see the module docstring).
    """

    #: the ports' meanings, for the Verilog's header
    PORT_MEANINGS = {
        "i_wr_en": "host current write strobe (afferents)", "out_valid": "spike stream: valid",
        "out_ready": "spike stream: taken", "out_population": "0 afferent, 1 cuneate",
        "out_index": "the neuron", "out_tick": "its tick", "tick_count": "ticks",
        "link_count": "afferent spikes passed to the detector",
        "afferent_spike_count": "afferent spikes", "cuneate_spike_count": "cuneate spikes",
        "overrun_count": "ticks ignored", "cuneate_overflow_count": "cuneate spikes lost",
        "afferent_overflow": "sticky: the core's spike FIFO dropped a spike",
        "merged_count": "events the detector merged (0 by construction)",
        "clamp_flags": "sticky clamp flags (core and detector)",
        "tick_open": "a tick's batch is open", "tick_done": "pulse: the tick's batch is closed"}

    def __init__(self, config: NetworkConfig):
        self.cfg = cfg = config
        N, M = cfg.n_afferents, cfg.n_targets
        sig = {"i_wr_en": In(1), "i_wr_addr": In(range(N)), "i_wr_data": In(cfg.core.I.shape()),
               "out_valid": Out(1), "out_ready": In(1), "out_population": Out(1),
               "out_index": Out(range(max(N, M))), "out_tick": Out(cfg.tick_width),
               "tick_count": Out(COUNTER_BITS), "link_count": Out(COUNTER_BITS),
               "afferent_spike_count": Out(COUNTER_BITS),
               "cuneate_spike_count": Out(COUNTER_BITS), "overrun_count": Out(COUNTER_BITS),
               "cuneate_overflow_count": Out(COUNTER_BITS), "afferent_overflow": Out(1),
               "merged_count": Out(COUNTER_BITS),
               "clamp_flags": Out(5), "clamp_clear": In(1), "busy": Out(1),
               "tick_open": Out(1),
               "tick_done": Out(1)}
        if cfg.tick_source == "external":
            sig["tick"] = In(1)
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        S, M = cfg.n_sources, cfg.n_targets
        m = Module()
        m.submodules.core = core = IzhikevichCore(cfg.core)
        m.submodules.det = det = CoincidenceDetector(cfg.det)
        self.core, self.det = core, det
        m.d.comb += [core.i_wr_en.eq(self.i_wr_en), core.i_wr_addr.eq(self.i_wr_addr),
                     core.i_wr_data.eq(self.i_wr_data), core.sel_wr_en.eq(0),
                     det.clamp_clear.eq(self.clamp_clear),
                     core.clamp_clear.eq(self.clamp_clear)]

        # ---- tick: held until the previous sweep is complete and the detector idle
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        pending = Signal()
        inflight = Signal()            # a core sweep started and its sweep_done not yet seen
        go = Signal()
        m.d.comb += go.eq((pending | tick) & ~inflight & ~det.busy & ~core.sweep_done)
        m.d.comb += [core.tick.eq(go), det.tick.eq(go)]
        with m.If(go):
            m.d.sync += [pending.eq(0), inflight.eq(1), self.tick_count.eq(self.tick_count + 1)]
        with m.Else():
            with m.If(tick):
                m.d.sync += pending.eq(1)
                with m.If(pending):
                    m.d.sync += self.overrun_count.eq(self.overrun_count + 1)
            with m.If(core.sweep_done):
                m.d.sync += inflight.eq(0)
        m.d.comb += self.busy.eq(inflight | det.busy | pending)

        # ---- link: one afferent update per cycle -> at most one detector event per cycle
        link = Signal()
        F = cfg.first_source
        m.d.comb += link.eq(core.upd_valid & core.upd_spike & (core.upd_index >= F)
                            & (core.upd_index < F + S))
        m.d.comb += [det.in_valid.eq(link), det.in_source.eq(core.upd_index - F)]
        with m.If(link):
            m.d.sync += self.link_count.eq(self.link_count + 1)
        with m.If(core.upd_valid & core.upd_spike):
            m.d.sync += self.afferent_spike_count.eq(self.afferent_spike_count + 1)
        with m.If(det.spike_valid):
            m.d.sync += self.cuneate_spike_count.eq(self.cuneate_spike_count + 1)
        m.d.comb += [self.merged_count.eq(det.merged_count),
                     self.clamp_flags.eq(core.clamp_flags | det.clamp_flags)]

        # ---- output stream: cuneate FIFO first, then the core's spike FIFO
        iw = max(1, (M - 1).bit_length())
        tw = cfg.tick_width
        m.submodules.cun_fifo = fifo = SyncFIFOBuffered(width=iw + tw,
                                                        depth=cfg.cuneate_fifo_depth)
        m.d.comb += [fifo.w_en.eq(det.spike_valid),
                     fifo.w_data.eq(Cat(det.spike_target[:iw], det.spike_tick[:tw]))]
        with m.If(det.spike_valid & ~fifo.w_rdy):
            m.d.sync += self.cuneate_overflow_count.eq(self.cuneate_overflow_count + 1)
        m.d.comb += self.afferent_overflow.eq(core.spike_overflow)
        cun = fifo.r_rdy
        m.d.comb += [
            self.out_valid.eq(cun | core.spike_valid),
            self.out_population.eq(cun),
            self.out_index.eq(Mux(cun, fifo.r_data[:iw], core.spike_index)),
            self.out_tick.eq(Mux(cun, fifo.r_data[iw:], core.spike_sweep)),
            fifo.r_en.eq(self.out_ready & cun),
            core.spike_ready.eq(self.out_ready & ~cun),
        ]

        # ---- tick report: every spike of the tick taken handed to the stream
        settle = Signal(range(REPORT_SETTLE + 1))
        with m.If(go):
            m.d.sync += [self.tick_open.eq(1), settle.eq(REPORT_SETTLE)]
        with m.Elif(self.tick_open & ~inflight & ~det.busy):
            with m.If(settle != 0):
                m.d.sync += settle.eq(settle - 1)
            with m.Elif(~self.out_valid):
                m.d.comb += self.tick_done.eq(1)
                m.d.sync += self.tick_open.eq(0)
        return m


def network_verilog(cfg: NetworkConfig, name: str = "afferent_cuneate_network",
                    lowered: bool = False) -> str:
    """Verilog of the network; ``lowered`` gives the yosys-lowered netlist for Icarus 11 (see
    :func:`cuneate.hdl.flow.verilog.lowered_verilog`), here without ``opt_clean`` so the blocks'
    internal update outputs (``core.upd_*``, ``det.upd_*``) stay visible to a scoreboard."""
    return verilog_text(AfferentCuneateNetwork(cfg), name, lowered, opt_clean=False)


def generate_network(out, cfg: NetworkConfig, name: str = "afferent_cuneate_network") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json``; returns the paths."""
    return write_block(out, AfferentCuneateNetwork(cfg), cfg.to_dict(), name)


def synth_resources(cfg, flows=("ecp5", "xc6s"), workdir=None) -> dict:
    """Synthesis figures (cell counts, no fmax) of the block built from ``cfg`` per flow."""
    return synthesize_flows(network_verilog(cfg), "afferent_cuneate_network", flows, workdir)
