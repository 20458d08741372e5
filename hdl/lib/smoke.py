"""A deliberately tiny component used to prove the HDL toolchain end to end.

:class:`SmokeCounter` is converted to Verilog and simulated by cocotb on Icarus and Verilator.
It exercises a clocked register, a synchronous reset and a combinational output, which is all
the smoke test needs to show that export, build and per-cycle checking work.
"""

from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["SmokeCounter", "smoke_reference"]


class SmokeCounter(wiring.Component):
    """Counter that adds ``step`` every enabled cycle, wrapping at ``2**width``.

    Ports: ``en`` (in), ``step`` (in, ``width`` bits), ``count`` (out, registered, latency 1),
    ``is_zero`` (out, combinational from ``count``).
    """

    def __init__(self, width: int = 8):
        if width < 1:
            raise ValueError("width must be >= 1")
        self.width = width
        super().__init__({"en": In(1), "step": In(width), "count": Out(width),
                          "is_zero": Out(1)})

    def elaborate(self, platform):
        m = Module()
        with m.If(self.en):
            m.d.sync += self.count.eq(self.count + self.step)
        m.d.comb += self.is_zero.eq(self.count == 0)
        return m


def smoke_reference(width, enables, steps):
    """Expected ``count`` after each cycle for the given per-cycle inputs (pure Python)."""
    out, c = [], 0
    for en, st in zip(enables, steps):
        if en:
            c = (c + st) % (1 << width)
        out.append(c)
    return out
