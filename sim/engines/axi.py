"""The ``axi`` engine: a block behind the AXI face (:class:`~cuneate.hdl.axi.AxiTop`: AXI4-Stream
writes in and spikes out, AXI4-Lite registers), compiled by Verilator with its C++ bus harness
and driven through :class:`~cuneate.sim.axi.transport.AxiTransport` by the host's transport
contract, as ``board`` drives the UART face. Each block's engine interface runs its inputs
through the transport (:class:`~cuneate.sim.engines.board.FaceEngine`); each run's counters
hold the bus's figures (``axi_*``: cycles, beats and register accesses each way).
"""

from __future__ import annotations

from ..izhikevich.engines import IzhikevichEngine
from ..lif.engines import LifEngine
from ..network.engines import NetworkEngine
from ..plasticity.engines import PlasticityFace
from .board import FaceEngine
from .registry import implements

__all__ = ["AxiEngine", "AxiIzhikevich", "AxiLif", "AxiNetwork", "AxiPlasticity"]


class AxiEngine(FaceEngine):
    """The blocks behind the AXI face."""

    def transport_class(self) -> type:
        from ..axi.transport import AxiTransport     # Verilator's harness: loads when it runs
        return AxiTransport


@implements("izhikevich", "axi", speed=1e6)
class AxiIzhikevich(AxiEngine, IzhikevichEngine):
    """The core (or array) behind the AXI face, in a scene also behind the channel fan-out."""

    fanout = True


@implements("lif", "axi", speed=1e5)
class AxiLif(AxiEngine, LifEngine):
    """The LIF core behind the AXI face."""


@implements("network", "axi", speed=1e5)
class AxiNetwork(AxiEngine, NetworkEngine):
    """The afferent -> cuneate network behind the AXI face."""


@implements("plasticity", "axi", speed=1e5)
class AxiPlasticity(AxiEngine, PlasticityFace):
    """The learning layer behind the AXI face (:mod:`cuneate.hdl.plasticity.payload`)."""
