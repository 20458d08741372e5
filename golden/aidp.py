"""Activity-intensity-dependent plasticity (AIDP): the learning rule of cuneate neurons that
learn their afferent synapses (brief section 5b), float64.

Equations
---------
Synapse ``m`` of cuneate neuron (CN) ``j`` takes afferent ``i = src[j, m]`` with weight
``w_jm`` (mV/ms, ``0 <= w <= w_max``). Its **local calcium** follows the afferent's spikes ``t_l``
after a latency ``t*``, each spike's calcium entering in proportion to the synapse's weight
(a stronger synapse admits more calcium)::

    C_jm(t) = alpha sum_l w_jm [exp(-(t - t_l - t*)/tau_d) - exp(-(t - t_l - t*)/tau_r)]
    alpha = tau_1 / (tau_d - tau_r),   tau_r = 4 ms, tau_d = 12.5 ms, tau_1 = 21 ms

(the brief writes the two exponentials the other way round, which is negative for
``tau_r < tau_d``; the kernel is the positive difference, rising with ``tau_r`` and decaying
with ``tau_d``). The CN's **main calcium** is its total synaptic drive, the net synaptic
current of the layer (:mod:`cuneate.golden.cuneate_layer`)::

    Ca_j(t) = I_j(t) = E_j(t) - g H(t)           (excitation minus the lumped inhibition)

Above the learning threshold ``theta`` the CN is in potentiation mode, below it in depression
mode: the **zero-offset main calcium** is ``Z_j = Ca_j - theta``. A synapse's **learning
drive** over a window (a presentation) is the correlation of its local calcium with it::

    L_jm = integral over the window of C_jm(t) Z_j(t) dt

At the window's end the drive is **compensated**: taken relative to the mean drive of the CN's
``K`` synapses, ``D_jm = L_jm - (1/K) sum_m' L_jm'``, so that the window's steps sum to zero
before the sigmoids (the CN's total weight is conserved up to the sigmoids and the bounds; the
synapses compete for it). Without this compensation the rule runs away: every weight of a CN
goes to the bound or to 0 together (measured on the learning protocol; docs/learning.md). The
**step** is the constant ``eta`` times the drive, scaled by a sigmoid of the synapse's weight::

    w_jm <- clip(w_jm + eta D_jm sigma(w_jm, sign D_jm), 0, w_max)
    sigma(w, +) = 1 / (1 + exp((w - w_pot) / s))      potentiation slows towards the top
    sigma(w, -) = 1 / (1 + exp(-(w - w_dep) / s))     depression slows towards 0

and the drives restart from 0. A window may end without a step (``apply = False``: the drives
are cleared, the weights kept), as the protocol's test presentations do.

Integration scheme (on the layer's tick grid ``dt``): the two calcium traces ``c_d``, ``c_r``
jump by ``w`` at the tick a delayed spike is stamped with and decay exactly between ticks,
``c' = (c + w s(k - n*)) exp(-dt/tau)`` (``n* = t*/dt`` ticks), so ``C = alpha (c_d - c_r)`` is
the kernel sampled on the grid (0 at lag 0, as the PSP of :mod:`cuneate.golden.coincidence`);
the integral is the left rectangle rule, ``L += C(k) Z(k) dt`` with both as fetched at tick
``k`` (before the tick's input enters).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .validate import numbers

__all__ = ["AidpParams", "sigmoid", "window_step"]


@dataclass(frozen=True)
class AidpParams:
    """The AIDP rule's parameters (see the module docstring); times in ms, weights and the
    threshold in mV/ms."""

    tau_rise_ms: float = 4.0
    tau_decay_ms: float = 12.5
    tau_1_ms: float = 21.0
    latency_ms: float = 1.0
    theta: float = 0.0
    eta: float = 5e-4
    w_max: float = 6.0
    w_pot: float = 4.5
    w_dep: float = 0.5
    slope: float = 0.5

    def __post_init__(self):
        numbers(self, "aidp.", positive=("tau_rise_ms", "tau_decay_ms", "tau_1_ms", "w_max",
                                         "slope"),
                nonneg=("latency_ms", "eta"), finite=("theta", "w_pot", "w_dep"))
        if not self.tau_rise_ms < self.tau_decay_ms:
            raise ValueError(f"aidp: the local calcium needs tau_rise ({self.tau_rise_ms:g} ms) "
                             f"< tau_decay ({self.tau_decay_ms:g} ms)")

    @property
    def alpha(self) -> float:
        """``tau_1 / (tau_d - tau_r)`` (21 / 8.5 = 2.47 by default)."""
        return self.tau_1_ms / (self.tau_decay_ms - self.tau_rise_ms)

    def latency_ticks(self, dt_ms: float) -> int:
        """``t* / dt`` (refused unless a whole number of ticks)."""
        n = self.latency_ms / dt_ms
        if abs(n - round(n)) > 1e-9:
            raise ValueError(f"aidp.latency_ms = {self.latency_ms:g} is not a whole number of "
                             f"ticks of {dt_ms:g} ms")
        return int(round(n))

    def to_dict(self) -> dict:
        return asdict(self) | {"alpha": self.alpha}


def sigmoid(w, positive, p: AidpParams):
    """``sigma(w, +)`` where ``positive`` else ``sigma(w, -)`` (elementwise)."""
    w = np.asarray(w, dtype=np.float64)
    pot = 1.0 / (1.0 + np.exp((w - p.w_pot) / p.slope))
    dep = 1.0 / (1.0 + np.exp(-(w - p.w_dep) / p.slope))
    return np.where(positive, pot, dep)


def window_step(w: np.ndarray, L: np.ndarray, p: AidpParams, apply: bool = True) -> np.ndarray:
    """The weights after a window's end (``w`` and the drives ``L``: ``(M, K)``, one row per
    CN); ``w`` itself when not ``apply``."""
    if not apply:
        return w
    total = np.zeros(L.shape[0])
    for m in range(L.shape[1]):                       # summed in synapse order
        total = total + L[:, m]
    D = L - (total / L.shape[1])[:, None]
    return np.clip(w + p.eta * D * sigmoid(w, D > 0, p), 0.0, p.w_max)
