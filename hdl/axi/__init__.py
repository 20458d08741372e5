"""The AXI face: AXI4-Stream writes in and spikes out (``stream``), an AXI4-Lite register bank
(``lite``), what the bus faces share (``face``: :class:`StreamFace`, ticks, counters, the
register file), a block behind it with standard port names (``top``: :class:`AxiTop`,
:class:`BusTop`), and the protocol proofs (``formal``)."""

from .face import FACE_IDLE_CYCLES, StreamFace, face_cycles
from .lite import AxiLiteRegisters
from .stream import StreamSpikes, StreamWrites
from .top import AxiTop, BusTop

__all__ = ["AxiTop", "BusTop", "StreamFace", "StreamWrites", "StreamSpikes",
           "AxiLiteRegisters", "FACE_IDLE_CYCLES", "face_cycles"]
