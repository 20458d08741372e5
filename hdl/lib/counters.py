"""A bank of saturating event counters, what every face counts with."""

from __future__ import annotations

from amaranth import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["CounterBank"]


class CounterBank(wiring.Component):
    """Counters of ``width`` bits, one per name, saturating at ``2**width - 1`` (never
    wrapping). ``inc_<name>`` (``inc_width`` bits) adds events in a cycle; ``clear`` zeroes
    every counter. Increments and the clear are registered before the adders (the logic that
    raises them does not lead into the carry chains): a counter shows its events two cycles
    after them (``count_<name>``)."""

    def __init__(self, names, width: int = 32, inc_width: int = 8):
        self.names, self.width = tuple(names), int(width)
        members = {"clear": In(1)}
        for n in self.names:
            members[f"inc_{n}"] = In(inc_width)
            members[f"count_{n}"] = Out(self.width)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        w = self.width
        clear = Signal()
        m.d.sync += clear.eq(self.clear)
        for n in self.names:
            inc = getattr(self, f"inc_{n}")
            inc_r = Signal.like(inc, name=f"inc_r_{n}")
            ctr = getattr(self, f"count_{n}")
            m.d.sync += inc_r.eq(inc)
            total = ctr + inc_r
            m.d.sync += ctr.eq(Mux(clear, 0, Mux(total[w], (1 << w) - 1, total[:w])))
        return m
