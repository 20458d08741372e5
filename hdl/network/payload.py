"""The afferent -> cuneate network as a payload (:mod:`cuneate.hdl.lib.payload`): the
afferents' currents in, the spikes of both populations out in one id space (afferent ``i`` as
``i``, cuneate neuron ``j`` as ``n_afferents + j``), each tagged with the tick the network
reports it at."""

from __future__ import annotations

import numpy as np
from amaranth import Module, Mux

from ..izhikevich.config import CLAMP_KINDS
from ..lib.payload import (BlockPayload, BlockSpec, PayloadInfo, PayloadTwin, implements,
                           write_port)
from .config import NetworkConfig
from .core import REPORT_SETTLE, AfferentCuneateNetwork
from .twin import NetworkTwin

__all__ = ["NetworkSpec", "NetworkPayload"]


@implements(NetworkConfig)
class NetworkSpec(BlockSpec):
    """The network of ``config``. A tick keeps it busy for its tick work (``cycles_needed``),
    the report's settling and the draining of one spike per afferent and cuneate neuron."""

    def __init__(self, config: NetworkConfig):
        self.config = c = config
        N, M = c.n_afferents, c.n_targets
        self.info = PayloadInfo(
            block="afferent_cuneate_network", written="current", n_written=N,
            value_format=c.core.I, populations=(("afferent", 0, N), ("cuneate", N, M)),
            sweep_width=c.tick_width, clock_hz=c.clock_hz, update_hz=c.update_hz,
            cycles_per_tick=c.cycles_per_tick,
            busy_cycles=c.cycles_needed + REPORT_SETTLE + N + M, clamp_kinds=CLAMP_KINDS,
            rounding=c.core.rounding,
            parts=({"block": "izhikevich_core", "neurons": N, "role": "afferents"},
                   {"block": "coincidence_detector", "neurons": M,
                    "sources": c.n_sources}))

    def component(self) -> "NetworkPayload":
        return NetworkPayload(self)

    def twin(self) -> "_NetworkTwin":
        return _NetworkTwin(NetworkTwin(self.config))


class _NetworkTwin(PayloadTwin):
    """The network's twin as a payload: a tick's afferent spikes as their ids, its cuneate
    spikes after them (``n_afferents + j``)."""

    def __init__(self, twin: NetworkTwin):
        self.model = twin

    def write(self, addr: int, raw: int) -> None:
        self.model.core.I[int(addr)] = raw

    def sweep(self) -> np.ndarray:
        aff, cun = self.model.tick()
        return np.concatenate([np.flatnonzero(aff),
                               self.model.cfg.n_afferents + np.flatnonzero(cun)])

    def clamp_flags(self) -> int:
        return int(self.model.core.clamp_sticky | self.model.det.clamp_sticky)


class NetworkPayload(BlockPayload):
    """:class:`~cuneate.hdl.network.AfferentCuneateNetwork` (the attribute ``network``) behind
    the payload signature. ``busy`` is the network's ``busy | tick_open`` (the next tick waits
    until every spike of the last is handed over), ``sweep_done`` its ``tick_done``."""

    def __init__(self, spec: NetworkSpec):
        super().__init__(spec, network=AfferentCuneateNetwork(spec.config))

    def elaborate(self, platform):
        m = Module()
        m.submodules.network = net = self.network
        N = self.spec.config.n_afferents
        s = self.spikes
        m.d.comb += write_port(self.write, net)
        m.d.comb += [
            s.valid.eq(net.out_valid), net.out_ready.eq(s.ready),
            s.payload.index.eq(Mux(net.out_population, N + net.out_index, net.out_index)),
            s.payload.sweep.eq(net.out_tick),
            net.tick.eq(self.tick), self.busy.eq(net.busy | net.tick_open),
            self.sweep_done.eq(net.tick_done),
            self.clamp_flags.eq(net.clamp_flags), net.clamp_clear.eq(self.clamp_clear),
            self.overflow.eq(net.afferent_overflow | (net.cuneate_overflow_count != 0)),
            self.overrun.eq(net.overrun_count != 0),
        ]
        return m
