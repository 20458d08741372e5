"""A Wishbone B4 pipelined slave in front of the register file (:class:`WishboneRegisters`).

32-bit data, word addresses of ``ADDR_BITS`` bits (``wb_adr`` = byte offset / 4, as LiteX and
amaranth-soc address), byte selects ``wb_sel``. A request (``wb_cyc & wb_stb``) is taken in
the cycle it is offered (``wb_stall`` is always 0) and answered in the next cycle by ``wb_ack``
(``wb_dat_r`` holding a read's word) or ``wb_err`` (what the register file refuses,
:mod:`cuneate.hdl.lib.regmap`), one answer per request, in order; an answer due in a cycle
without ``wb_cyc`` is dropped (the master ended the cycle: B4's abort).
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..lib.regmap import MAP_BYTES, WORD_BITS, register_port

__all__ = ["WishboneRegisters", "ADDR_BITS"]

#: word address bits of the Wishbone port (4 KiB of bytes, as the AXI4-Lite face)
ADDR_BITS = 10


class WishboneRegisters(wiring.Component):
    """The Wishbone signals (without the ``wb_`` prefix a top adds) and ``regs``, the register
    file's port (:func:`~cuneate.hdl.lib.regmap.register_port`)."""

    def __init__(self):
        super().__init__({
            "cyc": In(1), "stb": In(1), "we": In(1), "adr": In(ADDR_BITS),
            "dat_w": In(WORD_BITS), "sel": In(WORD_BITS // 8), "dat_r": Out(WORD_BITS),
            "ack": Out(1), "err": Out(1), "stall": Out(1),
            "regs": Out(register_port()),
        })

    def answered(self, req):
        """The request answered in this cycle: the one taken in the last (a documented hook:
        the proof's mutant overrides it)."""
        return req

    def elaborate(self, platform):
        m = Module()
        r = self.regs
        top = MAP_BYTES // 4
        req = Signal(name="request")
        m.d.comb += [req.eq(self.cyc & self.stb), self.stall.eq(0),
                     r.en.eq(req), r.w_en.eq(self.we),
                     r.addr.eq(Mux(self.adr < top, self.adr, top)),
                     r.w_data.eq(self.dat_w), r.w_strb.eq(self.sel)]
        due = Signal(name="due")              # a request was taken in the last cycle
        bad = Signal(name="refused")
        m.d.sync += [due.eq(self.answered(req)), bad.eq(r.err)]
        with m.If(req & ~self.we):
            m.d.sync += self.dat_r.eq(r.r_data)
        m.d.comb += [self.ack.eq(due & ~bad & self.cyc), self.err.eq(due & bad & self.cyc)]
        return m
