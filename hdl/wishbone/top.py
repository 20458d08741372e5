"""A block behind the Wishbone face (:class:`WishboneTop`): the streams ``s_axis_*`` and
``m_axis_*`` as on the AXI face, the register map on a Wishbone B4 pipelined slave
(``wb_*``, :mod:`cuneate.hdl.wishbone.bus`)."""

from __future__ import annotations

from ..axi.top import BusTop
from ..lib.payload import PayloadSpec
from .bus import ADDR_BITS, WishboneRegisters

__all__ = ["WishboneTop"]


class WishboneTop(BusTop):
    """The block of ``spec`` behind the Wishbone face: ``s_axis_*``, ``m_axis_*``, ``wb_*``."""

    BUS = {"name": "wishbone-b4-pipelined", "data_bits": 32, "addr_bits": ADDR_BITS,
           "granularity": "word",
           "text": f"Wishbone B4 pipelined (wb_*), 32-bit data, {ADDR_BITS}-bit word "
                   f"addresses (byte offset / 4)"}

    def __init__(self, spec: PayloadSpec):
        super().__init__(spec, WishboneRegisters(), "wb_")
