"""The ``board`` engine: a block behind the UART host link, the board top compiled by
Verilator behind a simulated serial line (:class:`~cuneate.sim.link.engines.BoardTransport`,
opened for the block's configuration), driven by the real host stack.

One class per block it runs (:func:`face_engines`, as for every face), each registered with
:func:`~cuneate.sim.engines.registry.implements`: the Izhikevich core (in a scene also as the
afferents of the afferent -> cuneate network behind the link), the LIF core, the network, the
learning layer, and the channel fan-out on chip in front of any of them
(:data:`~cuneate.sim.fanout.engines.FRONT`). The engine gives its transport
(:meth:`BoardEngine.transport`); each block's engine interface runs its inputs through it (its
default ``sweeps`` or ``pairs``: the block's currents written for their ticks, the ticks
stepped, the spike frames read back, every counter of the transport contract checked and the
device's own error counters). The link carries spikes alone: no clamp counts, no input
spikes; each run's counters hold the line's figures (``board_*``: cycles, bytes and frames each
way).
"""

from __future__ import annotations

from ..fanout.engines import FRONT, FanoutFront
from ..izhikevich.engines import IzhikevichEngine
from ..lif.engines import LifEngine
from ..network.engines import NetworkEngine
from ...hdl.lib.config import ConfigError
from ...hdl.plasticity.payload import readout_bytes
from ..plasticity.engines import PlasticityFace
from .engine import BlockEngine
from .registry import implements

__all__ = ["FaceEngine", "FACE_BLOCKS", "face_engines", "BoardEngine", "BoardIzhikevich",
           "BoardLif", "BoardNetwork", "BoardPlasticity", "BoardFanoutFront"]


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

    def front(self, fanout, inner):
        """The channel fan-out ``fanout`` on chip in front of the block (``inner``, this
        engine's implementation of it, needs nothing more): the transport built with it."""
        return self.transport(fanout=fanout)


#: the blocks every face serves: ``(block, its engine interface, its engines' class names'
#: ending)``
FACE_BLOCKS = (("izhikevich", IzhikevichEngine, "Izhikevich"), ("lif", LifEngine, "Lif"),
               ("network", NetworkEngine, "Network"), ("plasticity", PlasticityFace, "Plasticity"),
               (FRONT, FanoutFront, "FanoutFront"))


def face_engines(face: type, name: str, prefix: str, speeds: dict,
                 extras: dict | None = None) -> tuple[type, ...]:
    """The engines ``name`` of every block of :data:`FACE_BLOCKS` behind the face ``face`` (a
    :class:`FaceEngine`), each registered (:func:`~cuneate.sim.engines.registry.implements`)
    at ``speeds[block]``: the class ``prefix + ending`` of ``face`` and the block's engine
    interface, in ``face``'s module, with ``extras[block]`` (attributes the face adds for that
    block); in :data:`FACE_BLOCKS`' order."""
    made = []
    for block, interface, ending in FACE_BLOCKS:
        cls_name = prefix + ending
        body = {"__module__": face.__module__, "__qualname__": cls_name,
                "__doc__": f"The block ``{block}`` behind the ``{name}`` face "
                           f"(:class:`{face.__name__}`, :class:`{interface.__name__}`)."}
        cls = type(cls_name, (face, interface), body | (extras or {}).get(block, {}))
        made.append(implements(block, name, speed=speeds[block])(cls))
    return tuple(made)


class BoardEngine(FaceEngine):
    """The blocks behind the UART link (``options``: more
    :class:`~cuneate.sim.link.engines.BoardTransport` keywords: ``port``, ``ahead``,
    ``corrupt``, ...)."""

    def transport_class(self) -> type:
        # the board top's simulation (amaranth.sim, the UART host stack: measured 20 ms) loads
        # when a board runs, not whenever the registry loads the engines
        from ..link.engines import BoardTransport
        return BoardTransport


def _readout_synapses(self, cfg) -> int:
    """As many as a spike batch holds beside a tick's CN spikes, ``batch_sweeps`` readout
    sweeps in a batch; refused when not one synapse fits."""
    from ..link.engines import board_link         # the board top loads when it runs
    lc = board_link(cfg)
    per = (lc.batch_capacity - cfg.n_targets) // (lc.batch_sweeps * readout_bytes(cfg))
    if per < 1:
        raise ConfigError(f"the board link's spike batch ({lc.batch_capacity} spikes, "
                          f"{lc.batch_sweeps} sweeps) holds no readout of a synapse "
                          f"({readout_bytes(cfg)} bytes) beside {cfg.n_targets} CNs' spikes")
    return min(cfg.n_synapses, per)


#: the board's engines, one per block: the core in a scene also behind the channel fan-out or
#: as the afferents of the network on chip (``layer``); the learning layer's readout sweeps
#: sized to the link's spike batch (``readout_synapses``)
(BoardIzhikevich, BoardLif, BoardNetwork, BoardPlasticity, BoardFanoutFront) = face_engines(
    BoardEngine, "board", "Board",
    {"izhikevich": 1e5, "lif": 1e3, "network": 1e4, "plasticity": 1e4, FRONT: 1e5},
    extras={"izhikevich": {"layer": "chip"},
            "plasticity": {"readout_synapses": _readout_synapses}})
