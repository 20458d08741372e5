"""Float reference model of the Izhikevich neuron, vectorized over neurons.

Equations (Izhikevich 2003)::

    dv/dt = A v^2 + B v + C - u + I      A = 0.04 /(ms mV), B = 5 /ms, C = 140 mV/ms
    du/dt = a (b (v - v_u) - lambda u)   v_u = 0, lambda = 1 (the standard form)
    if v >= v_th (30 mV):  v <- c,  u <- u + d

``A``, ``B``, ``C``, ``v_u`` and ``lambda`` (``u_leak``) belong to a parameter set
(:class:`IzhikevichParams`): the classic presets use the standard values, and the published
figure code of Izhikevich (2004) uses ``0.04 v^2 + 4.1 v + 108`` for class-1 excitability and
the integrator, and ``du/dt = a b (v + 65)`` (``v_u = -65``, ``lambda = 0``) for accommodation
(see :mod:`cuneate.golden.behaviours`). ``a``, ``b`` and ``d`` may be negative or zero.

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

from .kernel import available as kernel_available

__all__ = [
    "spike_times", "spike_ticks",
    "A", "B", "C", "V_TH", "V0", "SCHEMES", "DEFAULT_DT_MS", "STATE_BOUND",
    "IzhikevichParams", "PRESETS", "DivergenceError", "IzhikevichResult", "NeuronParams",
    "to_params", "resolve_param_sets", "resolve_params", "derivatives", "step", "simulate", "current_schedule", "group_spikes",
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
    """One Izhikevich parameter set.

    ``a`` (1/ms, the time scale of the recovery variable ``u``) and ``b`` (the sensitivity of
    ``u`` to ``v``) set the recovery, ``c`` (mV) the reset and ``d`` (mV/ms) the jump of ``u`` at
    a spike; ``A``, ``B``, ``C`` are the coefficients of the
    v-equation and ``v_u``, ``u_leak`` the form of the u-equation
    ``du/dt = a (b (v - v_u) - u_leak u)`` (``u_leak`` is 1 or 0). ``name`` only labels the set
    in messages and reports.
    """

    a: float
    b: float
    c: float
    d: float
    A: float = 0.04
    B: float = 5.0
    C: float = 140.0
    u_leak: float = 1.0
    v_u: float = 0.0
    name: str = field(default="", compare=False)

    def __post_init__(self):
        for k in ("a", "b", "c", "d", "A", "B", "C", "u_leak", "v_u"):
            val = getattr(self, k)
            if not isinstance(val, (int, float, np.integer, np.floating)) or not np.isfinite(val):
                raise ValueError(f"Izhikevich parameter {k} must be a finite number, got {val!r}")
        if self.u_leak not in (0.0, 1.0):
            raise ValueError(f"u_leak must be 1 (du/dt = a (b v - u)) or 0 "
                             f"(du/dt = a b (v - v_u)), got {self.u_leak!r}")
        if not self.A > 0:
            raise ValueError(f"the v-equation needs A > 0 (a quadratic with a minimum), "
                             f"got A = {self.A!r}")

    def as_tuple(self) -> tuple[float, float, float, float]:
        return (self.a, self.b, self.c, self.d)

    @property
    def standard(self) -> bool:
        """True when A, B, C and the u-equation have their standard (2003) values."""
        return (self.A, self.B, self.C, self.u_leak, self.v_u) == (A, B, C, 1.0, 0.0)

    def label(self) -> str:
        return self.name or f"(a={self.a:g}, b={self.b:g}, c={self.c:g}, d={self.d:g})"

    def to_dict(self) -> dict:
        out = {"a": self.a, "b": self.b, "c": self.c, "d": self.d}
        if not self.standard:
            out |= {"A": self.A, "B": self.B, "C": self.C, "u_leak": self.u_leak,
                    "v_u": self.v_u}
        if self.name:
            out["name"] = self.name
        return out


#: Classic parameter sets (Izhikevich 2003/2004).
PRESETS: Mapping[str, IzhikevichParams] = {
    "RS": IzhikevichParams(0.02, 0.2, -65.0, 8.0, name="RS"),    # regular spiking
    "IB": IzhikevichParams(0.02, 0.2, -55.0, 4.0, name="IB"),    # intrinsically bursting
    "CH": IzhikevichParams(0.02, 0.2, -50.0, 2.0, name="CH"),    # chattering
    "FS": IzhikevichParams(0.1, 0.2, -65.0, 2.0, name="FS"),     # fast spiking
    "LTS": IzhikevichParams(0.02, 0.25, -65.0, 2.0, name="LTS"),  # low-threshold spiking
    "RZ": IzhikevichParams(0.1, 0.26, -65.0, 2.0, name="RZ"),    # resonator
}


class DivergenceError(FloatingPointError):
    """The integration left the representable/physical range (non-finite or beyond the bound)."""

    def __init__(self, neuron: int, step: int, dt_ms: float, v: float, u: float, scheme: str,
                 bound: float):
        self.neuron, self.step, self.dt_ms, self.v, self.u = neuron, step, dt_ms, v, u
        self.scheme, self.bound = scheme, bound
        self.t_ms = float(spike_times(step, dt_ms))       # the time of the update's spike
        super().__init__(
            f"Izhikevich state diverged: neuron {neuron}, update {step} "
            f"(t = {self.t_ms:g} ms), dt = {dt_ms:g} ms, scheme {scheme!r}: "
            f"v = {v!r}, u = {u!r} (bound |state| <= {bound:g}); reduce dt or the input current")


def to_params(p) -> IzhikevichParams:
    """One parameter set from a preset name, an :class:`IzhikevichParams`, a 4-tuple
    ``(a, b, c, d)`` or a mapping with keys ``a, b, c, d`` and optionally ``A, B, C, u_leak, v_u,
    name``."""
    if isinstance(p, IzhikevichParams):
        return p
    if isinstance(p, str):
        try:
            return PRESETS[p.upper()]
        except KeyError:
            raise ValueError(f"unknown Izhikevich preset {p!r}; known: {', '.join(PRESETS)}") \
                from None
    if isinstance(p, Mapping):
        unknown = set(p) - {"a", "b", "c", "d", "A", "B", "C", "u_leak", "v_u", "name"}
        if unknown:
            raise ValueError(f"unknown Izhikevich parameter(s) {sorted(unknown)}")
        missing = [k for k in "abcd" if k not in p]
        if missing:
            raise ValueError(f"a parameter set needs a, b, c, d; missing {missing}")
        kw = {k: (str(v) if k == "name" else float(v)) for k, v in p.items()}
        return IzhikevichParams(**kw)
    try:
        t = tuple(float(x) for x in p)
    except (TypeError, ValueError):
        raise ValueError(f"cannot read an Izhikevich parameter set from {p!r}") from None
    if len(t) != 4:
        raise ValueError(f"a parameter set needs 4 values (a, b, c, d), got {len(t)}")
    return IzhikevichParams(*t)


def _is_single(params) -> bool:
    return isinstance(params, (str, IzhikevichParams, Mapping)) or (
        isinstance(params, Sequence) and len(params) == 4
        and all(isinstance(x, (int, float, np.integer, np.floating)) for x in params))


def resolve_param_sets(params, n_neurons: int | None = None) -> list[IzhikevichParams]:
    """One :class:`IzhikevichParams` per neuron (a single set is repeated)."""
    if _is_single(params):
        return [to_params(params)] * (1 if n_neurons is None else n_neurons)
    rows = [to_params(p) for p in params]
    if n_neurons is not None and len(rows) != n_neurons:
        raise ValueError(f"{len(rows)} parameter sets given for {n_neurons} neurons")
    return rows


@dataclass
class NeuronParams:
    """Per-neuron parameter arrays (shape ``(n_neurons,)``) of every coefficient."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    u_leak: np.ndarray
    v_u: np.ndarray

    @classmethod
    def from_sets(cls, sets: Sequence[IzhikevichParams], dtype=np.float64) -> "NeuronParams":
        keys = ("a", "b", "c", "d", "A", "B", "C", "u_leak", "v_u")
        distinct, index = _distinct(sets)
        table = np.array([[getattr(s, k) for k in keys] for s in distinct], dtype=dtype)
        rows = table[index] if len(distinct) > 1 else np.broadcast_to(table, (len(sets), 9))
        return cls(**{k: np.array(rows[:, j]) for j, k in enumerate(keys)})

    def extras(self) -> dict:
        """Keyword arguments of :func:`step` beyond ``a, b, c, d``."""
        return {"A": self.A, "B": self.B, "C": self.C, "u_leak": self.u_leak, "v_u": self.v_u}


