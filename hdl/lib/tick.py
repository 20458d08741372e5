"""The tick every time-multiplexed block starts its sweeps on: a block's own divider
(:func:`tick_strobe`) or a face's tick generator (:class:`TickGenerator`)."""

from __future__ import annotations

from amaranth import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["tick_strobe", "TickGenerator"]


def tick_strobe(m: Module, cfg, tick_in=None) -> Signal:
    """A one-cycle strobe that starts a sweep.

    With ``cfg.tick_source == "internal"`` it comes from a divider of ``cfg.cycles_per_tick``
    cycles (first strobe in cycle 0); with ``"external"`` it is ``tick_in``, the block's
    ``tick`` input."""
    if cfg.tick_source == "internal":
        # the strobe is a register (``div`` wraps to 0 in the cycle it is set): the sweep
        # issue's multiplexers start from registers only
        n = cfg.cycles_per_tick
        div = Signal(range(n))
        tick = Signal(init=1, name="tick_strobe")
        wrap = div == n - 1
        m.d.sync += [div.eq(Mux(wrap, 0, div + 1)), tick.eq(wrap)]
        return tick
    tick = Signal()
    m.d.comb += tick.eq(tick_in)
    return tick


class TickGenerator(wiring.Component):
    """A face's ticks: a divider of ``cycles_per_tick`` that runs freely (``start``), for
    ``step_count`` ticks (``step``) or not at all (``stop``, the state after reset).

    A due tick waits (``pending``) while ``hold`` (the block is busy or the face is writing
    into it) and goes, as ``tick`` for one cycle, in the first cycle without: its jitter is
    the hold, the divider keeps its pace (no drift). A tick due while the previous one still
    waits is lost (``overrun`` pulses). ``sweeps_started`` counts the ticks given; ``running``
    is high while ticks are due (``free``, or ``steps`` left).

    With ``settable`` the divider is the input ``divider`` (cycles from one tick to the next,
    >= 1; a smaller value takes effect at once) instead of the constant."""

    def __init__(self, cycles_per_tick: int, settable: bool = False):
        self.cycles_per_tick = int(cycles_per_tick)
        self.settable = bool(settable)
        members = {
            "hold": In(1), "start": In(1), "stop": In(1), "step": In(1), "step_count": In(32),
            "tick": Out(1), "running": Out(1), "free": Out(1), "steps": Out(32),
            "pending": Out(1), "sweeps_started": Out(32), "overrun": Out(1),
        }
        if self.settable:
            members["divider"] = In(32, init=self.cycles_per_tick)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        n = self.cycles_per_tick
        active = self.free | (self.steps != 0)
        m.d.comb += [self.running.eq(active),
                     self.tick.eq(self.pending & ~self.hold)]
        if self.settable:
            div = Signal(32)
            wrap = div + 1 >= self.divider
        else:
            div = Signal(range(n))
            wrap = div == n - 1
        fire = active & wrap
        with m.If(active):
            m.d.sync += div.eq(Mux(wrap, 0, div + 1))
        with m.If(self.tick):
            m.d.sync += self.sweeps_started.eq(self.sweeps_started + 1)
            with m.If(~self.free & (self.steps != 0)):
                m.d.sync += self.steps.eq(self.steps - 1)
        with m.If(fire):
            m.d.sync += self.pending.eq(1)
            with m.If(self.pending & ~self.tick):
                m.d.comb += self.overrun.eq(1)
        with m.Elif(self.tick):
            m.d.sync += self.pending.eq(0)
        with m.If(self.start):
            m.d.sync += self.free.eq(1)
        with m.Elif(self.stop):
            m.d.sync += [self.free.eq(0), self.steps.eq(0)]
        with m.Elif(self.step):
            m.d.sync += [self.free.eq(0), self.steps.eq(self.step_count)]
        return m
