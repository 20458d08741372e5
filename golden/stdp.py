"""Pair-based spike-timing-dependent plasticity (STDP) on the cuneate layer's afferent synapses,
float64: the classic rule the brief describes beside AIDP (section 5b), golden only (the
hardware learns with AIDP).

Equations
---------
Every pair of a presynaptic spike at ``t_pre`` (afferent ``i = src[j, m]``) and a spike of the
CN ``j`` at ``t_post`` changes the synapse by (all pairs, additive, bounded)::

    dw = +A_plus  exp(-(t_post - t_pre) / tau_plus)     t_post > t_pre   (potentiation)
    dw = -A_minus exp(-(t_pre - t_post) / tau_minus)    t_pre > t_post   (depression)
    w  <- clip(w + dw, 0, w_max)

computed online with two traces: a presynaptic trace ``x_i`` (+1 at each spike of afferent
``i``, decaying with ``tau_plus``) and a postsynaptic trace ``y_j`` (+1 at each spike of CN
``j``, decaying with ``tau_minus``): at a spike of CN ``j`` every synapse of ``j`` gains
``A_plus x_i``; at a spike of afferent ``i`` every synapse it makes loses ``A_minus y_j``.

Integration scheme (the layer's tick grid ``dt``, spike times on the grid): in tick ``k`` the
afferent spikes stamped with ``k`` depress with ``y`` as fetched (the CN spikes of earlier
ticks) and a spike of the CN's update of tick ``k`` potentiates with ``x`` as fetched (the
afferent spikes of earlier ticks): a pre and a post spike of the same tick make no pair. Then
both traces take their tick's spikes and decay exactly, ``x' = (x + s) exp(-dt/tau)``, so a
pair ``n`` ticks apart counts ``exp(-n dt/tau)``. The weights change every tick (no window);
:func:`step` is one tick's change.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .validate import numbers

__all__ = ["StdpParams", "step"]


@dataclass(frozen=True)
class StdpParams:
    """Pair-based STDP: amplitudes in mV/ms a pair, time constants in ms (the classic
    asymmetric window, depression slightly dominant)."""

    a_plus: float = 0.03
    a_minus: float = 0.0315
    tau_plus_ms: float = 16.8
    tau_minus_ms: float = 33.7
    w_max: float = 6.0

    def __post_init__(self):
        numbers(self, "stdp.", positive=("tau_plus_ms", "tau_minus_ms", "w_max"),
                nonneg=("a_plus", "a_minus"))

    def to_dict(self) -> dict:
        return asdict(self)


def step(w, x_pre, y_post, pre_spiked, post_spiked, p: StdpParams):
    """One tick's weight change: ``w``, ``x_pre`` (each synapse's presynaptic trace, before this
    tick's spikes) and ``pre_spiked`` are ``(M, K)``, ``y_post`` (before this tick's CN spikes)
    and ``post_spiked`` ``(M,)``. Returns the new weights."""
    w = np.asarray(w, dtype=np.float64)
    dw = -p.a_minus * np.where(pre_spiked, y_post[:, None], 0.0)
    dw = dw + p.a_plus * np.where(post_spiked[:, None], x_pre, 0.0)
    return np.clip(w + dw, 0.0, p.w_max)
