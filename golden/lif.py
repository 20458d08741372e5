"""Float64 reference models of leaky integrate-and-fire (LIF) neurons, vectorized over neurons.

Two families from the design brief (section 6).

Continuous LIF (mechanoreceptor networks)
-----------------------------------------
::

    tau_m dv/dt = -(v - v_rest) + I_total,      I_total = I_ext + I_A - I_G
    if v >= v_th:  spike, v <- v_reset, v held at v_reset for t_ref

Units: ``v``, ``v_th``, ``v_reset``, ``v_rest`` in mV; every current ``I`` in mV (it is the
current times the membrane resistance, so ``v_inf = v_rest + I``); times in ms. Defaults: threshold
18 mV above a 0 mV rest (brief); ``tau_m`` 20 ms (excitatory; 10 ms for inhibitory cells); the
brief gives no reset or refractory value, so ``v_reset = 11 mV``, ``t_ref = 2 ms`` (excitatory;
1 ms inhibitory) are taken from the Brunel-Wang/Mazzoni LIF network family whose threshold,
``tau_m`` and 1 ms latency the brief quotes.

Time grid and spike convention (same as :mod:`cuneate.golden.izhikevich`): update ``k`` advances
``t = k dt`` to ``(k+1) dt`` with the input ``I[k]`` (evaluated at ``t = k dt``) held constant over
the step; the threshold is tested on the updated ``v`` (``>=``); a spike produced by update ``k`` is
reported at ``(k+1) dt``. After a spike, the next ``n_ref = ceil(t_ref / dt)`` updates leave ``v``
clamped at ``v_reset`` and cannot spike (so with ``t_ref`` a multiple of ``dt``, integration
resumes exactly ``t_ref`` after the spike).

Integration schemes (``scheme=``):

``"exact"`` (default)
    Exact exponential integration for input constant within a step:
    ``v' = v_inf + (v - v_inf) exp(-dt/tau_m)`` with ``v_inf = v_rest + I[k]``. For a constant
    suprathreshold input the inter-spike interval is then
    ``t_ref + tau_m ln((v_inf - v_reset)/(v_inf - v_th))`` rounded *up* to the grid (at most one
    ``dt`` late when ``t_ref`` is a multiple of ``dt``).
``"euler"``
    Forward Euler: ``v' = v + (dt/tau_m) (v_rest - v + I[k])``. Refused for ``dt >= 2 tau_m``,
    where it is unstable.

Synapses: difference-of-exponentials currents, see :mod:`cuneate.golden.synapses` (re-exported
here).

Force transduction: ``I(t) = k1 + k2 f(t)`` (:func:`force_to_current`).

Discrete LIF (quantized networks)
---------------------------------
::

    u[t] = alpha u[t-1] + sum_i w_i x_i[t],      alpha = exp(-dt/tau)
    if u[t] > u_th (strict):  spike s[t] = 1,  u[t] <- u_rest

Dimensionless; ``t`` counts time steps. Defaults from the brief: ``alpha = 0.389``, ``u_th = 0.65``,
``u_rest = 0``. An optional refractory period of ``r`` steps holds ``u`` at ``u_rest`` (input
ignored, no spike) for the ``r`` steps after a spike. The state before the first step is
``u[-1] = u0`` (default ``u_rest``).

Validation: every entry point raises :class:`ValueError` with a clear message on non-finite or
wrong-shaped input, non-positive time constants or steps, ``v_reset >= v_th``, unknown options.
A state that becomes non-finite raises :class:`LIFDivergenceError`; no NaN escapes silently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .validate import finite_array, number
from .izhikevich import current_schedule, group_spikes, spike_times
from .synapses import (AMPA, GABA, LATENCY_MS, NORMALIZATIONS, DiffExpSynapse, ExpTraces,
                       diff_exp_kernel, diff_exp_peak_time, synaptic_current)

__all__ = [
    "V_TH", "V_RESET", "V_REST", "TAU_M_EXC_MS", "TAU_M_INH_MS", "T_REF_EXC_MS", "T_REF_INH_MS",
    "LATENCY_MS", "LIF_SCHEMES", "NORMALIZATIONS", "STATE_BOUND",
    "DISCRETE_ALPHA", "DISCRETE_U_TH",
    "LIFDivergenceError", "DiffExpSynapse", "AMPA", "GABA",
    "diff_exp_peak_time", "diff_exp_kernel", "synaptic_current", "force_to_current",
    "lif_step", "LIFResult", "simulate_lif", "simulate_lif_network",
    "DiscreteLIFResult", "discrete_alpha", "simulate_discrete_lif",
]

V_TH = 18.0
V_RESET = 11.0
V_REST = 0.0
TAU_M_EXC_MS = 20.0
TAU_M_INH_MS = 10.0
T_REF_EXC_MS = 2.0
T_REF_INH_MS = 1.0
LIF_SCHEMES = ("exact", "euler")
STATE_BOUND = 1e6
DISCRETE_ALPHA = 0.389
DISCRETE_U_TH = 0.65

# relative slack used when turning a time into a whole number of steps (absorbs float rounding,
# e.g. 1.0 / 0.1 = 10.000000000000002)
_GRID_EPS = 1e-9


class LIFDivergenceError(FloatingPointError):
    """A LIF membrane potential became non-finite or exceeded the state bound."""

    def __init__(self, neuron: int, step: int, dt_ms: float, v: float, scheme: str,
                 bound: float):
        self.neuron, self.step, self.dt_ms, self.v, self.scheme = neuron, step, dt_ms, v, scheme
        self.t_ms = float(spike_times(step, dt_ms))       # the time of the update's spike
        super().__init__(
            f"LIF state diverged: neuron {neuron}, update {step} (t = {self.t_ms:g} ms), "
            f"dt = {dt_ms:g} ms, scheme {scheme!r}: v = {v!r} (bound |v| <= {bound:g}); check the "
            f"input current and dt")


# ----------------------------------------------------------------------------- validation helpers

def _per_neuron(x, n: int, name: str, *, positive=False, nonneg=False,
                dtype=np.float64) -> np.ndarray:
    arr = finite_array(x, name, ndim=(0, 1))
    if arr.ndim == 1 and arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} values for {n} neurons")
    arr = np.broadcast_to(arr, (n,)).astype(dtype)
    if positive and not np.all(arr > 0):
        raise ValueError(f"{name} must be > 0, got {arr[~(arr > 0)][0]!r}")
    if nonneg and not np.all(arr >= 0):
        raise ValueError(f"{name} must be >= 0, got {arr[~(arr >= 0)][0]!r}")
    return arr


def force_to_current(force, k1, k2) -> np.ndarray:
    """Force-to-current transduction ``I = k1 + k2 * f`` (element-wise, broadcasting).

    ``force`` in the sensor's force unit (e.g. N), ``k1`` in mV, ``k2`` in mV per force unit;
    ``k1``/``k2`` may be per-taxel arrays broadcastable against ``force``.
    """
    f = finite_array(force, "force")
    a = finite_array(k1, "k1")
    b = finite_array(k2, "k2")
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            out = a + b * f
    except ValueError as exc:
        raise ValueError(f"k1, k2 and force do not broadcast: {exc}") from None
    if not np.all(np.isfinite(out)):
        raise ValueError("force_to_current overflowed float64")
    return out


# ------------------------------------------------------------------------- continuous LIF

def lif_step(v, I, dt_ms: float, tau_m_ms, v_rest=V_REST, scheme: str = "exact"):
    """One membrane update *without* threshold/reset: returns ``v'`` (see module docstring)."""
    if scheme == "exact":
        v_inf = v_rest + I
        return v_inf + (v - v_inf) * np.exp(-dt_ms / tau_m_ms)
    if scheme == "euler":
        return v + (dt_ms / tau_m_ms) * (v_rest - v + I)
    raise ValueError(f"unknown LIF scheme {scheme!r}; known: {', '.join(LIF_SCHEMES)}")


