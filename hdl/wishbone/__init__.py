"""The Wishbone face: the register map on a Wishbone B4 pipelined slave (``bus``), and a block
behind it with the AXI4-Stream streams (``top``: :class:`WishboneTop`); ``formal``: its
handshake proof."""

from .bus import WishboneRegisters
from .top import WishboneTop

__all__ = ["WishboneRegisters", "WishboneTop"]
