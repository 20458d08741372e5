"""Float64 reference model of cuneate neurons as coincidence detectors.

Equations (design brief, section 5)::

    dv/dt = A v^2 + B v + C - u + I(t)          (Izhikevich, RS parameters by default)
    du/dt = a (b v - u)
    I(t)  = J * sum_i w_i * sum_{t_j in spikes of afferent i} PSP(t - t_j - delta_i)

    PSP(s) = (exp(-s/tau_d) - exp(-s/tau_r)) / N   for s >= 0,   0 for s < 0

with ``tau_r = 0.5 ms``, ``tau_d = 2 ms`` (AMPA-like), ``J = 8 mV/ms``, per-input conduction delays
``delta_i`` (ms) and optional weights ``w_i`` (default 1). Cuneate neurons differ only in their
delays: when the delay difference of two inputs compensates the latency between the two afferents,
their PSPs superimpose and the neuron fires.

Units: times in ms, ``v``/``u`` in mV, ``I`` in mV/ms (membrane capacitance normalized to 1), ``J``
in mV/ms, PSP dimensionless.

PSP normalization (``normalize=``, default ``"none"``): ``N = 1``, i.e. the plain difference of
exponentials, whose peak is ``exp(-t_p/tau_d) - exp(-t_p/tau_r) ~= 0.4725`` at
``t_p = tau_r tau_d/(tau_d - tau_r) ln(tau_d/tau_r) ~= 0.924 ms``. This is the literal reading of
the brief's equation and the one under which the brief's ``J = 8`` gives a coincidence detector.
Measured with RS, forward Euler, ``dt = 1/16 ms``, from the resting state (v, u) = (-70, -14): a
single PSP whose *peak* drive is below ~7.7 mV/ms does not fire the neuron. So with ``N = 1`` one
afferent spike (peak drive ``8 * 0.4725 ~= 3.8``) is far below threshold and two coincident spikes
(~7.6) sit right at it; afferent doublets (two spikes a few ms apart, as an SA/FA afferent emits
at a ridge) fire the neuron robustly only when the delays make the two afferents' PSPs overlap.
With ``normalize="peak"`` (``N`` = the raw peak, PSP peak 1, ``J`` = peak current) a *single* PSP
with ``J = 8`` already reaches that threshold, so there is no coincidence selectivity at the
brief's ``J``; ``J = 8 * 0.4725 ~= 3.78`` with that normalization reproduces the default drive
exactly. ``"area"`` (``N = tau_d - tau_r``, unit integral) is also available.

Discretization and integration: the drive is evaluated at the start of each update,
``I[k] = I(k dt)`` (the convention of :func:`cuneate.golden.izhikevich.current_schedule`), by direct
summation of the PSP kernel (exact, no recursion). :func:`simulate_cuneate` then calls
:func:`cuneate.golden.izhikevich.simulate` (forward Euler by default, ``dt = 1/16 ms``); its spike
convention applies (spike of update ``k`` reported at ``(k+1) dt``).

Validation: :class:`ValueError` on non-finite or negative delays, non-finite spike times, weights
or ``J``, shape mismatches and bad kernel constants; divergence of the neuron raises
:class:`cuneate.golden.izhikevich.DivergenceError`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from . import izhikevich
from .validate import finite_array, number
from .lif import diff_exp_kernel, diff_exp_peak_time, synaptic_current

__all__ = [
    "TAU_RISE_MS", "TAU_DECAY_MS", "J_MV_PER_MS", "PSP_NORMALIZE",
    "psp_kernel", "psp_peak_time", "psp_drive", "simulate_cuneate",
]

TAU_RISE_MS = 0.5
TAU_DECAY_MS = 2.0
J_MV_PER_MS = 8.0
#: Default PSP normalization (see the module docstring for why it is ``"none"``).
PSP_NORMALIZE = "none"


def psp_kernel(t_ms, tau_rise_ms: float = TAU_RISE_MS, tau_decay_ms: float = TAU_DECAY_MS,
               normalize: str = PSP_NORMALIZE) -> np.ndarray:
    """Bi-exponential PSP ``(exp(-t/tau_d) - exp(-t/tau_r)) / N`` for ``t >= 0``, else 0.

    ``normalize``: ``"none"`` (default, ``N = 1``), ``"peak"`` (peak 1) or ``"area"``
    (``N = tau_d - tau_r``, integral 1 ms^-1).
    """
    return diff_exp_kernel(t_ms, tau_rise_ms, tau_decay_ms, normalize)


def psp_peak_time(tau_rise_ms: float = TAU_RISE_MS, tau_decay_ms: float = TAU_DECAY_MS) -> float:
    """``tau_r tau_d / (tau_d - tau_r) ln(tau_d / tau_r)`` in ms (0.924 ms for 0.5/2 ms)."""
    return diff_exp_peak_time(tau_rise_ms, tau_decay_ms)


def _inputs(input_spike_times) -> list[np.ndarray]:
    if isinstance(input_spike_times, np.ndarray) or not isinstance(input_spike_times, Sequence):
        raise ValueError("input_spike_times must be a list with one 1-D array of spike times (ms) "
                         "per afferent")
    out = []
    for i, s in enumerate(input_spike_times):
        try:
            arr = np.asarray(s, dtype=np.float64).reshape(-1) if np.ndim(s) <= 1 else None
        except (TypeError, ValueError):
            raise ValueError(f"input_spike_times[{i}] must be numeric") from None
        if arr is None:
            raise ValueError(f"input_spike_times[{i}] must be 1-D, got shape {np.shape(s)}")
        out.append(finite_array(arr, f"input_spike_times[{i}]"))
    if not out:
        raise ValueError("input_spike_times is empty: give one spike-time array per afferent")
    return out


def _matrix(x, n_inputs: int, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != n_inputs:
        raise ValueError(f"{name} must have shape (n_cuneate, n_inputs={n_inputs}) or "
                         f"({n_inputs},), got {np.shape(x)}")
    return finite_array(arr, name)


def psp_drive(input_spike_times, delays_ms, t_grid_ms, J: float = J_MV_PER_MS, weights=None,
              tau_rise_ms: float = TAU_RISE_MS, tau_decay_ms: float = TAU_DECAY_MS,
              normalize: str = PSP_NORMALIZE) -> np.ndarray:
    """Synaptic drive ``I[k, c] = J sum_i w[c, i] sum_j PSP(t_k - t_j^i - delays[c, i])``.

    Parameters
    ----------
    input_spike_times
        List of 1-D arrays, one per afferent ``i`` (spike times in ms).
    delays_ms
        Conduction delays ``(n_cuneate, n_inputs)`` in ms (``>= 0``); a 1-D ``(n_inputs,)`` array
        means one cuneate neuron.
    t_grid_ms
        1-D evaluation times; for a simulation, the update start times ``k dt``.
    J
        Coupling in mV/ms (finite).
    weights
        Optional ``(n_cuneate, n_inputs)`` (or ``(n_inputs,)``) multipliers, default 1.

    Returns
    -------
    numpy.ndarray
        ``(n_steps, n_cuneate)`` current in mV/ms.
    """
    spikes = _inputs(input_spike_times)
    n_in = len(spikes)
    delays = _matrix(delays_ms, n_in, "delays_ms")
    if not np.all(delays >= 0):
        raise ValueError("delays_ms must be >= 0 (conduction delays cannot be negative)")
    w = np.ones_like(delays) if weights is None else _matrix(weights, n_in, "weights")
    if w.shape != delays.shape:
        raise ValueError(f"weights shape {w.shape} does not match delays shape {delays.shape}")
    Jf = number(J, "J")
    cur = synaptic_current(spikes, t_grid_ms, tau_rise_ms, tau_decay_ms, latency_ms=delays.T,
                           weight=w.T, normalize=normalize)
    return Jf * cur


def simulate_cuneate(input_spike_times, delays_ms, duration_ms: float,
                     dt_ms: float = izhikevich.DEFAULT_DT_MS, J: float = J_MV_PER_MS,
                     params="RS", scheme: str = "euler", *, weights=None,
                     tau_rise_ms: float = TAU_RISE_MS, tau_decay_ms: float = TAU_DECAY_MS,
                     normalize: str = PSP_NORMALIZE, v0=None, u0=None,
                     record: bool = False) -> izhikevich.IzhikevichResult:
    """Simulate ``n_cuneate`` Izhikevich neurons driven by delayed afferent PSPs.

    Builds ``I = psp_drive(..., t_grid = k dt for k < n_steps)`` with
    ``n_steps = round(duration_ms / dt_ms)`` and returns
    ``izhikevich.simulate(params, I, n_steps=n_steps, n_neurons=n_cuneate, dt_ms=dt_ms,
    scheme=scheme, ...)``. ``params`` may be a preset or a list of per-neuron sets.
    """
    dt = number(dt_ms, "dt_ms", positive=True)
    dur = number(duration_ms, "duration_ms", nonneg=True)
    n_steps = int(round(dur / dt))
    t_grid = np.arange(n_steps) * dt
    drive = psp_drive(input_spike_times, delays_ms, t_grid, J=J, weights=weights,
                      tau_rise_ms=tau_rise_ms, tau_decay_ms=tau_decay_ms, normalize=normalize)
    n_cn = drive.shape[1]
    return izhikevich.simulate(params, drive, n_steps=n_steps, n_neurons=n_cn, dt_ms=dt,
                               scheme=scheme, v0=v0, u0=u0, record=record)
