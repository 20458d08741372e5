"""The coincidence detector's own stage functions, written once for the twin and the RTL: the
delayed input sum (:func:`accumulate`, one input per cycle, each read from the history slot
:func:`history_slot` names) and the PSP current with the trace
inputs (:func:`psp_current`, update cycle 1). The traces are the shared ones of
:mod:`cuneate.hdl.lib.synapses`, the targets' update the Izhikevich datapath's; the schedule
and the formats are in :mod:`cuneate.hdl.coincidence.core` and
:class:`~cuneate.hdl.coincidence.config.CoincidenceConfig`.
"""

from __future__ import annotations

from amaranth import Cat

from ..lib.fixed import narrow, round_shift, select
from .config import CLAMP_KINDS, CoincidenceConfig

__all__ = ["history_slot", "accumulate", "psp_current", "clamp_bits_hdl"]


def history_slot(slot, delay, depth: int):
    """The ring slot holding the spikes stamped ``delay`` ticks before the tick stamped into
    ``slot`` (``0 <= slot, delay < depth``): ``(slot - delay) mod depth``."""
    diff = slot - delay
    return select(diff < 0, diff + depth, diff)


def accumulate(acc, bit, w):
    """One input of the sum: ``acc + (w if bit else 0)``."""
    return acc + select(bit, w, 0)


def psp_current(cfg: CoincidenceConfig, xd, xr, a):
    """Update cycle 1: the PSP current ``x_d - x_r`` (traces as fetched) rounded to the
    Izhikevich current format, and ``y = x + a`` for both traces."""
    i = narrow(round_shift(xd - xr, cfg.i_shift, cfg.rounding), cfg.iz.I, cfg.i_raw_bounds,
               "PSP current")
    ys = [xd + (a << cfg.wshift), xr + (a << cfg.wshift)]
    return i, ys


def clamp_bits_hdl(flags: dict):
    """Pack per-update clamp flags into the bit order of :data:`CLAMP_KINDS` (RTL)."""
    return Cat(*[flags[k] for k in CLAMP_KINDS])
