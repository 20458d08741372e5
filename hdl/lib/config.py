"""What every block's configuration shares: the one :class:`ConfigError` and the format sizing
helpers.

A configuration (``IzhikevichConfig``, ``LifConfig``, ``CoincidenceConfig``, ``NetworkConfig``,
``LinkConfig``) derives every format and constant of its block at construction and refuses, by
raising :class:`ConfigError` with a one-line reason, whatever its formats cannot hold. Nothing is
refused later, at elaboration or while simulating.
"""

from __future__ import annotations

import math
import numbers
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Sequence

from .fixed import ROUNDINGS, FixedConstant, FixedPointError

__all__ = ["ConfigError", "refusing", "MIN_NEURONS", "CoreOptions", "MAX_BLOCK_RAM_BITS",
           "SATURATION", "TICK_SOURCES", "int_bits_for", "check_rounding", "check_tick_source",
           "whole_cycles_per_tick", "check_delays", "shared_exponent"]

#: The most block-RAM bits a block may ask for: the block RAM of the largest supported FPGA
#: (the ULX3S's ECP5-85F, 208 blocks of 18 Kibit).
MAX_BLOCK_RAM_BITS = 208 * 18 * 1024

SATURATION = ("refuse", "flag")
TICK_SOURCES = ("internal", "external")


#: The fewest neurons the engines and boards run a time-multiplexed core with: the LIF core's
#: minimum (its pipeline depth plus margin); an Izhikevich core's own is
#: :func:`~cuneate.hdl.izhikevich.config.min_neurons` (depth + 1), its deepest above this.
MIN_NEURONS = 8


class ConfigError(FixedPointError):
    """A block configuration that cannot hold; raised at construction (before elaboration),
    with a one-line reason."""


@contextmanager
def refusing(what: str, *errors):
    """Turn a :class:`~cuneate.hdl.lib.fixed.FixedPointError` (or one of ``errors``) raised
    inside into the one-line ``ConfigError("<what> refused: <reason>")``; a
    :class:`ConfigError` passes as it is."""
    try:
        yield
    except ConfigError:
        raise
    except (FixedPointError, *errors) as exc:
        raise ConfigError(f"{what} refused: {exc}") from None


@dataclass(kw_only=True)
class CoreOptions:
    """The options every time-multiplexed core takes (keywords only).

    ``saturation``: formats narrower than the proven range are refused (``"refuse"``) or
    accepted with flagged, counted clamps (``"flag"``); ``rounding``: ``"nearest"`` or
    ``"truncate"``; ``tick_source``: ``"internal"`` (a divider of ``clock_hz / update_hz``) or
    ``"external"`` (the ``tick`` input); ``spike_fifo_depth`` and ``sweep_number_width``: the
    spike stream's buffering and the width of the (wrapping) sweep number.
    """

    saturation: str = "refuse"
    rounding: str = "nearest"
    tick_source: str = "internal"
    spike_fifo_depth: int = 64
    sweep_number_width: int = 16

    def _check_options(self) -> None:
        if self.saturation not in SATURATION:
            raise ConfigError(f"saturation must be one of {SATURATION}, got "
                              f"{self.saturation!r}")
        check_rounding(self.rounding)
        check_tick_source(self.tick_source)


def check_rounding(rounding) -> None:
    """Refuses a rounding other than :data:`~cuneate.hdl.lib.fixed.ROUNDINGS`."""
    if rounding not in ROUNDINGS:
        raise ConfigError(f"unknown rounding {rounding!r}; known: {', '.join(ROUNDINGS)}")


def check_tick_source(tick_source) -> None:
    """Refuses a tick source other than :data:`TICK_SOURCES`."""
    if tick_source not in TICK_SOURCES:
        raise ConfigError("tick_source must be 'internal' or 'external'")


def whole_cycles_per_tick(clock_hz: float, update_hz: float) -> int:
    """``clock_hz / update_hz``: the cycles of one update (tick), refused unless both rates are
    positive finite numbers and their ratio a whole number (to 1e-9) of at least 1."""
    if not all(isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(x)
               and x > 0 for x in (clock_hz, update_hz)):
        raise ConfigError("clock_hz and update_hz must be positive finite numbers")
    ratio = clock_hz / update_hz
    cycles = int(round(ratio)) if math.isfinite(ratio) else 0
    if cycles < 1 or abs(ratio - cycles) > 1e-9 * ratio:
        raise ConfigError(f"clock_hz / update_hz = {clock_hz:.12g} / {update_hz:.12g} = "
                          f"{ratio:.12g} is not an integer number of cycles per update")
    return cycles


def int_bits_for(lo: float, hi: float) -> int:
    """Fewest integer bits (sign included) of a signed format holding [lo, hi] at any
    fraction width (the format's max is ``2**(ib-1) - lsb``, so ``hi`` needs strict room)."""
    ib = 1
    while not (-(2.0 ** (ib - 1)) <= lo and hi < 2.0 ** (ib - 1)):
        ib += 1
    return ib


def shared_exponent(name: str, values: Sequence[float], width: int, nominal: float = 1.0,
                    max_rel_error: float | None = None):
    """Constants sharing one exponent, normalized to the largest magnitude (so one shift serves
    every parameter set); ``nominal`` sets the exponent when every value is 0; a non-zero value
    whose relative representation error exceeds ``max_rel_error`` is refused."""
    big = max(abs(x) for x in values)
    ref = FixedConstant.normalized(name, big if big else nominal, width)
    return [FixedConstant.scaled(f"{name}[{i}]", x, ref.frac_bits, width,
                                 max_rel_error=max_rel_error if x else None)
            for i, x in enumerate(values)]


def check_delays(delays, n: int, max_ticks: int, what: str):
    """``n`` integer delays in ``0 .. max_ticks`` ticks as a list (None stays None), or a
    one-line refusal naming the delay the history cannot hold."""
    if delays is None:
        return None
    d = [int(x) for x in delays]
    if len(d) != n or any(x != y for x, y in zip(d, delays)):
        raise ConfigError(f"{what} delays: {n} integer tick counts needed (one per source)")
    bad = [x for x in d if not 0 <= x <= max_ticks]
    if bad:
        raise ConfigError(f"{what} delay of {bad[0]} ticks is outside the {what} history "
                          f"(0 .. {max_ticks} ticks)")
    return d
