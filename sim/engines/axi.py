"""The ``axi`` engine: a block behind the AXI face (:class:`~cuneate.hdl.axi.AxiTop`: AXI4-Stream
writes in and spikes out, AXI4-Lite registers), compiled by Verilator with its C++ bus harness
and driven through :class:`~cuneate.sim.axi.transport.AxiTransport` by the host's transport
contract, as ``board`` drives the UART face. Each block's engine interface runs its inputs
through the transport (:class:`~cuneate.sim.engines.board.FaceEngine`), the channel fan-out's
in front of the block too (:data:`~cuneate.sim.fanout.engines.FRONT`); each run's counters
hold the bus's figures (``axi_*``: cycles, beats and register accesses each way).
"""

from __future__ import annotations

from ..fanout.engines import FRONT
from .board import FaceEngine, face_engines

__all__ = ["AxiEngine", "AxiIzhikevich", "AxiLif", "AxiNetwork", "AxiPlasticity",
           "AxiFanoutFront"]


class AxiEngine(FaceEngine):
    """The blocks behind the AXI face."""

    def transport_class(self) -> type:
        from ..axi.transport import AxiTransport     # Verilator's harness: loads when it runs
        return AxiTransport


#: the AXI face's engines, one per block (the channel fan-out's: its payload adapter in the AXI
#: top, in front of a block)
AxiIzhikevich, AxiLif, AxiNetwork, AxiPlasticity, AxiFanoutFront = face_engines(
    AxiEngine, "axi", "Axi",
    {"izhikevich": 1e6, "lif": 1e5, "network": 1e5, "plasticity": 1e5, FRONT: 1e6})
