"""Float64 reference encoders: tactile sensor signals -> mechanoreceptor input currents.

Two afferent classes of the MEMS-fingertip works (design brief, section 4) are modelled as the
*current* that drives an Izhikevich RS neuron (:mod:`cuneate.golden.izhikevich`); this module only
computes that current, it does not integrate any neuron.

Equations
---------
Opponent signal (two sensor channels pulling in opposite directions)::

    S(t) = ch_a(t) - ch_b(t)

SA (slowly adapting, Merkel-like) current, proportional to the sustained signal::

    I_SA(t) = (K / R) * S(t)    if S(t) >= S_th
            = 0                 otherwise

FA (fast adapting, Meissner-like) current, proportional to the rate of change of the SA-style
current (the brief's ``dv/dt = ... + (tau/Cm) dI/dt`` term)::

    I_FA(t) = (tau / Cm) * d/dt [ G * S(t) ]        then optionally rectified

Units
-----
``S`` is in sensor units (dimensionless after any sensor calibration). ``K`` (gain, 10 000 to
15 000 in the publications) and ``R`` (ohm, 1 in the publications) turn it into a current in the
Izhikevich model's units, mV/ms (membrane capacitance normalized to ``Cm = 1``). For FA, ``dt_ms``
and ``tau_ms`` are in ms, so ``(tau/Cm) dI/dt`` is again in mV/ms.

Discretization
--------------
Signals are sampled on a uniform grid ``t_k = k dt`` (shape ``(n_steps,)`` or
``(n_steps, n_channels)``; axis 0 is time). The SA current is evaluated sample by sample (no
integration). The FA derivative uses the **backward difference**
``dI/dt[k] = (I[k] - I[k-1]) / dt`` for ``k >= 1`` and ``dI/dt[0] = 0`` (no history before the
first sample), so the FA current at sample ``k`` depends only on samples ``<= k`` (causal), which is
what an online encoder can compute. The brief's MEMS works simulate at ``dt = 50 us = 0.05 ms``.

Validation
----------
Every function raises :class:`ValueError` on non-finite samples (naming the first bad sample),
wrong dimensionality, shape mismatches, non-positive ``R``, ``dt``, ``tau`` or ``Cm``, and unknown
options; no NaN or inf is ever produced from finite input.
"""

from __future__ import annotations

import numpy as np

from .validate import finite_array, number

__all__ = [
    "DEFAULT_GAIN_K", "DEFAULT_R_OHM", "DEFAULT_CM", "DEFAULT_FA_TAU_MS", "RECTIFY_MODES",
    "opponent_difference", "sa_current", "fa_current",
]

#: Default SA gain K (the publications used 10 000 to 15 000).
DEFAULT_GAIN_K = 12500.0
#: Default resistance R in ohm (the publications used 1).
DEFAULT_R_OHM = 1.0
#: Normalized membrane capacitance.
DEFAULT_CM = 1.0
#: Default FA time constant in ms. The brief gives no value; 1 ms is a neutral choice that makes
#: ``I_FA`` numerically equal to ``G * dS/dt`` with ``dS/dt`` expressed per ms.
DEFAULT_FA_TAU_MS = 1.0
RECTIFY_MODES = ("abs", "positive", None)


def _sample_channel(idx: tuple[int, ...]) -> str:
    return f"sample {idx[0]}" + (f", channel {idx[1]}" if len(idx) == 2 else "")


def _signal(x, name: str = "signal") -> np.ndarray:
    """Validate a sampled signal: float64, 1-D or 2-D (time on axis 0), non-empty, finite."""
    return finite_array(x, name, ndim=(1, 2), nonempty=True,
                        shapes="(n_steps,) or (n_steps, n_channels)", where=_sample_channel)


def _check_out(out: np.ndarray, what: str) -> None:
    bad = ~np.isfinite(out)
    if bad.any():
        k = int(np.argwhere(bad)[0][0])
        raise ValueError(f"{what} overflowed float64 at sample {k}; the inputs or gains are too "
                         f"large")