def _distinct(sets: Sequence[IzhikevichParams]) -> tuple[list, np.ndarray | None]:
    """The distinct objects of ``sets`` (by identity, in order of appearance) and each
    entry's index into them (``None`` when all are one object: a set repeated)."""
    first = sets[0] if len(sets) else None
    if all(s is first for s in sets):
        return ([first] if len(sets) else []), None
    seen: dict = {}
    index = np.array([seen.setdefault(id(s), (len(seen), s))[0] for s in sets], np.int64)
    return [s for _, s in seen.values()], index


def resolve_params(params, n_neurons: int | None = None, dtype=np.float64):
    """Arrays ``(a, b, c, d)`` of shape ``(n_neurons,)`` (see :func:`resolve_param_sets`)."""
    np_ = NeuronParams.from_sets(resolve_param_sets(params, n_neurons), dtype)
    return np_.a.copy(), np_.b.copy(), np_.c.copy(), np_.d.copy()


def derivatives(v, u, I, a, b, *, A=A, B=B, C=C, u_leak=1.0, v_u=0.0):
    """Right-hand side ``(dv/dt, du/dt)`` in mV/ms."""
    dt_v = A * v * v + B * v + C - u + I
    return dt_v, a * (b * (v - v_u) - u_leak * u)


def _uterm(b, v, u, u_leak, v_u):
    """``b (v - v_u) - u_leak u``, written so that the standard form keeps its exact
    floating-point operation order ``b v - u``."""
    if np.all(np.asarray(u_leak) == 1.0) and np.all(np.asarray(v_u) == 0.0):
        return b * v - u
    return b * (v - v_u) - u_leak * u