@dataclass
class LIFResult:
    """Outcome of :func:`simulate_lif` / :func:`simulate_lif_network`."""

    dt_ms: float
    scheme: str
    n_steps: int
    spikes_ms: list[np.ndarray]
    spike_steps: list[np.ndarray]
    v: np.ndarray                            # final membrane potential (n_neurons,)
    v_trace: np.ndarray | None = None        # (n_steps + 1, n_neurons) when recorded
    i_exc_trace: np.ndarray | None = None    # (n_steps, n_neurons), network only
    i_inh_trace: np.ndarray | None = None    # (n_steps, n_neurons), network only

    @property
    def spike_counts(self) -> np.ndarray:
        return np.array([len(s) for s in self.spikes_ms])


def _resolve_steps(current, duration_ms, n_steps, dt_ms) -> int:
    if duration_ms is not None and n_steps is not None:
        raise ValueError("give at most one of duration_ms and n_steps")
    if n_steps is not None:
        if int(n_steps) != n_steps or n_steps < 0:
            raise ValueError(f"n_steps must be a non-negative integer, got {n_steps!r}")
        return int(n_steps)
    if duration_ms is not None:
        d = number(duration_ms, "duration_ms", nonneg=True)
        return int(round(d / dt_ms))
    if callable(current) or np.ndim(current) == 0:
        raise ValueError("a constant or callable current needs duration_ms or n_steps")
    return int(np.shape(current)[0])


