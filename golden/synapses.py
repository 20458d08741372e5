"""Float64 difference-of-exponentials synapses (current based), shared by the LIF and cuneate
golden models.

Synapses: difference of exponentials (current based, no conductance)::

    I_syn(t) = w * sum_j K(t - t_j - L),     K(s) = (exp(-s/tau_d) - exp(-s/tau_r)) / N  (s >= 0)
                                              K(s) = 0                                  (s < 0)

with presynaptic spike times ``t_j``, latency ``L`` (1 ms in the brief) and normalization ``N``:
``"peak"`` (default: ``max K = 1`` so ``w`` is the peak current in mV; ``N = K_raw(t_peak)``),
``"area"`` (``N = tau_d - tau_r``: ``K`` integrates to 1 ms^-1, so ``w`` is a charge in mV ms) or
``"none"`` (``N = 1``). The peak is at ``t_peak = tau_r tau_d/(tau_d - tau_r) ln(tau_d/tau_r)``.
:func:`synaptic_current` evaluates the sum directly (exact at any time); the network simulator
:func:`simulate_lif_network` uses two exactly-decaying exponential traces per synapse type, which
gives the same values on the grid. Default time constants (the brief gives none): AMPA rise 0.4 ms,
decay 2 ms; GABA rise 0.25 ms, decay 5 ms.

Validation: every entry point raises :class:`ValueError` with a clear message on non-finite or
wrong-shaped input, non-positive or unordered time constants, unknown options.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .validate import finite_array, number

__all__ = ["LATENCY_MS", "NORMALIZATIONS", "DiffExpSynapse", "AMPA", "GABA",
           "diff_exp_peak_time", "diff_exp_kernel", "synaptic_current", "check_taus",
           "norm_factor", "ExpTraces"]

LATENCY_MS = 1.0
NORMALIZATIONS = ("peak", "area", "none")
# relative slack used when turning a time into a whole number of steps
_GRID_EPS = 1e-9
# cap on the number of float64 temporaries of one kernel evaluation block
_BLOCK_ELEMS = 1 << 22


def check_taus(tau_rise_ms, tau_decay_ms) -> tuple[float, float]:
    """The time constants as floats, or ``ValueError`` unless ``0 < tau_rise < tau_decay``."""
    tr = number(tau_rise_ms, "tau_rise_ms", positive=True)
    td = number(tau_decay_ms, "tau_decay_ms", positive=True)
    if not tr < td:
        raise ValueError(f"a difference of exponentials needs 0 < tau_rise_ms < tau_decay_ms, got "
                         f"tau_rise_ms={tr!r}, tau_decay_ms={td!r}")
    return tr, td


def _check_normalize(normalize: str) -> str:
    if normalize not in NORMALIZATIONS:
        raise ValueError(f"normalize must be one of {', '.join(map(repr, NORMALIZATIONS))}, got "
                         f"{normalize!r}")
    return normalize


# ----------------------------------------------------------------------------------- synapses

def diff_exp_peak_time(tau_rise_ms: float, tau_decay_ms: float) -> float:
    """Time (ms) of the maximum of ``exp(-t/tau_d) - exp(-t/tau_r)``:
    ``tau_r tau_d / (tau_d - tau_r) * ln(tau_d / tau_r)``."""
    tr, td = check_taus(tau_rise_ms, tau_decay_ms)
    return tr * td / (td - tr) * math.log(td / tr)


def norm_factor(tr: float, td: float, normalize: str) -> float:
    """The divisor that normalizes the difference of exponentials to a peak of 1
    (``"peak"``), an area of ``tau_d - tau_r`` (``"area"``) or not at all (``"none"``)."""
    if normalize == "none":
        return 1.0
    if normalize == "area":
        return td - tr
    tp = tr * td / (td - tr) * math.log(td / tr)
    return math.exp(-tp / td) - math.exp(-tp / tr)


def _kernel_unchecked(s: np.ndarray, tr: float, td: float, norm: float) -> np.ndarray:
    pos = s >= 0
    sp = np.where(pos, s, 0.0)
    return np.where(pos, (np.exp(-sp / td) - np.exp(-sp / tr)) / norm, 0.0)


def diff_exp_kernel(t_ms, tau_rise_ms: float, tau_decay_ms: float,
                    normalize: str = "peak") -> np.ndarray:
    """Difference-of-exponentials kernel ``K(t)`` (0 for ``t < 0``), see the module docstring.

    Parameters
    ----------
    t_ms
        Times in ms (any shape, finite).
    tau_rise_ms, tau_decay_ms
        Time constants in ms, ``0 < tau_rise < tau_decay``.
    normalize
        ``"peak"`` (max 1), ``"area"`` (integral 1 ms^-1) or ``"none"``.
    """
    tr, td = check_taus(tau_rise_ms, tau_decay_ms)
    t = finite_array(t_ms, "t_ms")
    return _kernel_unchecked(t, tr, td, norm_factor(tr, td, _check_normalize(normalize)))


def _spike_lists(spike_times_ms, name: str) -> tuple[list[np.ndarray], bool]:
    """Return (list of 1-D spike-time arrays, was_single)."""
    if isinstance(spike_times_ms, np.ndarray) or np.isscalar(spike_times_ms):
        arr = finite_array(spike_times_ms, name, ndim=(0, 1))
        return [np.atleast_1d(arr)], True
    seq = list(spike_times_ms)
    if all(np.isscalar(x) for x in seq):
        return [finite_array(seq, name, ndim=(1,))], True
    return [finite_array(s, f"{name}[{i}]", ndim=(0, 1)).reshape(-1)
            for i, s in enumerate(seq)], False


def _pair_array(x, n_pre: int, n_post: int | None, name: str, *, nonneg=False):
    arr = finite_array(x, name, ndim=(0, 1, 2))
    if arr.ndim == 1 and arr.shape[0] != n_pre:
        raise ValueError(f"{name} has {arr.shape[0]} values for {n_pre} presynaptic sources")
    if arr.ndim == 2:
        if arr.shape[0] != n_pre or (n_post is not None and arr.shape[1] != n_post):
            raise ValueError(f"{name} must have shape ({n_pre}, n_post), got {arr.shape}")
    if nonneg and not np.all(arr >= 0):
        raise ValueError(f"{name} must be >= 0 (conduction latencies and delays cannot be "
                         f"negative)")
    return arr


def synaptic_current(spike_times_ms, t_grid_ms, tau_rise_ms: float, tau_decay_ms: float,
                     latency_ms=LATENCY_MS, weight=1.0, normalize: str = "peak") -> np.ndarray:
    """Difference-of-exponentials synaptic current on a time grid, by direct summation.

    ``I(t) = sum_pre w[pre, post] sum_j K(t - t_j^pre - L[pre, post])``.

    Parameters
    ----------
    spike_times_ms
        Either one 1-D array of presynaptic spike times (ms) or a list of such arrays (one per
        presynaptic source).
    t_grid_ms
        1-D array of evaluation times (ms); need not be uniform.
    tau_rise_ms, tau_decay_ms
        Kernel time constants (ms), ``0 < tau_rise < tau_decay``.
    latency_ms
        Latency ``L`` >= 0: scalar, per source ``(n_pre,)``, or per pair ``(n_pre, n_post)``.
    weight
        ``w``: scalar, per source ``(n_pre,)`` or per pair ``(n_pre, n_post)``. Its sign is kept.
    normalize
        Kernel normalization, see :func:`diff_exp_kernel`.

    Returns
    -------
    numpy.ndarray
        ``(n_t,)`` when neither ``latency_ms`` nor ``weight`` is 2-D (sum over sources), else
        ``(n_t, n_post)``.
    """
    tr, td = check_taus(tau_rise_ms, tau_decay_ms)
    norm = norm_factor(tr, td, _check_normalize(normalize))
    spikes, _ = _spike_lists(spike_times_ms, "spike_times_ms")
    t = finite_array(t_grid_ms, "t_grid_ms", ndim=(1,))
    n_pre = len(spikes)
    lat = _pair_array(latency_ms, n_pre, None, "latency_ms", nonneg=True)
    w = _pair_array(weight, n_pre, lat.shape[1] if lat.ndim == 2 else None, "weight")
    two_d = lat.ndim == 2 or w.ndim == 2
    n_post = lat.shape[1] if lat.ndim == 2 else (w.shape[1] if w.ndim == 2 else 1)
    lat2 = np.broadcast_to(lat.reshape(lat.shape + (1,) * (2 - lat.ndim)) if lat.ndim == 1
                           else lat, (n_pre, n_post))
    w2 = np.broadcast_to(w.reshape(w.shape + (1,) * (2 - w.ndim)) if w.ndim == 1 else w,
                         (n_pre, n_post))
    out = np.zeros((t.shape[0], n_post))
    for i, s in enumerate(spikes):
        if s.size == 0 or not np.any(w2[i]):
            continue
        chunk = max(1, _BLOCK_ELEMS // max(1, t.shape[0] * n_post))
        acc = np.zeros((t.shape[0], n_post))
        for j0 in range(0, s.size, chunk):
            sj = s[j0:j0 + chunk]
            rel = t[:, None, None] - lat2[i][None, :, None] - sj[None, None, :]
            acc += _kernel_unchecked(rel, tr, td, norm).sum(axis=2)
        out += acc * w2[i][None, :]
    if not np.all(np.isfinite(out)):
        raise ValueError("synaptic current overflowed float64; check the weights")
    return out if two_d else out[:, 0]


@dataclass(frozen=True)
class DiffExpSynapse:
    """A current-based difference-of-exponentials synapse (see the module docstring).

    Attributes
    ----------
    tau_rise_ms, tau_decay_ms
        Time constants in ms, ``0 < tau_rise < tau_decay``.
    weight
        Peak current in mV for ``normalize="peak"`` (sign kept; in a network, excitatory and
        inhibitory synapses take positive weights and GABA is subtracted).
    latency_ms
        Delay between a presynaptic spike and the start of the response, ms (>= 0).
    normalize
        ``"peak"``, ``"area"`` or ``"none"``.
    """

    tau_rise_ms: float
    tau_decay_ms: float
    weight: float = 1.0
    latency_ms: float = LATENCY_MS
    normalize: str = "peak"

    def __post_init__(self):
        check_taus(self.tau_rise_ms, self.tau_decay_ms)
        number(self.weight, "weight")
        number(self.latency_ms, "latency_ms", nonneg=True)
        _check_normalize(self.normalize)

    @property
    def peak_time_ms(self) -> float:
        """Time from spike arrival (after the latency) to the peak of the response."""
        return diff_exp_peak_time(self.tau_rise_ms, self.tau_decay_ms)

    def kernel(self, t_ms) -> np.ndarray:
        """``weight * K(t - latency)`` for a single presynaptic spike at ``t = 0``."""
        return self.weight * diff_exp_kernel(np.asarray(t_ms, dtype=np.float64) - self.latency_ms,
                                             self.tau_rise_ms, self.tau_decay_ms, self.normalize)

    def current(self, spike_times_ms, t_grid_ms) -> np.ndarray:
        """Current trace on ``t_grid_ms`` from one array (or list of arrays) of spike times."""
        return synaptic_current(spike_times_ms, t_grid_ms, self.tau_rise_ms, self.tau_decay_ms,
                                self.latency_ms, self.weight, self.normalize)


#: AMPA-like excitatory synapse (rise 0.4 ms, decay 2 ms, latency 1 ms, unit peak).
AMPA = DiffExpSynapse(0.4, 2.0, 1.0, LATENCY_MS)
#: GABA-like inhibitory synapse (rise 0.25 ms, decay 5 ms, latency 1 ms, unit peak).
GABA = DiffExpSynapse(0.25, 5.0, 1.0, LATENCY_MS)


class ExpTraces:
    """Exact grid implementation of a difference-of-exponentials synapse population.

    A spike arriving at ``t_a`` (between grid points) is added to the two traces at the first grid
    time ``t_m >= t_a`` as ``w exp(-(t_m - t_a)/tau)``; the traces then decay exactly by
    ``exp(-dt/tau)`` per step, so ``c (x_d - x_r)`` equals the directly summed kernel on the grid.
    """

    def __init__(self, syn: DiffExpSynapse, n: int, dt: float):
        self.tr, self.td, self.lat = syn.tau_rise_ms, syn.tau_decay_ms, syn.latency_ms
        self.c = syn.weight / norm_factor(self.tr, self.td, syn.normalize)
        self.dt = dt
        self.dec_d, self.dec_r = math.exp(-dt / self.td), math.exp(-dt / self.tr)
        self.xd = np.zeros(n)
        self.xr = np.zeros(n)
        self.pending: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def current(self) -> np.ndarray:
        return self.c * (self.xd - self.xr)

    def schedule(self, t_arrival: float, w_post: np.ndarray) -> None:
        m = int(math.ceil(t_arrival / self.dt - _GRID_EPS))
        off = max(0.0, m * self.dt - t_arrival)
        add_d = w_post * math.exp(-off / self.td)
        add_r = w_post * math.exp(-off / self.tr)
        if m in self.pending:
            pd, pr = self.pending[m]
            self.pending[m] = (pd + add_d, pr + add_r)
        else:
            self.pending[m] = (add_d, add_r)

    def advance(self, m: int) -> None:
        """Move the traces from grid index ``m - 1`` to ``m``."""
        self.xd *= self.dec_d
        self.xr *= self.dec_r
        p = self.pending.pop(m, None)
        if p is not None:
            self.xd += p[0]
            self.xr += p[1]