def step(v, u, I, a, b, c, d, dt_ms, scheme="euler", *, A=A, B=B, C=C, u_leak=1.0, v_u=0.0):
    """Advance every neuron by one update.

    Returns ``(v_new, u_new, spiked, v_pre)`` where ``v_pre`` is the membrane potential before the
    threshold/reset (useful to judge how close a spike decision was). Arithmetic is done in the
    dtype of ``v`` (float64 normally; float32 for the precision yardstick). ``A, B, C, u_leak,
    v_u`` are scalars or per-neuron arrays (see :class:`IzhikevichParams`).
    """
    dtype = v.dtype
    dt = dtype.type(dt_ms)

    def cast(x):
        return np.asarray(x, dtype=dtype) if np.ndim(x) else dtype.type(x)
    Ad, Bd, Cd, lam, vu = (cast(x) for x in (A, B, C, u_leak, v_u))
    if scheme == "euler":
        v_new = v + dt * (Ad * v * v + Bd * v + Cd - u + I)
        u_new = u + dt * (a * _uterm(b, v, u, lam, vu))
    elif scheme == "izhikevich":
        h = dtype.type(0.5) * dt
        v_half = v + h * (Ad * v * v + Bd * v + Cd - u + I)
        v_new = v_half + h * (Ad * v_half * v_half + Bd * v_half + Cd - u + I)
        u_new = u + dt * (a * _uterm(b, v_new, u, lam, vu))
    elif scheme == "rk4":
        def f(vv, uu):
            return Ad * vv * vv + Bd * vv + Cd - uu + I, a * _uterm(b, vv, uu, lam, vu)
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
    # a broadcast array repeats its data: check each stored value once
    stored = arr[tuple(slice(0, 1) if st == 0 else slice(None) for st in arr.strides)]
    if not np.all(np.isfinite(stored)):
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


