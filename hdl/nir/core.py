"""A NIR network on chip: a chain of LIF cores (:class:`~cuneate.hdl.lif.LifCore`) sharing one
tick, and its Verilog.

* **Layers.** Core ``layer<l>`` holds layer ``l``'s neurons, its weight memory the Affine/Linear
  weights into them (one column per neuron of layer ``l - 1``, or per network input), its
  current memory the host-written constant currents (the Affine biases, written once through
  ``i_wr_*`` with ``i_wr_layer``), its parameter sets the neurons' decay, threshold and reset,
  its optional current-based synapse (CubaLIF) and input delays (Delay).
* **Links.** Every update of layer ``l`` leaves its core on ``upd_*``, one per cycle; a spike
  is an input event of layer ``l + 1`` in the same cycle (``in_valid``, ``in_source`` = the
  neuron's index). No buffer and no back-pressure: the next core takes one event per cycle,
  the core emits at most one, so nothing can be dropped or duplicated. The events of sweep
  ``k`` are pending in the next core until tick ``k + 1``.
* **Tick.** ``tick`` starts every core at once, but only ``settle_cycles`` after the previous
  one (every core's sweep issued, its pipeline drained, its spikes passed on); a tick that comes
  earlier is held (``busy``) and taken then; one more while one is held is counted in
  ``tick_overrun`` (never lost silently).
* **Output.** The last layer's spike stream (``out_valid/out_ready/out_index/out_sweep``,
  sweep modulo ``2**sweep_number_width``) or, for a readout layer (NIR's LI, CubaLI), its
  membrane of every update (``out_v_valid``, ``out_v_index``, ``out_v``).
"""

from __future__ import annotations

from amaranth import Module, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..flow.verilog import verilog_text, write_block
from ..lif.config import CLAMP_KINDS
from ..lif.core import LifCore
from .config import NirNetworkConfig

__all__ = ["NirNetwork", "nir_network_verilog", "generate_nir_network", "COUNTER_BITS"]

COUNTER_BITS = 32


class NirNetwork(wiring.Component):
    """The network as RTL (see the module docstring)."""

    #: the ports' meanings, for the Verilog's header
    PORT_MEANINGS = {
        "i_wr_layer": "the layer written", "out_valid": "output spike: valid",
        "out_ready": "output spike: taken", "out_index": "the output neuron",
        "out_sweep": "its sweep", "out_v_valid": "readout membrane: valid",
        "out_v_index": "its neuron", "out_v": "its membrane (raw)",
        "tick_overrun": "ticks that came before the network settled",
        "in_valid": "an input spike arrives", "in_source": "its input"}

    def __init__(self, config: NirNetworkConfig):
        self.cfg = cfg = config
        L = cfg.n_layers
        maxN = max(c.n_neurons for c in cfg.layers)
        iw = max(c.I.width for c in cfg.layers)
        last = cfg.layers[-1]
        sig = {"tick": In(1), "i_wr_en": In(1), "i_wr_layer": In(range(max(L, 2))),
               "i_wr_addr": In(range(maxN)), "i_wr_data": In(signed(iw)),
               "out_valid": Out(1), "out_ready": In(1), "out_index": Out(range(last.n_neurons)),
               "out_sweep": Out(last.sweep_number_width),
               "out_v_valid": Out(1), "out_v_index": Out(range(last.n_neurons)),
               "out_v": Out(last.V.shape()), "tick_overrun": Out(COUNTER_BITS),
               "clamp_flags": Out(len(CLAMP_KINDS)), "spike_overflow": Out(1), "busy": Out(1)}
        if cfg.n_inputs:
            sig.update(in_valid=In(1), in_source=In(range(cfg.n_inputs)))
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        m = Module()
        cores = []
        for li, c in enumerate(cfg.layers):
            core = LifCore(c)
            m.submodules[f"layer{li}"] = core
            cores.append(core)
            m.d.comb += [core.i_wr_en.eq(self.i_wr_en & (self.i_wr_layer == li)),
                         core.i_wr_addr.eq(self.i_wr_addr), core.i_wr_data.eq(self.i_wr_data),
                         core.sel_wr_en.eq(0), core.clamp_clear.eq(0)]
            if li < cfg.n_layers - 1:
                m.d.comb += core.spike_ready.eq(1)
        # --- links: layer l's spikes are layer l+1's input events ----------------------------
        if cfg.n_inputs:
            m.d.comb += [cores[0].in_valid.eq(self.in_valid),
                         cores[0].in_source.eq(self.in_source)]
        for a, b in zip(cores, cores[1:]):
            m.d.comb += [b.in_valid.eq(a.upd_valid & a.upd_spike), b.in_source.eq(a.upd_index)]
        # --- the tick: all cores at once, settle_cycles apart ---------------------------------
        settle = cfg.settle_cycles
        since = Signal(range(settle + 1), init=settle)
        held = Signal()
        fire = (since == settle) & (held | self.tick)
        with m.If(fire):
            m.d.sync += [since.eq(0), held.eq(0)]
        with m.Else():
            with m.If(since != settle):
                m.d.sync += since.eq(since + 1)
            with m.If(self.tick):
                with m.If(held):
                    m.d.sync += self.tick_overrun.eq(self.tick_overrun + 1)
                m.d.sync += held.eq(1)
        for core in cores:
            m.d.comb += core.tick.eq(fire)
        m.d.comb += self.busy.eq(held | (since != settle))
        # --- output ----------------------------------------------------------------------------
        out = cores[-1]
        m.d.comb += [self.out_valid.eq(out.spike_valid), out.spike_ready.eq(self.out_ready),
                     self.out_index.eq(out.spike_index), self.out_sweep.eq(out.spike_sweep),
                     self.out_v_valid.eq(out.upd_valid), self.out_v_index.eq(out.upd_index),
                     self.out_v.eq(out.upd_v)]
        flags = 0
        overflow = 0
        for core in cores:
            flags = flags | core.clamp_flags
            overflow = overflow | core.spike_overflow
        m.d.comb += [self.clamp_flags.eq(flags), self.spike_overflow.eq(overflow)]
        return m


def nir_network_verilog(config: NirNetworkConfig, name: str = "nir_network") -> str:
    """Verilog text of the network (deterministic)."""
    return verilog_text(NirNetwork(config), name)


def generate_nir_network(out, config: NirNetworkConfig, name: str = "nir_network") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json``; returns the paths."""
    return write_block(out, NirNetwork(config), config.to_dict(), name)
