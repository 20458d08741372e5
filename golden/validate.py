"""Shared input validation of the golden models (private).

Every check raises :class:`ValueError` whose message starts with the argument's name.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

__all__ = ["number", "numbers", "finite_array"]


def number(value, name: str, *, positive: bool = False, nonneg: bool = False) -> float:
    """``value`` as a finite float; optionally ``> 0`` (``positive``) or ``>= 0`` (``nonneg``)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if positive and not v > 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if nonneg and not v >= 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return v


def numbers(obj, prefix: str = "", *, positive=(), nonneg=(), finite=()) -> None:
    """:func:`number` on the attributes of ``obj`` named in ``positive`` (``> 0``), then
    ``nonneg`` (``>= 0``), then ``finite``; an error names the attribute after ``prefix``."""
    for names, kw in ((positive, {"positive": True}), (nonneg, {"nonneg": True}), (finite, {})):
        for k in names:
            number(getattr(obj, k), prefix + k, **kw)


def _at_index(idx: tuple[int, ...]) -> str:
    return f"index {idx if len(idx) != 1 else idx[0]}"


def finite_array(x, name: str, *, ndim: int | tuple[int, ...] | None = None,
                 nonempty: bool = False, shapes: str | None = None,
                 where: Callable[[tuple[int, ...]], str] | None = None) -> np.ndarray:
    """``x`` as a float64 array whose every value is finite.

    Parameters
    ----------
    ndim
        Allowed number(s) of dimensions (``None``: any).
    nonempty
        Require at least one sample along axis 0.
    shapes
        Wording of the allowed shapes for the ``ndim`` error, e.g. ``"(n_steps,) or
        (n_steps, n_channels)"`` (default: the allowed dimensionalities, ``"1-D or 2-D"``).
    where
        Maps the index tuple of the first non-finite value to its description in the error
        message (default ``"index i"``, or ``"index (i, j, ...)"`` for more than one dimension).
    """
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric array-like: {exc}") from None
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if arr.ndim not in allowed:
            if shapes is None:
                raise ValueError(f"{name} must be {' or '.join(f'{d}-D' for d in allowed)}, got "
                                 f"shape {arr.shape}")
            raise ValueError(f"{name} must have shape {shapes}, got {arr.ndim}-D shape "
                             f"{arr.shape}")
    if nonempty and arr.ndim > 0 and arr.shape[0] == 0:
        raise ValueError(f"{name} is empty (needs at least one sample)")
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name} contains a non-finite value ({arr[idx]!r}) at "
                         f"{(where or _at_index)(idx)}")
    return arr