def spike_times(ticks, dt_ms: float) -> np.ndarray:
    """The spike times (ms) of the updates of ticks (steps) ``ticks``: ``(k + 1) dt``, in the
    order given (the one tick-to-time conversion of every model, twin and engine)."""
    return (np.asarray(ticks, dtype=np.float64) + 1) * dt_ms


def spike_ticks(times_ms, dt_ms: float) -> np.ndarray:
    """The ticks whose updates made the spikes at ``times_ms`` (the inverse of
    :func:`spike_times`)."""
    return np.rint(np.asarray(times_ms, dtype=np.float64) / dt_ms).astype(np.int64) - 1


def group_spikes(hit_steps, hit_neurons, n_neurons: int, dt_ms: float | None = None):
    """Group parallel chunks of (update index, neuron index) into one sorted array per neuron
    (views of one array). With ``dt_ms``, also the spike times ``(k + 1) dt`` per neuron:
    returns ``(steps, times)``."""
    from .kernel import by_neuron
    if hit_steps:
        ks, bounds = by_neuron(np.concatenate(hit_steps), np.concatenate(hit_neurons),
                               n_neurons)
    else:
        ks, bounds = np.zeros(0, dtype=np.int64), np.zeros(n_neurons + 1, np.int64)
    edges = list(zip(bounds[:-1].tolist(), bounds[1:].tolist()))
    steps = [ks[a:b] for a, b in edges]
    if dt_ms is None:
        return steps
    times = spike_times(ks, dt_ms)
    return steps, [times[a:b] for a, b in edges]


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


KERNELS = ("numba", "numpy")


