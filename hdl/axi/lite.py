"""An AXI4-Lite slave in front of the register file (:class:`AxiLiteRegisters`).

32-bit data, byte addresses of ``ADDR_BITS`` bits (the map in the low ``MAP_BYTES``; the low
two bits ignored). One access at a time per direction: a write is taken when its address and
its data are both offered (AWREADY and WREADY together; the slave may wait for both, AXI4
A3.3.1) and no write response waits; a read when no read response waits and no write is taken
in the same cycle (the register file has one port: a write goes first). Each response (BVALID,
RVALID with RDATA) is a register held until the master takes it; BRESP/RRESP are OKAY, or
SLVERR for what the register file refuses (:mod:`cuneate.hdl.lib.regmap`).
"""

from __future__ import annotations

from amaranth import Module, Mux
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..lib.regmap import MAP_BYTES, WORD_BITS, register_port

__all__ = ["AxiLiteRegisters", "ADDR_BITS", "OKAY", "SLVERR"]

#: byte address bits of the AXI4-Lite port (a 4 KiB window, the smallest an address editor
#: assigns)
ADDR_BITS = 12
OKAY, SLVERR = 0b00, 0b10


class AxiLiteRegisters(wiring.Component):
    """The AXI4-Lite channels (AXI's names without the ``s_axil_`` prefix a top adds) and
    ``regs``, the register file's port (:func:`~cuneate.hdl.lib.regmap.register_port`)."""

    def __init__(self):
        super().__init__({
            "awaddr": In(ADDR_BITS), "awvalid": In(1), "awready": Out(1),
            "wdata": In(WORD_BITS), "wstrb": In(WORD_BITS // 8), "wvalid": In(1),
            "wready": Out(1),
            "bresp": Out(2), "bvalid": Out(1), "bready": In(1),
            "araddr": In(ADDR_BITS), "arvalid": In(1), "arready": Out(1),
            "rdata": Out(WORD_BITS), "rresp": Out(2), "rvalid": Out(1), "rready": In(1),
            "regs": Out(register_port()),
        })

    def keep_b(self):
        """Whether the write response stays on offer this cycle (a documented hook: the
        proof's mutant overrides it)."""
        return self.bvalid & ~self.bready

    def elaborate(self, platform):
        m = Module()
        r = self.regs
        top = MAP_BYTES // 4

        def word(addr):
            # addresses past the map decode to the first word outside it (an error)
            return Mux(addr[2:] < top, addr[2:], top)

        write = self.awvalid & self.wvalid & ~self.bvalid
        read = self.arvalid & ~self.rvalid & ~write
        m.d.comb += [self.awready.eq(write), self.wready.eq(write), self.arready.eq(read),
                     r.en.eq(write | read), r.w_en.eq(write),
                     r.addr.eq(Mux(write, word(self.awaddr), word(self.araddr))),
                     r.w_data.eq(self.wdata), r.w_strb.eq(self.wstrb)]
        with m.If(write):
            m.d.sync += [self.bvalid.eq(1), self.bresp.eq(Mux(r.err, SLVERR, OKAY))]
        with m.Else():
            m.d.sync += self.bvalid.eq(self.keep_b())
        with m.If(read):
            m.d.sync += [self.rvalid.eq(1), self.rdata.eq(r.r_data),
                         self.rresp.eq(Mux(r.err, SLVERR, OKAY))]
        with m.Elif(self.rready):
            m.d.sync += self.rvalid.eq(0)
        return m
