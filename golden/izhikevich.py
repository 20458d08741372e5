"""Float reference model of the Izhikevich neuron, vectorized over neurons.

Equations (Izhikevich 2003)::

    dv/dt = A v^2 + B v + C - u + I      A = 0.04 /(ms mV), B = 5 /ms, C = 140 mV/ms
    du/dt = a (b v - u)
    if v >= v_th (30 mV):  v <- c,  u <- u + d

Project conventions (shared by every engine, golden, fixed-point twin and RTL):

* One *update* ``k`` (k = 0, 1, 2, ...) advances the state from ``t = k dt`` to ``t = (k+1) dt``
  using the input current ``I[k]`` held constant over the step.
* The threshold is tested on the state produced by the update. A spike produced by update ``k``
  is reported at ``t = (k+1) dt`` ms; on a spike ``v <- c`` and ``u <- u_new + d``.
* Initial state ``v0 = -65 mV`` and ``u0 = b v0`` unless given.

Integration schemes (``scheme=``):

``"euler"`` (default)
    Standard forward Euler: ``v`` and ``u`` are both advanced from the *same old* state,
    ``v' = v + dt f(v, u, I)``, ``u' = u + dt a (b v - u)``. This is what the FPGA core computes.
``"izhikevich"``
    The variant of Izhikevich's published code: ``v`` takes two half steps of ``dt/2`` (the second
    from the first's result) and ``u`` is then advanced by ``dt`` from the *new* ``v``:
    ``u' = u + dt a (b v' - u)``.
``"rk4"``
    Classical fourth-order Runge-Kutta on ``(v, u)`` over the whole step (reference only).

Divergence is never returned silently: if any updated state is non-finite or its magnitude
exceeds ``state_bound`` (default 1e4 mV), :class:`DivergenceError` is raised naming the neuron,
the update index and ``dt``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

__all__ = [
    "A", "B", "C", "V_TH", "V0", "SCHEMES", "DEFAULT_DT_MS", "STATE_BOUND",
    "IzhikevichParams", "PRESETS", "DivergenceError", "IzhikevichResult",
    "resolve_params", "derivatives", "step", "simulate", "current_schedule", "group_spikes",
]

A = 0.04
B = 5.0
C = 140.0
V_TH = 30.0
V0 = -65.0
DEFAULT_DT_MS = 1.0 / 16.0
STATE_BOUND = 1e4
SCHEMES = ("euler", "izhikevich", "rk4")


@dataclass(frozen=True)
class IzhikevichParams:
    """One Izhikevich parameter set (a, b dimensionless rates; c, d in mV)."""

    a: float
    b: float
    c: float
    d: float

    def as_tuple(self) -> tuple[float, float, float, float]:
        return (self.a, self.b, self.c, self.d)


#: Classic parameter sets (Izhikevich 2003/2004).
PRESETS: Mapping[str, IzhikevichParams] = {
    "RS": IzhikevichParams(0.02, 0.2, -65.0, 8.0),   # regular spiking
    "IB": IzhikevichParams(0.02, 0.2, -55.0, 4.0),   # intrinsically bursting
    "CH": IzhikevichParams(0.02, 0.2, -50.0, 2.0),   # chattering
    "FS": IzhikevichParams(0.1, 0.2, -65.0, 2.0),    # fast spiking
    "LTS": IzhikevichParams(0.02, 0.25, -65.0, 2.0),  # low-threshold spiking
    "RZ": IzhikevichParams(0.1, 0.26, -65.0, 2.0),   # resonator
}


class DivergenceError(FloatingPointError):
    """The integration left the representable/physical range (non-finite or beyond the bound)."""

    def __init__(self, neuron: int, step: int, dt_ms: float, v: float, u: float, scheme: str,
                 bound: float):
        self.neuron, self.step, self.dt_ms, self.v, self.u = neuron, step, dt_ms, v, u
        self.scheme, self.bound = scheme, bound
        super().__init__(
            f"Izhikevich state diverged: neuron {neuron}, update {step} "
            f"(t = {(step + 1) * dt_ms:g} ms), dt = {dt_ms:g} ms, scheme {scheme!r}: "
            f"v = {v!r}, u = {u!r} (bound |state| <= {bound:g}); reduce dt or the input current")


def resolve_params(params, n_neurons: int | None = None, dtype=np.float64):
    """Turn a preset name, an :class:`IzhikevichParams`, or a sequence of either (one per neuron)
    into four arrays ``(a, b, c, d)`` of shape ``(n_neurons,)``."""
    def one(p):
        if isinstance(p, str):
            try:
                return PRESETS[p.upper()].as_tuple()
            except KeyError:
                raise ValueError(f"unknown Izhikevich preset {p!r}; known: {', '.join(PRESETS)}") \
                    from None
        if isinstance(p, IzhikevichParams):
            return p.as_tuple()
        t = tuple(float(x) for x in p)
        if len(t) != 4:
            raise ValueError(f"a parameter set needs 4 values (a, b, c, d), got {len(t)}")
        return t

    if isinstance(params, (str, IzhikevichParams)) or (
            isinstance(params, Sequence) and len(params) == 4
            and all(isinstance(x, (int, float, np.floating)) for x in params)):
        rows = [one(params)] * (1 if n_neurons is None else n_neurons)
    else:
        rows = [one(p) for p in params]
        if n_neurons is not None and len(rows) != n_neurons:
            raise ValueError(f"{len(rows)} parameter sets given for {n_neurons} neurons")
    arr = np.asarray(rows, dtype=dtype)
    if not np.all(np.isfinite(arr)):
        raise ValueError("Izhikevich parameters must be finite")
    return arr[:, 0].copy(), arr[:, 1].copy(), arr[:, 2].copy(), arr[:, 3].copy()


def derivatives(v, u, I, a, b):
    """Right-hand side ``(dv/dt, du/dt)`` in mV/ms."""
    dt_v = A * v * v + B * v + C - u + I
    return dt_v, a * (b * v - u)


def step(v, u, I, a, b, c, d, dt_ms, scheme="euler"):
    """Advance every neuron by one update.

    Returns ``(v_new, u_new, spiked, v_pre)`` where ``v_pre`` is the membrane potential before the
    threshold/reset (useful to judge how close a spike decision was). Arithmetic is done in the
    dtype of ``v`` (float64 normally; float32 for the precision yardstick).
    """
    dtype = v.dtype
    dt = dtype.type(dt_ms)
    Ad, Bd, Cd = dtype.type(A), dtype.type(B), dtype.type(C)
    if scheme == "euler":
        v_new = v + dt * (Ad * v * v + Bd * v + Cd - u + I)
        u_new = u + dt * (a * (b * v - u))
    elif scheme == "izhikevich":
        h = dtype.type(0.5) * dt
        v_half = v + h * (Ad * v * v + Bd * v + Cd - u + I)
        v_new = v_half + h * (Ad * v_half * v_half + Bd * v_half + Cd - u + I)
        u_new = u + dt * (a * (b * v_new - u))
    elif scheme == "rk4":
        def f(vv, uu):
            return Ad * vv * vv + Bd * vv + Cd - uu + I, a * (b * vv - uu)
        h = dtype.type(0.5) * dt
        k1v, k1u = f(v, u)
        k2v, k2u = f(v + h * k1v, u + h * k1u)
        k3v, k3u = f(v + h * k2v, u + h * k2u)
        k4v, k4u = f(v + dt * k3v, u + dt * k3u)
        sixth = dt / dtype.type(6.0)
        v_new = v + sixth * (k1v + 2 * k2v + 2 * k3v + k4v)
        u_new = u + sixth * (k1u + 2 * k2u + 2 * k3u + k4u)
    else:
        raise ValueError(f"unknown integration scheme {scheme!r}; known: {', '.join(SCHEMES)}")
    v_pre = v_new
    spiked = v_new >= dtype.type(V_TH)
    v_new = np.where(spiked, c, v_new).astype(dtype, copy=False)
    u_new = np.where(spiked, u_new + d, u_new).astype(dtype, copy=False)
    return v_new, u_new, spiked, v_pre


def current_schedule(current, n_steps: int, n_neurons: int, dt_ms: float,
                     dtype=np.float64) -> Callable[[int], np.ndarray | float]:
    """Normalize an input-current description into ``k -> I[k]`` (scalar or shape (n_neurons,)).

    ``current`` may be

    * a number: constant for every neuron and step;
    * an array of shape ``(n_neurons,)`` *only* through :func:`numpy.broadcast_to` to
      ``(n_steps, n_neurons)`` (a bare 1-D array is always read as per-step);
    * a 1-D array of length ``n_steps``: per-step, shared by all neurons;
    * a 2-D array ``(n_steps, n_neurons)``: per-step, per-neuron;
    * a callable ``f(t_ms)`` evaluated at the start of each update, ``t = k dt``, returning a
      number or an array of shape ``(n_neurons,)``.
    """
    if callable(current):
        def from_callable(k):
            val = np.asarray(current(k * dt_ms), dtype=dtype)
            if val.ndim not in (0, 1) or (val.ndim == 1 and val.shape[0] != n_neurons):
                raise ValueError(f"current callable returned shape {val.shape}, expected a number "
                                 f"or ({n_neurons},)")
            if not np.all(np.isfinite(val)):
                raise ValueError(f"current callable returned a non-finite value at t = "
                                 f"{k * dt_ms:g} ms")
            return val
        return from_callable
    arr = np.asarray(current, dtype=dtype)
    if not np.all(np.isfinite(arr)):
        raise ValueError("input current contains non-finite values")
    if arr.ndim == 0:
        const = arr[()]
        return lambda k: const
    if arr.ndim == 1:
        if arr.shape[0] != n_steps:
            raise ValueError(f"a 1-D current is per-step and needs {n_steps} values, got "
                             f"{arr.shape[0]} (for per-neuron constants pass shape "
                             f"({n_steps}, {n_neurons}) or a callable)")
        return lambda k: arr[k]
    if arr.ndim == 2:
        if arr.shape != (n_steps, n_neurons):
            raise ValueError(f"a 2-D current must have shape ({n_steps}, {n_neurons}), got "
                             f"{arr.shape}")
        return lambda k: arr[k]
    raise ValueError(f"input current must be 0-, 1- or 2-D, got {arr.ndim}-D")


def group_spikes(hit_steps, hit_neurons, n_neurons: int) -> list[np.ndarray]:
    """Group parallel chunks of (update index, neuron index) into one sorted array per neuron."""
    if not hit_steps:
        return [np.zeros(0, dtype=np.int64) for _ in range(n_neurons)]
    ks = np.concatenate(hit_steps)
    ns = np.concatenate(hit_neurons)
    order = np.lexsort((ks, ns))
    ks, ns = ks[order], ns[order]
    bounds = np.searchsorted(ns, np.arange(n_neurons + 1))
    return [ks[bounds[i]:bounds[i + 1]].copy() for i in range(n_neurons)]


@dataclass
class IzhikevichResult:
    """Outcome of :func:`simulate`: spike times per neuron and, optionally, state traces."""

    dt_ms: float
    scheme: str
    n_steps: int
    spikes_ms: list[np.ndarray]
    v: np.ndarray                       # final state
    u: np.ndarray
    v_trace: np.ndarray | None = None   # (n_steps + 1, n_neurons) when recorded
    u_trace: np.ndarray | None = None
    spike_steps: list[np.ndarray] = field(default_factory=list)

    @property
    def spike_counts(self) -> np.ndarray:
        return np.array([len(s) for s in self.spikes_ms])


def simulate(params="RS", current=10.0, *, duration_ms: float | None = None,
             n_steps: int | None = None, n_neurons: int | None = None,
             dt_ms: float = DEFAULT_DT_MS, scheme: str = "euler", v0=None, u0=None,
             record: bool = False, dtype=np.float64,
             state_bound: float = STATE_BOUND) -> IzhikevichResult:
    """Simulate a population of Izhikevich neurons.

    Parameters
    ----------
    params
        Preset name (``"RS"``, ``"IB"``, ``"CH"``, ``"FS"``, ``"LTS"``, ``"RZ"``), an
        :class:`IzhikevichParams`, a 4-tuple ``(a, b, c, d)``, or a list of those (one per neuron).
    current
        Input current in mV/ms; see :func:`current_schedule`.
    duration_ms, n_steps
        Length of the run; exactly one must be given. ``n_steps = round(duration_ms / dt_ms)``.
    n_neurons
        Population size (defaults to the number of parameter sets given, else 1).
    dt_ms
        Integration step in ms (default 1/16 ms, i.e. a 16 kHz update rate).
    scheme
        ``"euler"``, ``"izhikevich"`` or ``"rk4"`` (see the module docstring).
    v0, u0
        Initial state (default ``-65`` and ``b * v0``).
    record
        Keep the whole ``v``/``u`` trace (memory ``2 (n_steps+1) n_neurons`` values).
    dtype
        ``numpy.float64`` (reference) or ``numpy.float32`` (the precision yardstick).

    Raises
    ------
    DivergenceError
        If a state becomes non-finite or exceeds ``state_bound`` in magnitude.
    """
    if scheme not in SCHEMES:
        raise ValueError(f"unknown integration scheme {scheme!r}; known: {', '.join(SCHEMES)}")
    if not (np.isfinite(dt_ms) and dt_ms > 0):
        raise ValueError(f"dt_ms must be a positive finite number, got {dt_ms!r}")
    if (duration_ms is None) == (n_steps is None):
        raise ValueError("give exactly one of duration_ms and n_steps")
    if n_steps is None:
        if not (np.isfinite(duration_ms) and duration_ms >= 0):
            raise ValueError(f"duration_ms must be a non-negative number, got {duration_ms!r}")
        n_steps = int(round(duration_ms / dt_ms))
    if n_steps < 0:
        raise ValueError("n_steps must be >= 0")
    dtype = np.dtype(dtype)
    single = isinstance(params, (str, IzhikevichParams)) or (
        isinstance(params, Sequence) and len(params) == 4
        and all(isinstance(x, (int, float, np.floating)) for x in params))
    if n_neurons is None:
        n_neurons = 1 if single else len(params)
    if n_neurons < 1:
        raise ValueError("n_neurons must be >= 1")
    a, b, c, d = resolve_params(params, n_neurons, dtype=dtype)
    v = np.full(n_neurons, V0, dtype=dtype) if v0 is None else \
        np.broadcast_to(np.asarray(v0, dtype=dtype), (n_neurons,)).copy()
    u = (b * v).astype(dtype) if u0 is None else \
        np.broadcast_to(np.asarray(u0, dtype=dtype), (n_neurons,)).copy()
    I_of = current_schedule(current, n_steps, n_neurons, dt_ms, dtype=dtype)

    v_tr = u_tr = None
    if record:
        v_tr = np.empty((n_steps + 1, n_neurons), dtype=dtype)
        u_tr = np.empty((n_steps + 1, n_neurons), dtype=dtype)
        v_tr[0], u_tr[0] = v, u
    hit_steps: list[np.ndarray] = []
    hit_neurons: list[np.ndarray] = []
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(n_steps):
            v, u, spiked, v_pre = step(v, u, I_of(k), a, b, c, d, dt_ms, scheme)
            bad = ~(np.isfinite(v_pre) & np.isfinite(u) & (np.abs(v_pre) <= state_bound)
                    & (np.abs(u) <= state_bound))
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise DivergenceError(i, k, dt_ms, float(v_pre[i]), float(u[i]), scheme,
                                      state_bound)
            if spiked.any():
                idx = np.flatnonzero(spiked)
                hit_neurons.append(idx)
                hit_steps.append(np.full(idx.size, k, dtype=np.int64))
            if record:
                v_tr[k + 1], u_tr[k + 1] = v, u
    steps = group_spikes(hit_steps, hit_neurons, n_neurons)
    return IzhikevichResult(dt_ms=dt_ms, scheme=scheme, n_steps=n_steps,
                            spikes_ms=[(s + 1) * dt_ms for s in steps], v=v, u=u,
                            v_trace=v_tr, u_trace=u_tr, spike_steps=steps)