def simulate(params="RS", current=10.0, *, duration_ms: float | None = None,
             n_steps: int | None = None, n_neurons: int | None = None,
             dt_ms: float = DEFAULT_DT_MS, scheme: str = "euler", v0=None, u0=None,
             record: bool = False, dtype=np.float64,
             state_bound: float = STATE_BOUND, progress=None, kernel: str | None = None,
             threads: int | None = None) -> IzhikevichResult:
    """Simulate a population of Izhikevich neurons.

    Parameters
    ----------
    params
        Preset name (``"RS"``, ``"IB"``, ``"CH"``, ``"FS"``, ``"LTS"``, ``"RZ"``), an
        :class:`IzhikevichParams`, a 4-tuple ``(a, b, c, d)``, a mapping, or a list of those (one
        per neuron). A reset ``c`` at or above ``v_th`` is refused (:class:`ValueError`).
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
    progress
        Called with the number of updates done, every 1000 updates (for progress bars).
    kernel
        ``"numba"``: a compiled loop over neurons and steps (the same floating-point operations
        in the same order, so the same state and spikes to the bit; ``euler`` and
        ``izhikevich`` schemes without ``record``); ``"numpy"``: the vectorized
        :func:`step` per update (the reference). Default: ``"numba"`` where it applies.
    threads
        Threads for the compiled loop (neurons are independent); default two (at most the
        cores) when the current is an array, from 512 neurons and 2e6 updates on (each thread
        runs its blocks of neurons through every step), from 50 000 neurons on when it is a
        callable (evaluated per step, so the threads meet once per step), else one.
        Per-neuron constants are cheapest as a zero-copy broadcast,
        ``np.broadcast_to(I, (n_steps, n_neurons))``.

    Raises
    ------
    DivergenceError
        If a state becomes non-finite or exceeds ``state_bound`` in magnitude.
    """
    if scheme not in SCHEMES:
        raise ValueError(f"unknown integration scheme {scheme!r}; known: {', '.join(SCHEMES)}")
    if kernel not in (None, *KERNELS):
        raise ValueError(f"unknown golden kernel {kernel!r}; known: {', '.join(KERNELS)}")
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
    if n_neurons is None:
        n_neurons = 1 if _is_single(params) else len(params)
    if n_neurons < 1:
        raise ValueError("n_neurons must be >= 1")
    sets = resolve_param_sets(params, n_neurons)
    for s in _distinct(sets)[0]:
        if not s.c < V_TH:
            i = next(i for i, x in enumerate(sets) if x is s)
            raise ValueError(f"parameter set of neuron {i} {s.label()}: reset c = {s.c:g} mV is "
                             f"not below the threshold v_th = {V_TH:g} mV (the neuron would "
                             f"spike on every update)")
    prm = NeuronParams.from_sets(sets, dtype)
    v = np.full(n_neurons, V0, dtype=dtype) if v0 is None else \
        np.broadcast_to(np.asarray(v0, dtype=dtype), (n_neurons,)).copy()
    u = (prm.b * v).astype(dtype) if u0 is None else \
        np.broadcast_to(np.asarray(u0, dtype=dtype), (n_neurons,)).copy()
    I_of = current_schedule(current, n_steps, n_neurons, dt_ms, dtype=dtype)
    fast_ok = scheme in ("euler", "izhikevich") and not record and \
        dtype in (np.dtype(np.float64), np.dtype(np.float32)) and \
        state_bound >= 0 and np.asarray(state_bound, dtype=dtype) == state_bound
    if kernel is None:
        kernel = "numba" if fast_ok and kernel_available() else "numpy"
    elif kernel == "numba" and not fast_ok:
        raise ValueError(f"the numba golden kernel runs the euler and izhikevich schemes in "
                         f"float64/float32 without record, with a state bound exact in that "
                         f"type (asked: {scheme!r}, {dtype.name}, record={record}, "
                         f"state_bound={state_bound!r})")
    if kernel == "numba":
        from .izhikevich_kernel import simulate_compiled
        hit_steps, hit_neurons, bad = simulate_compiled(
            prm, v, u, current, I_of, n_steps, n_neurons, dt_ms, scheme, dtype, state_bound,
            progress, threads, V_TH)
        if bad is not None:
            k, i, vp, uu = bad
            raise DivergenceError(i, k, dt_ms, vp, uu, scheme, state_bound)
        v_tr = u_tr = None
    else:
        v, u, hit_steps, hit_neurons, v_tr, u_tr = _simulate_numpy(
            prm, v, u, I_of, n_steps, n_neurons, dt_ms, scheme, dtype, record, state_bound,
            progress)
    steps, times = group_spikes(hit_steps, hit_neurons, n_neurons, dt_ms)
    return IzhikevichResult(dt_ms=dt_ms, scheme=scheme, n_steps=n_steps, spikes_ms=times, v=v,
                            u=u, v_trace=v_tr, u_trace=u_tr, spike_steps=steps)


def _simulate_numpy(prm, v, u, I_of, n_steps, n_neurons, dt_ms, scheme, dtype, record,
                    state_bound, progress):
    """The reference loop: :func:`step` over all neurons per update."""
    a, b, c, d = prm.a, prm.b, prm.c, prm.d
    extras = prm.extras()
    v_tr = u_tr = None
    if record:
        v_tr = np.empty((n_steps + 1, n_neurons), dtype=dtype)
        u_tr = np.empty((n_steps + 1, n_neurons), dtype=dtype)
        v_tr[0], u_tr[0] = v, u
    hit_steps: list[np.ndarray] = []
    hit_neurons: list[np.ndarray] = []
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(n_steps):
            v, u, spiked, v_pre = step(v, u, I_of(k), a, b, c, d, dt_ms, scheme, **extras)
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
            if progress is not None and (k + 1) % 1000 == 0:
                progress(k + 1)
    return v, u, hit_steps, hit_neurons, v_tr, u_tr