def _infer_n(current, n_neurons, *arrays) -> int:
    if n_neurons is not None:
        if int(n_neurons) != n_neurons or n_neurons < 1:
            raise ValueError(f"n_neurons must be a positive integer, got {n_neurons!r}")
        return int(n_neurons)
    if not callable(current) and np.ndim(current) == 2:
        return int(np.shape(current)[1])
    for a in arrays:
        if np.ndim(a) == 1:
            return int(np.shape(a)[0])
    return 1


class _Membranes:
    """Shared LIF membrane bookkeeping (parameters, refractory counters, spike collection).
    The parameters and the state are held in ``dtype`` (float64, or float32 for the precision
    yardstick), so the whole update runs in that arithmetic."""

    def __init__(self, n, dt_ms, tau_m_ms, v_th, v_reset, v_rest, t_ref_ms, scheme, v0,
                 state_bound, dtype=np.float64):
        if scheme not in LIF_SCHEMES:
            raise ValueError(f"unknown LIF scheme {scheme!r}; known: {', '.join(LIF_SCHEMES)}")
        self.n, self.dt, self.scheme = n, dt_ms, scheme
        self.tau = _per_neuron(tau_m_ms, n, "tau_m_ms", positive=True, dtype=dtype)
        self.v_th = _per_neuron(v_th, n, "v_th", dtype=dtype)
        self.v_reset = _per_neuron(v_reset, n, "v_reset", dtype=dtype)
        self.v_rest = _per_neuron(v_rest, n, "v_rest", dtype=dtype)
        t_ref = _per_neuron(t_ref_ms, n, "t_ref_ms", nonneg=True)
        if not np.all(self.v_reset < self.v_th):
            i = int(np.flatnonzero(~(self.v_reset < self.v_th))[0])
            raise ValueError(f"v_reset must be below v_th (neuron {i}: v_reset = "
                             f"{self.v_reset[i]!r}, v_th = {self.v_th[i]!r})")
        if scheme == "euler" and not np.all(dt_ms < 2 * self.tau):
            raise ValueError(f"forward Euler is unstable for dt_ms >= 2 tau_m (dt_ms = {dt_ms!r}, "
                             f"min tau_m = {self.tau.min()!r}); use scheme='exact' or a smaller dt")
        self.n_ref = np.ceil(t_ref / dt_ms - _GRID_EPS).astype(np.int64).clip(min=0)
        self.decay = np.exp(-dt_ms / self.tau)
        self.v = self.v_rest.copy() if v0 is None else _per_neuron(v0, n, "v0", dtype=dtype)
        self.ref = np.zeros(n, dtype=np.int64)
        self.bound = state_bound
        self.hit_steps: list[np.ndarray] = []
        self.hit_neurons: list[np.ndarray] = []

    def update(self, k: int, I) -> np.ndarray:
        if self.scheme == "exact":
            v_inf = self.v_rest + I
            v_new = v_inf + (self.v - v_inf) * self.decay
        else:
            v_new = self.v + (self.dt / self.tau) * (self.v_rest - self.v + I)
        bad = ~(np.isfinite(v_new) & (np.abs(v_new) <= self.bound))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise LIFDivergenceError(i, k, self.dt, float(v_new[i]), self.scheme, self.bound)
        frozen = self.ref > 0
        v_new = np.where(frozen, self.v_reset, v_new)
        spiked = (~frozen) & (v_new >= self.v_th)
        self.ref = np.where(frozen, self.ref - 1, self.ref)
        if spiked.any():
            idx = np.flatnonzero(spiked)
            self.hit_neurons.append(idx)
            self.hit_steps.append(np.full(idx.size, k, dtype=np.int64))
            v_new = np.where(spiked, self.v_reset, v_new)
            self.ref = np.where(spiked, self.n_ref, self.ref)
        self.v = v_new
        return spiked

    def result(self, n_steps, v_tr, i_exc=None, i_inh=None) -> LIFResult:
        steps = group_spikes(self.hit_steps, self.hit_neurons, self.n)
        return LIFResult(dt_ms=self.dt, scheme=self.scheme, n_steps=n_steps,
                         spikes_ms=[spike_times(s, self.dt) for s in steps], spike_steps=steps,
                         v=self.v, v_trace=v_tr, i_exc_trace=i_exc, i_inh_trace=i_inh)


