"""The tick every time-multiplexed block starts its sweeps on."""

from __future__ import annotations

from amaranth import Module, Mux, Signal

__all__ = ["tick_strobe"]


def tick_strobe(m: Module, cfg, tick_in=None) -> Signal:
    """A one-cycle strobe that starts a sweep.

    With ``cfg.tick_source == "internal"`` it comes from a divider of ``cfg.cycles_per_tick``
    cycles (first strobe in cycle 0); with ``"external"`` it is ``tick_in``, the block's
    ``tick`` input."""
    tick = Signal()
    if cfg.tick_source == "internal":
        div = Signal(range(cfg.cycles_per_tick))
        m.d.comb += tick.eq(div == 0)
        m.d.sync += div.eq(Mux(div == cfg.cycles_per_tick - 1, 0, div + 1))
    else:
        m.d.comb += tick.eq(tick_in)
    return tick