def opponent_difference(ch_a, ch_b) -> np.ndarray:
    """Opponent signal ``S = ch_a - ch_b`` of two sensor channels.

    Parameters
    ----------
    ch_a, ch_b
        Sampled channels of identical shape ``(n_steps,)`` or ``(n_steps, n_channels)``.

    Returns
    -------
    numpy.ndarray
        ``ch_a - ch_b`` (float64, same shape).
    """
    a = _signal(ch_a, "ch_a")
    b = _signal(ch_b, "ch_b")
    if a.shape != b.shape:
        raise ValueError(f"opponent channels must have the same shape, got {a.shape} and "
                         f"{b.shape}")
    with np.errstate(over="ignore", invalid="ignore"):
        out = a - b
    _check_out(out, "opponent difference")
    return out


def sa_current(signal, gain_K: float = DEFAULT_GAIN_K, R_ohm: float = DEFAULT_R_OHM,
               threshold: float = 0.0) -> np.ndarray:
    """Slowly-adapting (SA) afferent input current.

    ``I = (K / R) * S`` where ``S >= threshold``, else ``0`` (element-wise, per sample and
    channel).

    Parameters
    ----------
    signal
        Opponent signal ``S`` (see :func:`opponent_difference`), shape ``(n_steps,)`` or
        ``(n_steps, n_channels)``.
    gain_K
        Gain ``K`` (finite; 10 000 to 15 000 in the publications).
    R_ohm
        Resistance ``R`` in ohm (> 0).
    threshold
        ``S_th``; samples with ``S < S_th`` give zero current (the comparison is ``>=``).

    Returns
    -------
    numpy.ndarray
        Current in mV/ms, same shape as ``signal``.
    """
    s = _signal(signal)
    K = number(gain_K, "gain_K")
    R = number(R_ohm, "R_ohm", positive=True)
    th = number(threshold, "threshold")
    with np.errstate(over="ignore", invalid="ignore"):
        out = np.where(s >= th, (K / R) * s, 0.0)
    _check_out(out, "SA current")
    return out


def fa_current(signal, dt_ms: float, gain: float = DEFAULT_GAIN_K / DEFAULT_R_OHM,
               tau_ms: float = DEFAULT_FA_TAU_MS, Cm: float = DEFAULT_CM,
               rectify: str | None = None) -> np.ndarray:
    """Fast-adapting (FA) afferent input current from the time derivative of the signal.

    ``I_FA[k] = (tau / Cm) * G * (S[k] - S[k-1]) / dt`` for ``k >= 1`` and ``I_FA[0] = 0``
    (backward difference, causal), then optional rectification.

    Parameters
    ----------
    signal
        Opponent signal ``S``, shape ``(n_steps,)`` or ``(n_steps, n_channels)``, sampled at
        ``dt_ms``.
    dt_ms
        Sampling interval in ms (> 0).
    gain
        ``G`` = ``K / R``, the SA-style gain turning ``S`` into a current (finite).
    tau_ms
        Time constant ``tau`` in ms (> 0).
    Cm
        Normalized membrane capacitance (> 0).
    rectify
        ``None`` keeps the signed derivative (negative at release); ``"positive"`` keeps only
        increases (``max(I, 0)``); ``"abs"`` responds to both onset and offset (``|I|``), like a
        Meissner afferent.

    Returns
    -------
    numpy.ndarray
        Current in mV/ms, same shape as ``signal``.
    """
    s = _signal(signal)
    dt = number(dt_ms, "dt_ms", positive=True)
    G = number(gain, "gain")
    tau = number(tau_ms, "tau_ms", positive=True)
    cm = number(Cm, "Cm", positive=True)
    if rectify not in RECTIFY_MODES:
        raise ValueError(f"rectify must be one of 'abs', 'positive' or None, got {rectify!r}")
    deriv = np.zeros_like(s)
    with np.errstate(over="ignore", invalid="ignore"):
        deriv[1:] = (s[1:] - s[:-1]) / dt
        out = (tau / cm) * G * deriv
    _check_out(out, "FA current")
    if rectify == "abs":
        out = np.abs(out)
    elif rectify == "positive":
        out = np.maximum(out, 0.0)
    return out