def simulate_lif(current, dt_ms: float, *, duration_ms: float | None = None,
                 n_steps: int | None = None, n_neurons: int | None = None,
                 tau_m_ms=TAU_M_EXC_MS, v_th=V_TH, v_reset=V_RESET, v_rest=V_REST,
                 t_ref_ms=T_REF_EXC_MS, scheme: str = "exact", v0=None, record: bool = True,
                 state_bound: float = STATE_BOUND, dtype=np.float64) -> LIFResult:
    """Simulate uncoupled continuous LIF neurons driven by an input current.

    Parameters
    ----------
    current
        Input current in mV (current x resistance). As in
        :func:`cuneate.golden.izhikevich.current_schedule`: a number, a per-step 1-D array of
        length ``n_steps``, a ``(n_steps, n_neurons)`` array, or a callable ``f(t_ms)`` evaluated
        at the start of each update.
    dt_ms
        Time step in ms (> 0).
    duration_ms, n_steps
        Run length (at most one); inferred from an array ``current`` when both are omitted.
    n_neurons
        Population size (inferred from a 2-D current or a per-neuron parameter array, else 1).
    tau_m_ms, v_th, v_reset, v_rest, t_ref_ms
        Scalars or per-neuron arrays (ms / mV); ``tau_m > 0``, ``t_ref >= 0``,
        ``v_reset < v_th``.
    scheme
        ``"exact"`` (default) or ``"euler"`` (see the module docstring).
    v0
        Initial potential (default ``v_rest``).
    record
        Keep the ``(n_steps + 1, n_neurons)`` membrane trace (row 0 is the initial state).
    dtype
        Arithmetic of the parameters, the current and the state: ``numpy.float64`` (default)
        or ``numpy.float32`` (the precision yardstick of :mod:`cuneate.sim.lif.sweep`).

    Raises
    ------
    ValueError
        Bad parameters or input.
    LIFDivergenceError
        If ``|v|`` becomes non-finite or exceeds ``state_bound``.
    """
    dt = number(dt_ms, "dt_ms", positive=True)
    steps = _resolve_steps(current, duration_ms, n_steps, dt)
    n = _infer_n(current, n_neurons, tau_m_ms, v_th, v_reset, v_rest, t_ref_ms, v0)
    mem = _Membranes(n, dt, tau_m_ms, v_th, v_reset, v_rest, t_ref_ms, scheme, v0, state_bound,
                     dtype)
    I_of = current_schedule(current, steps, n, dt, dtype=dtype)
    v_tr = None
    if record:
        v_tr = np.empty((steps + 1, n), dtype=dtype)
        v_tr[0] = mem.v
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(steps):
            mem.update(k, I_of(k))
            if record:
                v_tr[k + 1] = mem.v
    return mem.result(steps, v_tr)


def _weight_matrix(w, n: int, name: str) -> np.ndarray:
    arr = finite_array(w, name, ndim=(0, 2))
    arr = np.broadcast_to(arr, (n, n)).astype(np.float64) if arr.ndim == 0 else arr
    if arr.shape != (n, n):
        raise ValueError(f"{name} must have shape ({n}, {n}) [pre, post], got {arr.shape}")
    if not np.all(arr >= 0):
        raise ValueError(f"{name} must be >= 0 (the sign comes from the synapse type: AMPA adds, "
                         f"GABA subtracts)")
    return arr


