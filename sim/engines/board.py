"""The ``board`` engine: a block behind the UART host link, the board top compiled by
Verilator behind a simulated serial line (:class:`~cuneate.sim.link.engines.BoardTransport`,
opened for the block's configuration), driven by the real host stack.

One class per block it runs, each registered with
:func:`~cuneate.sim.engines.registry.implements`: the Izhikevich core (and, in a scene, the
channel fan-out before it or the afferent -> cuneate network behind the link), the LIF core,
the network and the learning layer. The engine gives its transport
(:meth:`BoardEngine.transport`); each block's engine interface runs its inputs through it (its
default ``sweeps`` or ``pairs``: the block's currents written for their ticks, the ticks
stepped, the spike frames read back, every counter of the transport contract checked and the
device's own error counters). The link carries
spikes alone: no clamp counts, no input spikes; each run's counters hold the line's figures
(``board_*``: cycles, bytes and frames each way).
"""

from __future__ import annotations

from ..izhikevich.engines import IzhikevichEngine
from ..lif.engines import LifEngine
from ..network.engines import NetworkEngine
from ...hdl.plasticity.payload import readout_bytes
from ..plasticity.engines import PlasticityFace
from .engine import BlockEngine
from .registry import implements

__all__ = ["FaceEngine", "BoardEngine", "BoardIzhikevich", "BoardLif", "BoardNetwork",
           "BoardPlasticity"]


class FaceEngine(BlockEngine):
    """What an engine reaching its blocks through a face shares: the transport
    (:meth:`transport_class`, opened by the caller; ``options``: more keywords of it), the
    device's own checks, the line's or bus's figures prefixed with the engine's name."""

    def __init__(self, name, build_dir=None, progress=None, waves=None, **options):
        super().__init__(name, build_dir, progress, waves)
        self.options = options

    def transport_class(self) -> type:
        raise NotImplementedError

    def transport(self, **more):
        return self.transport_class()(build_dir=self.build_dir, progress=self.progress,
                                      waves=self.waves, **self.options, **more)

    def checked_counters(self, transport) -> dict:
        return transport.check()            # the host's refusals and the device's errors

    def closed(self, transport, counters) -> dict:
        return counters | {f"{self.name}_{k}": v for k, v in transport.figures().items()}

    def fanout_transport(self, fanout):
        return self.transport(fanout=fanout)


class BoardEngine(FaceEngine):
    """The blocks behind the UART link (``options``: more
    :class:`~cuneate.sim.link.engines.BoardTransport` keywords: ``port``, ``ahead``,
    ``corrupt``, ...)."""

    def transport_class(self) -> type:
        # the board top's simulation (amaranth.sim, the UART host stack: measured 20 ms) loads
        # when a board runs, not whenever the registry loads the engines
        from ..link.engines import BoardTransport
        return BoardTransport


@implements("izhikevich", "board", speed=1e5)
class BoardIzhikevich(BoardEngine, IzhikevichEngine):
    """The core behind the link (:class:`~cuneate.hdl.link.LinkedTop`), in a scene also behind
    the channel fan-out or as the afferents of the afferent -> cuneate network."""

    layer, fanout = "chip", True


@implements("lif", "board", speed=1e3)
class BoardLif(BoardEngine, LifEngine):
    """The LIF core behind the link (:class:`~cuneate.hdl.link.LinkedTop`)."""


@implements("network", "board", speed=1e4)
class BoardNetwork(BoardEngine, NetworkEngine):
    """The network behind the link (:class:`~cuneate.hdl.link.LinkedTop`)."""


@implements("plasticity", "board", speed=1e4)
class BoardPlasticity(BoardEngine, PlasticityFace):
    """The learning layer behind the link: its afferent spikes, window ends and readouts
    streamed as writes (:mod:`cuneate.hdl.plasticity.payload`)."""

    def readout_synapses(self, cfg) -> int:
        """As many as a spike batch holds beside a tick's CN spikes, ``batch_sweeps``
        readout sweeps in a batch (at least one synapse)."""
        from ..link.engines import board_link         # the board top loads when it runs
        lc = board_link(cfg)
        per = (lc.batch_capacity - cfg.n_targets) // (lc.batch_sweeps * readout_bytes(cfg))
        return max(1, min(cfg.n_synapses, per))
