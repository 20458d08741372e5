"""The channel fan-out's stage functions, written once for the twin (NumPy int64 arrays) and the
RTL (Amaranth values): the rectified, gated sample (:func:`rectify_gate`, stage 3), the product
with the gain (:func:`product`, stage 4) and the rounded, flagged current (:func:`to_current`,
stage 5). Formats and the schedule: :class:`~cuneate.hdl.fanout.config.FanoutConfig` and
:mod:`cuneate.hdl.fanout.core`.
"""

from __future__ import annotations

from ..lib.fixed import product as fixed_product
from ..lib.fixed import round_clamp_flagged, select
from .config import FanoutConfig

__all__ = ["rectify_gate", "product", "to_current"]

#: mode codes of the table (the index in :data:`~cuneate.golden.fanout.RECTIFY`)
NONE, POSITIVE, ABS = 0, 1, 2


def rectify_gate(s, mode, gated, theta):
    """The sample as the afferent takes it: ``s`` (mode 0), ``max(s, 0)`` (mode 1) or ``|s|``
    (mode 2), and 0 where the afferent is ``gated`` and ``s < theta`` (raw samples)."""
    neg = s < 0
    r = select(mode == POSITIVE, select(neg, 0, s), select(mode == ABS, select(neg, -s, s), s))
    return select(gated & (s < theta), 0, r)


def product(r, g):
    """The rectified sample times the gain, at full width."""
    return fixed_product(r, g, "fanout product")


def to_current(cfg: FanoutConfig, p):
    """The product rounded to the current format and clamped into it: ``(current, below,
    above)``; the flags say when the clamp acted (no clamp is built where the proven range of
    the rounded product fits the format). Exact at every gain: where the shared exponent adds
    bits (a negative ``shift``) the clamp compares the product itself
    (:func:`~cuneate.hdl.lib.fixed.round_clamp_flagged`)."""
    return round_clamp_flagged(p, cfg.shift, cfg.rounding, cfg.I.min_raw, cfg.I.max_raw, cfg.I,
                               cfg.i_bounds)