def simulate_lif_network(n: int, weights_exc, weights_inh, ext_current, dt_ms: float, *,
                         duration_ms: float | None = None, n_steps: int | None = None,
                         tau_m_ms=TAU_M_EXC_MS, v_th=V_TH, v_reset=V_RESET, v_rest=V_REST,
                         t_ref_ms=T_REF_EXC_MS, ampa: DiffExpSynapse = AMPA,
                         gaba: DiffExpSynapse = GABA, scheme: str = "exact", v0=None,
                         record: bool = True, state_bound: float = STATE_BOUND) -> LIFResult:
    """Simulate ``n`` recurrently coupled LIF neurons, ``I_total = I_ext + I_A - I_G``.

    Parameters
    ----------
    n
        Number of neurons.
    weights_exc, weights_inh
        Non-negative ``(n, n)`` matrices ``W[pre, post]`` (or a scalar for all pairs). A spike of
        ``pre`` reported at ``t_s`` adds ``W[pre, post] * syn.weight * K(t - t_s - syn.latency)``
        to ``I_A`` (``ampa``) or ``I_G`` (``gaba``) of ``post``. A neuron excites or inhibits
        according to its row of non-zero entries.
    ext_current
        External current in mV, as for :func:`simulate_lif` (e.g. from :func:`force_to_current`).
    ampa, gaba
        Synapse types (time constants, latency, unit weight, normalization).
    Other parameters
        As in :func:`simulate_lif`; per-neuron arrays allow excitatory (20 ms, 2 ms refractory)
        and inhibitory (10 ms, 1 ms) cells in one network.

    Returns
    -------
    LIFResult
        With ``i_exc_trace``/``i_inh_trace`` (``I_A``/``I_G`` used by each update) when
        ``record``.

    Notes
    -----
    Synaptic currents use the exact two-trace recursion described in :class:`ExpTraces`, which
    reproduces :func:`synaptic_current` on the grid. The current for update ``k`` is the value at
    ``t = k dt``.
    """
    if int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    n = int(n)
    dt = number(dt_ms, "dt_ms", positive=True)
    We = _weight_matrix(weights_exc, n, "weights_exc")
    Wi = _weight_matrix(weights_inh, n, "weights_inh")
    for name, syn in (("ampa", ampa), ("gaba", gaba)):
        if not isinstance(syn, DiffExpSynapse):
            raise ValueError(f"{name} must be a DiffExpSynapse, got {type(syn).__name__}")
    steps = _resolve_steps(ext_current, duration_ms, n_steps, dt)
    mem = _Membranes(n, dt, tau_m_ms, v_th, v_reset, v_rest, t_ref_ms, scheme, v0, state_bound)
    I_of = current_schedule(ext_current, steps, n, dt)
    exc, inh = ExpTraces(ampa, n, dt), ExpTraces(gaba, n, dt)
    v_tr = i_e = i_g = None
    if record:
        v_tr = np.empty((steps + 1, n))
        v_tr[0] = mem.v
        i_e = np.empty((steps, n))
        i_g = np.empty((steps, n))
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(steps):
            IA, IG = exc.current(), inh.current()
            spiked = mem.update(k, I_of(k) + IA - IG)
            if record:
                v_tr[k + 1] = mem.v
                i_e[k], i_g[k] = IA, IG
            if spiked.any():
                t_s = float(spike_times(k, dt))
                for pre in np.flatnonzero(spiked):
                    if We[pre].any():
                        exc.schedule(t_s + exc.lat, We[pre])
                    if Wi[pre].any():
                        inh.schedule(t_s + inh.lat, Wi[pre])
            exc.advance(k + 1)
            inh.advance(k + 1)
    return mem.result(steps, v_tr, i_e, i_g)


# --------------------------------------------------------------------------- discrete LIF

def discrete_alpha(tau: float, dt: float) -> float:
    """Decay factor ``alpha = exp(-dt / tau)`` of the discrete LIF (same time unit for both)."""
    return math.exp(-number(dt, "dt", positive=True) / number(tau, "tau", positive=True))


@dataclass
class DiscreteLIFResult:
    """Outcome of :func:`simulate_discrete_lif`.

    ``spikes`` (n_steps, n_neurons) bool; ``u`` the state carried to the next step (after reset);
    ``u_pre`` the value compared with the threshold (before reset; ``u_rest`` while refractory).
    """

    spikes: np.ndarray
    u: np.ndarray
    u_pre: np.ndarray
    alpha: float
    u_th: float
    u_rest: float
    refractory_steps: int

    @property
    def spike_counts(self) -> np.ndarray:
        return self.spikes.sum(axis=0)


