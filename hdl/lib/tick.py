"""The tick every time-multiplexed block starts its sweeps on."""

from __future__ import annotations

from amaranth import Module, Mux, Signal

__all__ = ["tick_strobe"]


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