def simulate_discrete_lif(inputs, weights, alpha: float | None = None,
                          u_th: float = DISCRETE_U_TH, u_rest: float = 0.0,
                          refractory_steps: int = 0, *, tau: float | None = None,
                          dt: float | None = None, u0=None,
                          dtype=np.float64) -> DiscreteLIFResult:
    """Simulate a layer of discrete-time LIF neurons (see the module docstring).

    Parameters
    ----------
    inputs
        ``(n_steps, n_inputs)`` input spikes or real values ``x_i[t]``.
    weights
        ``(n_inputs, n_neurons)`` (or ``(n_inputs,)`` for a single neuron); any sign.
    alpha
        Membrane decay per step in ``[0, 1]``; default 0.389 unless ``tau`` and ``dt`` are given
        (then ``alpha = exp(-dt/tau)``; giving both forms is an error).
    u_th
        Threshold; a spike needs ``u > u_th`` (strict).
    u_rest
        Reset value.
    refractory_steps
        Steps after a spike during which ``u`` is held at ``u_rest`` and cannot spike.
    u0
        State before the first step (scalar or ``(n_neurons,)``; default ``u_rest``).
    dtype
        Arithmetic of the inputs, weights, decay and state: ``numpy.float64`` (default) or
        ``numpy.float32``.
    """
    x = finite_array(inputs, "inputs", ndim=(2,)).astype(dtype, copy=False)
    w = finite_array(weights, "weights", ndim=(1, 2)).astype(dtype, copy=False)
    if w.ndim == 1:
        w = w[:, None]
    if w.shape[0] != x.shape[1]:
        raise ValueError(f"weights must have shape (n_inputs={x.shape[1]}, n_neurons), got "
                         f"{w.shape}")
    if (tau is None) != (dt is None):
        raise ValueError("give both tau and dt (alpha = exp(-dt/tau)) or neither")
    if tau is not None:
        if alpha is not None:
            raise ValueError("give either alpha or (tau, dt), not both")
        a = discrete_alpha(tau, dt)
    else:
        a = DISCRETE_ALPHA if alpha is None else number(alpha, "alpha")
    if not 0.0 <= a <= 1.0:
        raise ValueError(f"alpha must lie in [0, 1] (a decay factor), got {a!r}")
    th = number(u_th, "u_th")
    rest = number(u_rest, "u_rest")
    if int(refractory_steps) != refractory_steps or refractory_steps < 0:
        raise ValueError(f"refractory_steps must be a non-negative integer, got "
                         f"{refractory_steps!r}")
    r = int(refractory_steps)
    n_steps, n = x.shape[0], w.shape[1]
    u = np.full(n, rest, dtype=dtype) if u0 is None else _per_neuron(u0, n, "u0", dtype=dtype)
    with np.errstate(over="ignore", invalid="ignore"):
        drive = x @ w
    if not np.all(np.isfinite(drive)):
        raise ValueError("input drive x @ w overflowed float64")
    spikes = np.zeros((n_steps, n), dtype=bool)
    u_tr = np.empty((n_steps, n), dtype=dtype)
    u_pre = np.empty((n_steps, n), dtype=dtype)
    ref = np.zeros(n, dtype=np.int64)
    for t in range(n_steps):
        frozen = ref > 0
        with np.errstate(over="ignore", invalid="ignore"):
            un = np.where(frozen, rest, a * u + drive[t])
        if not np.all(np.isfinite(un)):
            i = int(np.flatnonzero(~np.isfinite(un))[0])
            raise ValueError(f"discrete LIF state overflowed float64 at step {t}, neuron {i} "
                             f"(u = {un[i]!r})")
        s = (~frozen) & (un > th)
        u_pre[t] = un
        spikes[t] = s
        u = np.where(s, rest, un)
        u_tr[t] = u
        ref = np.where(frozen, ref - 1, np.where(s, r, 0))
    return DiscreteLIFResult(spikes=spikes, u=u_tr, u_pre=u_pre, alpha=a, u_th=th, u_rest=rest,
                             refractory_steps=r)
