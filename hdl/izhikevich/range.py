"""The state range an Izhikevich parameter set can reach for currents in an accepted range, and
the error bound of one update of the core against the golden model.

The core's state formats and clamp levels are sized from this range (see
:class:`cuneate.hdl.izhikevich.IzhikevichConfig`), so that no clamp acts for any accepted input.
The range is derived in two parts:

**u (recovery variable): a documented worst-case search.** Forward Euler in float64 at the core's
``dt`` (the scheme the core implements) runs every parameter set from each of its initial states
under a battery of stimuli spanning the accepted range ``[I_lo, I_hi]``:

* constant currents at 17 evenly spaced levels from ``I_lo`` to ``I_hi`` (both included) and 0;
* steps ``I_lo -> I_hi`` and ``I_hi -> I_lo`` at half time;
* square waves between ``I_lo``/``I_hi``, ``0``/``I_hi`` and ``I_lo``/``0`` with periods of
  2 updates (the fastest the tick rate allows), 1, 2, 5, 10, 20, 50 and 100 ms and duty cycles
  25, 50 and 75 %;
* linear ramps ``I_lo -> I_hi`` and ``I_hi -> I_lo`` over the run.

The run lasts ``clip(10 / |a|, 400, 3000)`` ms (ten recovery time constants of the slowest set).
The search runs compiled (numba: each trajectory's Euler steps are golden's operations in
golden's order, the stimuli generated per step by the same operations as the matrix below,
so its extremes equal the NumPy loop's to the bit; that loop is kept as the reference).
The largest ``u`` comes from sustained maximal drive (more current, more spikes, each adding
``d``); square waves, steps and ramps were measured not to exceed it. The search's extremes are
widened by a margin ``0.02 (u_max - u_min) + max(|d|)`` (one recovery jump more than ever seen,
plus 2 % for the difference between the float search and the fixed-point datapath). A
trajectory that diverges (non-finite or beyond 1e4 in magnitude) refuses the configuration,
naming the parameter set, the stimulus and the time. The search generates its stimuli a block of
steps at a time (its memory does not grow with ``1 / dt``) and estimates its time before it
starts (:func:`search_estimate`, checked against :mod:`cuneate.golden.budget`).

**v (membrane potential): a bound proven from the u bound.** With ``u <= u_hi`` and
``I >= I_lo``, ``dv/dt >= f(v) = A v^2 + B v + C - u_hi + I_lo``. Below the lower root ``r`` of
``f`` the potential rises, and one Euler update maps ``v`` to at least
``g(v) = v + dt f(v)``, a parabola with its minimum at ``v* = -(1/dt + B) / (2A)``. Hence
``v >= min(r, min over [r, v_th] of g)``, i.e. ``r`` when ``v* <= r`` (small ``dt``: the update
is monotone) and ``g(v*)`` otherwise (Euler overshoots below the root). The stored ``v`` is
below ``v_th`` (a spike resets it to ``c``), so ``v`` lies in ``[v_floor, v_th)`` with
``v_floor`` that bound minus a margin of 1 mV + 1 %. When ``f`` has no root, ``v`` never falls
and the floor is the lowest of the initial ``v``, the resets ``c`` and the search minimum.

Everything downstream (multiplier operands, sums) follows from these two intervals by interval
arithmetic in the configuration.

**One step against golden.** :func:`one_step_bound` sums every rounding and representation error
of the datapath, each at its worst, into a bound on the difference between one update of the
core and one float64 forward-Euler step from the same state; the scoreboards check every update
against it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np

from ...golden import budget
from ...golden import izhikevich as golden
from ...golden.kernel import available as kernel_available

__all__ = ["SetRange", "RangeSearchError", "reachable_ranges", "stimulus_battery",
           "search_estimate", "SEARCH_STATE_BOUND", "one_step_bound"]

SEARCH_STATE_BOUND = 1e4


class RangeSearchError(ValueError):
    """A parameter set whose state diverges for a current in the accepted range."""


@dataclass(frozen=True)
class SetRange:
    """Reachable state range of one parameter set (mV; ``u`` in mV/ms units of the model)."""

    label: str
    i_lo: float
    i_hi: float
    duration_ms: float
    n_stimuli: int
    u_min_search: float
    u_max_search: float
    u_worst_stimulus: str
    v_min_search: float
    v_pre_max_search: float
    u_lo: float            # u clamp levels: search extremes widened by the margin
    u_hi: float
    v_floor_proven: float  # analytic lower bound of v for u <= u_hi, I >= I_lo
    v_floor: float         # v clamp level: the proven bound minus the margin

    def to_dict(self) -> dict:
        return asdict(self)


def _battery(i_lo: float, i_hi: float, dt_ms: float):
    """The search stimuli as ``(name, kind, args)``: ``const`` (level), ``step`` (before,
    after), ``square`` (low, high, period, duty) and ``ramp`` (start, stop)."""
    out = []
    for level in np.unique(np.concatenate([np.linspace(i_lo, i_hi, 17),
                                           [0.0] if i_lo < 0 < i_hi else []])):
        out.append((f"constant I = {level:g}", "const", (float(level),)))
    out.append((f"step {i_lo:g} -> {i_hi:g}", "step", (i_lo, i_hi)))
    out.append((f"step {i_hi:g} -> {i_lo:g}", "step", (i_hi, i_lo)))
    pairs = [(i_lo, i_hi)]
    if i_lo < 0 < i_hi:
        pairs += [(0.0, i_hi), (i_lo, 0.0)]
    for lo, hi in pairs:
        for period in (2 * dt_ms, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0):
            for duty in (0.25, 0.5, 0.75):
                out.append((f"square {lo:g}/{hi:g}, period {period:g} ms, duty {duty:g}",
                            "square", (lo, hi, period, duty)))
    out.append((f"ramp {i_lo:g} -> {i_hi:g}", "ramp", (i_lo, i_hi)))
    out.append((f"ramp {i_hi:g} -> {i_lo:g}", "ramp", (i_hi, i_lo)))
    return out


def _battery_rows(battery, k0: int, k1: int, dt_ms: float, n_steps: int) -> np.ndarray:
    """Rows ``k0 .. k1 - 1`` of the stimulus matrix, ``(k1 - k0, n_stimuli)``, equal bit for
    bit to the same rows of the whole matrix (a ramp is :func:`numpy.linspace`'s
    ``start + k * step`` with its last value exactly ``stop``)."""
    k = np.arange(k0, k1)
    t = k * dt_ms
    cols = []
    for _, kind, a in battery:
        if kind == "const":
            cols.append(np.full(k.size, a[0]))
        elif kind == "step":
            cols.append(np.where(k < n_steps // 2, a[0], a[1]))
        elif kind == "square":
            lo, hi, period, duty = a
            cols.append(np.where((t % period) < duty * period, hi, lo))
        else:
            start, stop = a
            if n_steps > 1:
                col = k.astype(np.float64) * ((stop - start) / (n_steps - 1)) + start
                col[k == n_steps - 1] = stop
            else:
                col = np.full(k.size, float(start))
            cols.append(col)
    return np.stack(cols, axis=1)


def stimulus_battery(i_lo: float, i_hi: float, dt_ms: float, n_steps: int):
    """The search stimuli as ``(names, I)`` with ``I`` of shape ``(n_steps, n_stimuli)`` (the
    search itself generates them a block of steps at a time)."""
    battery = _battery(i_lo, i_hi, dt_ms)
    return [b[0] for b in battery], _battery_rows(battery, 0, n_steps, dt_ms, n_steps)


#: Steps of the stimulus generated at a time by the search (its memory does not grow with dt).
SEARCH_BLOCK = 4096
#: Conservative cost of the search: seconds per step and per trajectory-step (Euler on NumPy).
SEARCH_S_PER_STEP, SEARCH_S_PER_TRAJECTORY_STEP = 6e-5, 1.5e-6
#: The same for the compiled search (measured 0.17-0.5 us per step of 94 trajectories on a
#: loaded 2-core machine: the stimuli's fixed cost per step, then about 1-2 ns a trajectory)
SEARCH_S_PER_STEP_COMPILED, SEARCH_S_PER_TRAJECTORY_STEP_COMPILED = 3e-7, 4e-9


def search_estimate(n_sets: int, n_inits: int, dt_ms: float, duration_ms: float = 3000.0
                    ) -> dict:
    """Memory (bytes) and time (s) of the range search of ``n_inits`` initial states over
    ``n_sets`` parameter sets at ``dt_ms`` for ``duration_ms`` (the longest search lasts
    3000 ms), before it runs."""
    n_steps = duration_ms / dt_ms
    cols = 100.0 * n_inits
    per_step, per_traj = ((SEARCH_S_PER_STEP_COMPILED, SEARCH_S_PER_TRAJECTORY_STEP_COMPILED)
                          if kernel_available() else
                          (SEARCH_S_PER_STEP, SEARCH_S_PER_TRAJECTORY_STEP))
    seconds = n_steps * (per_step + per_traj * cols)
    nbytes = 8.0 * (SEARCH_BLOCK + 16) * cols + 4096.0 * n_sets
    return {"steps": n_steps, "trajectories": cols, "seconds": seconds, "bytes": nbytes}


def _v_floor_bound(p: golden.IzhikevichParams, u_hi: float, i_lo: float, dt: float,
                   v_th: float) -> float | None:
    """Proven lower bound of v (see the module docstring), or None when f has no root."""
    k = p.C - u_hi + i_lo
    disc = p.B * p.B - 4 * p.A * k
    if disc < 0:
        return None
    r = (-p.B - math.sqrt(disc)) / (2 * p.A)
    v_star = -(1.0 / dt + p.B) / (2 * p.A)
    if v_star <= r or v_star >= v_th:
        return r
    return min(r, v_star + dt * (p.A * v_star * v_star + p.B * v_star + k))


def reachable_ranges(sets, dt_ms: float, i_lo: float, i_hi: float, inits, v_th: float
                     ) -> list[SetRange]:
    """Reachable state range of each parameter set.

    Parameters
    ----------
    sets
        :class:`~cuneate.golden.izhikevich.IzhikevichParams`, one per set.
    inits
        Per set, a tuple of initial states ``((v0, u0), ...)`` used by the configuration.
    """
    key = (tuple(sets), float(dt_ms), float(i_lo), float(i_hi),
           tuple(tuple((float(v), float(u)) for v, u in s) for s in inits), float(v_th))
    return list(_cached(key))


@lru_cache(maxsize=256)
def _cached(key) -> tuple[SetRange, ...]:
    sets, dt, i_lo, i_hi, inits, v_th = key
    slowest = min((abs(s.a) for s in sets if s.a != 0), default=0.1)
    duration = float(np.clip(10.0 / slowest, 400.0, 3000.0))
    n_steps = int(round(duration / dt))
    est = search_estimate(len(sets), sum(len(s) for s in inits), dt, duration)
    budget.check(f"the state-range search ({len(sets)} parameter set(s), {n_steps:.3g} steps "
                 f"of dt = {dt:g} ms)", est["bytes"], est["seconds"],
                 "lower the update rate (update_hz)")
    battery = _battery(i_lo, i_hi, dt)
    names = [b[0] for b in battery]
    n_stim = len(battery)
    cols_set, cols_v0, cols_u0 = [], [], []
    for si, (s, st) in enumerate(zip(sets, inits)):
        for v0, u0 in st:
            cols_set += [si] * n_stim
            cols_v0 += [v0] * n_stim
            cols_u0 += [u0] * n_stim
    cols_set = np.asarray(cols_set)
    v = np.asarray(cols_v0, dtype=np.float64)
    u = np.asarray(cols_u0, dtype=np.float64)
    search = _search_compiled if kernel_available() else _search_numpy
    ext = search(sets, cols_set, v, u, battery, n_steps, dt)
    if isinstance(ext, tuple) and len(ext) == 2:              # a divergence: (step, column)
        k, j = ext
        s, t_ms = sets[cols_set[j]], float(golden.spike_times(k, dt))
        raise RangeSearchError(
            f"parameter set {s.label()} diverges for currents in the accepted range "
            f"[{i_lo:g}, {i_hi:g}] mV/ms: under '{names[j % n_stim]}' the state leaves "
            f"|v|, |u| <= {SEARCH_STATE_BOUND:g} at t = {t_ms:g} ms (dt = "
            f"{dt:g} ms); narrow the accepted current range (current_range) or use a "
            f"smaller dt")
    v_min, u_min, u_max, v_pre_max = ext
    out = []
    for si, (s, st) in enumerate(zip(sets, inits)):
        sel = cols_set == si
        umn, umx = float(u_min[sel].min()), float(u_max[sel].max())
        worst = names[int(np.flatnonzero(sel)[np.argmax(u_max[sel])]) % n_stim]
        margin = 0.02 * (umx - umn) + max(abs(x.d) for x in sets)
        u_lo, u_hi = umn - margin, umx + margin
        vmn = float(v_min[sel].min())
        proven = _v_floor_bound(s, u_hi, i_lo, dt, v_th)
        lowest = min([vmn, s.c] + [v0 for v0, _ in st])
        base = lowest if proven is None else min(proven, lowest)
        v_floor = base - (1.0 + 0.01 * abs(base))
        out.append(SetRange(s.label(), i_lo, i_hi, duration, n_stim, umn, umx, worst, vmn,
                            float(v_pre_max[sel].max()), u_lo, u_hi,
                            base if proven is None else proven, v_floor))
    return tuple(out)


def _search_numpy(sets, cols_set, v, u, battery, n_steps: int, dt: float):
    """The search by :func:`cuneate.golden.izhikevich.step` over every trajectory per step
    (the reference loop). Returns the extremes ``(v_min, u_min, u_max, v_pre_max)`` per
    trajectory, or the first divergence as ``(step, trajectory)``."""
    n_rep = len(cols_set) // len(battery)
    prm = golden.NeuronParams.from_sets([sets[i] for i in cols_set])
    extras = prm.extras()
    v_min, u_min, u_max, v_pre_max = v.copy(), u.copy(), u.copy(), v.copy()
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(n_steps):
            if k % SEARCH_BLOCK == 0:
                stim = _battery_rows(battery, k, min(k + SEARCH_BLOCK, n_steps), dt, n_steps)
            I = np.tile(stim[k % SEARCH_BLOCK], n_rep)
            v, u, _, v_pre = golden.step(v, u, I, prm.a, prm.b, prm.c, prm.d, dt, "euler",
                                         **extras)
            bad = ~(np.isfinite(v_pre) & np.isfinite(u) & (np.abs(v_pre) <= SEARCH_STATE_BOUND)
                    & (np.abs(u) <= SEARCH_STATE_BOUND))
            if bad.any():
                return k, int(np.flatnonzero(bad)[0])
            np.minimum(v_min, v, out=v_min)
            np.minimum(u_min, u, out=u_min)
            np.maximum(u_max, u, out=u_max)
            np.maximum(v_pre_max, v_pre, out=v_pre_max)
    return v_min, u_min, u_max, v_pre_max


# the compiled search: stimulus kinds, the rows of its stimuli's constants
_KINDS = {"const": 0, "step": 1, "square": 2, "ramp": 3}
(_LO, _HI, _SLOPE, _THR) = range(4)
_SEARCH: dict = {}


if kernel_available():
    # the compiled search loop (numba) around the golden model's compiled block step; at
    # module level (not closures), so that numba's disk cache finds it again
    from numba import njit

    from ...golden.izhikevich_kernel import BLOCK as B
    from ...golden.izhikevich_kernel import block_kernel
    _block_steps = block_kernel()

    @njit(nogil=True, cache=True)
    def run(w, st, n, steps, ramps, gper, gthr, gptr, gcols, periods, whole, n_steps, half_k, dt, P,
            std_u, vth, bound, flags, rem, quot, state):
        """Every step of the ``n`` trajectories held in ``w`` (one parameter set ``P``) under
        their stimuli (constants in ``st``'s rows), generated per step as
        :func:`_battery_rows` does (same operations, same bits); the extremes kept in ``w``'s
        rows ``W_P`` on (the block step's ``track``). A stimulus is written when it changes: a
        square wave's columns (``gcols``, per (period, threshold) group: ``gper``, ``gthr``)
        when its comparison flips. ``t % p`` is the exact remainder (:func:`math.fmod`'s,
        ``t >= 0``); for a whole period ``p`` it is ``t - n p`` with the quotient ``n`` kept
        from step to step (``t`` only grows): ``n p`` is a whole number and ``t - n p``, a
        multiple of ``t``'s last place no larger than ``max(t, 2 p)``, is representable, so
        exact. Returns -1, or the first step at which a state left the bound."""
        for c in range(n):
            w[2 * B + c] = st[_LO * B + c]
        for g in range(gper.shape[0]):
            state[g] = False
        for k in range(n_steps):
            t = k * dt
            for j in range(periods.shape[0]):
                p = periods[j]
                if whole[j]:
                    while t - quot[j] * p >= p:
                        quot[j] += 1.0
                    rem[j] = t - quot[j] * p
                else:
                    rem[j] = t % p
            for g in range(gper.shape[0]):
                up = rem[gper[g]] < gthr[g]
                if up != state[g] or k == 0:
                    state[g] = up
                    for q in range(gptr[g], gptr[g + 1]):
                        c = gcols[q]
                        w[2 * B + c] = st[_HI * B + c] if up else st[_LO * B + c]
            if k == half_k:
                for c in steps:
                    w[2 * B + c] = st[_HI * B + c]
            last = k == n_steps - 1
            for c in ramps:
                w[2 * B + c] = st[_HI * B + c] if last else \
                    float(k) * st[_SLOPE * B + c] + st[_LO * B + c]
            _, nbad = _block_steps(w, flags, n, P, True, std_u, False, dt, dt, vth, bound, True)
            if nbad:
                return k
        return -1

    _SEARCH["run"] = run
    _SEARCH["block"] = B


def _search_kernel():
    """The compiled search loop."""
    return _SEARCH["run"]


def _search_compiled(sets, cols_set, v, u, battery, n_steps: int, dt: float,
                     threads: int | None = None):
    """:func:`_search_numpy` by the compiled loop: the same operations in the same order per
    trajectory (so the same extremes to the bit), a parameter set's trajectories in blocks
    (each kept in L1 and run through every step), the blocks split over ``threads``
    (default: every core, at most 2)."""
    import os
    from concurrent.futures import ThreadPoolExecutor

    from ...golden.izhikevich_kernel import W_P, W_ROWS, W_U, W_V
    run = _search_kernel()
    B = _SEARCH["block"]
    n_stim = len(battery)
    periods = sorted({a[2] for _, kind, a in battery if kind == "square"})
    kind = np.array([_KINDS[b[1]] for b in battery], dtype=np.int64)
    rows = np.zeros((4, n_stim))                   # the stimuli's constants
    pidx = np.zeros(n_stim, dtype=np.int64)
    for c, (_, kd, a) in enumerate(battery):
        if kd == "const":
            rows[_LO, c] = rows[_HI, c] = a[0]
        elif kd == "step":
            rows[_LO, c], rows[_HI, c] = a
        elif kd == "square":
            rows[_LO, c], rows[_HI, c], period, duty = a
            pidx[c], rows[_THR, c] = periods.index(period), duty * period
        else:
            rows[_LO, c], rows[_HI, c] = a
            if n_steps > 1:
                rows[_SLOPE, c] = (a[1] - a[0]) / (n_steps - 1)
            else:
                rows[_HI, c] = a[0]
    periods = np.array(periods or [1.0])
    whole = np.array([p == int(p) and n_steps * dt < 2.0 ** 40 for p in periods])
    n_rep = len(cols_set) // n_stim
    rows = np.tile(rows, n_rep)
    kind, pidx = np.tile(kind, n_rep), np.tile(pidx, n_rep)
    threads = threads or min(os.cpu_count() or 1, 2)
    jobs = []                                     # (set, first column, columns) of <= B
    for si, s in enumerate(sets):
        cols = np.flatnonzero(cols_set == si)
        parts = max(threads, -(-cols.size // B))
        edges = np.linspace(cols[0], cols[-1] + 1, parts + 1).astype(int)
        jobs += [(s, a, b - a) for a, b in zip(edges[:-1], edges[1:]) if b > a]

    def job(j):
        s, a, n = j
        P = ((s.a, s.b, s.c, s.d, s.A, s.B, s.C, s.u_leak, s.v_u),)
        std_u = s.u_leak == 1.0 and s.v_u == 0.0
        w, st = np.zeros((W_ROWS, B)), np.zeros((4, B))
        w[W_V, :n], w[W_U, :n] = v[a:a + n], u[a:a + n]
        w[W_P:W_P + 4, :n] = v[a:a + n], u[a:a + n], u[a:a + n], v[a:a + n]
        st[:, :n] = rows[:, a:a + n]
        # the square waves' columns by (period, threshold)
        sq = np.flatnonzero(kind[a:a + n] == _KINDS["square"]).tolist()
        keys = sorted({(int(pidx[a + c]), float(st[_THR, c])) for c in sq})
        members = [[c for c in sq if (pidx[a + c], st[_THR, c]) == key] for key in keys]
        gptr = np.cumsum([0] + [len(m) for m in members]).astype(np.int64)
        gcols = np.array([c for m in members for c in m], dtype=np.int64)
        gper = np.array([p for p, _ in keys], dtype=np.int64)
        gthr = np.array([t for _, t in keys], dtype=np.float64)
        kd = kind[a:a + n]
        k = run(w.reshape(-1), st.reshape(-1), n,
                np.flatnonzero(kd == _KINDS["step"]), np.flatnonzero(kd == _KINDS["ramp"]),
                gper, gthr, gptr, gcols, periods, whole, n_steps, n_steps // 2, float(dt), P,
                std_u, golden.V_TH, SEARCH_STATE_BOUND, np.zeros(B, np.bool_),
                np.empty(len(periods)), np.zeros(len(periods)), np.zeros(len(keys), np.bool_))
        if k >= 0:
            bad = ~((np.abs(w[3, :n]) <= SEARCH_STATE_BOUND)
                    & (np.abs(w[1, :n]) <= SEARCH_STATE_BOUND))
            return k, a + int(np.flatnonzero(bad)[0]), None
        return -1, a, w[W_P:W_P + 4, :n]
    if len(jobs) == 1:
        results = [job(jobs[0])]
    else:
        with ThreadPoolExecutor(min(threads, len(jobs))) as pool:
            results = list(pool.map(job, jobs))
    bad = [(k, c) for k, c, _ in results if k >= 0]
    if bad:
        return min(bad)
    ext = np.concatenate([r[2] for r in results], axis=1)
    return ext[0], ext[1], ext[2], ext[3]


def one_step_bound(cfg, v, u, I, sel=None):
    """Upper bounds (mV) on |v' - v'_golden| and |u' - u'_golden| for one update of the core
    configured by ``cfg`` from the state ``(v, u)`` (floats, exactly representable) with input
    ``I`` (inside the accepted range), before reset, for neurons of parameter sets ``sel``
    (default: the worst set).

    Sum of every rounding and representation error of the datapath, each at its worst:
    operand roundings (half an LSB, or one LSB when truncating), constant errors, the
    rounded completing-the-square offset, and the alignments into the state formats.
    """
    v, u, I = (np.asarray(x, dtype=np.float64) for x in (v, u, I))
    half = 0.5 if cfg.rounding == "nearest" else 1.0
    eW, eQ, eV, eU, eY = (half * f.lsb for f in (cfg.W, cfg.Q, cfg.V, cfg.U, cfg.Y))
    eVQ = half * cfg.VQ.lsb
    dt = cfg.dt_ms

    def per(values, reduce=max):
        arr = np.asarray(values, dtype=np.float64)
        if sel is None:
            return reduce(arr)
        return arr[np.asarray(sel, dtype=np.int64)]
    P = cfg.params
    woff = per([w.quantized for w in cfg.woff], reduce=lambda a: a[np.argmax(np.abs(a))])
    ka = per([k.quantized for k in cfg.KA])
    dka = per([abs(k.abs_error) for k in cfg.KA])
    dB = per([abs(2 * p.A * w.quantized - p.B) for p, w in zip(P, cfg.woff)])
    dK0 = per([abs(k.abs_error) for k in cfg.K0])
    same = len({w.raw for w in cfg.woff}) == 1
    w = np.abs(v + woff) if (sel is not None or same) else np.abs(v) + np.abs(woff)
    bound_v = (dka * w * w + ka * (2 * w * eW + eW * eW) + eQ * (w + eW) + eV + dK0
               + dt * dB * np.abs(v))
    if cfg.dt_shift is not None:
        bound_v = bound_v + eV                           # dt*u alignment (dt*I is exact)
    else:
        eX = half * cfg.X.lsb
        kd, dkd = cfg.KDT.quantized, abs(cfg.KDT.abs_error)
        bound_v = bound_v + dkd * np.abs(I - u) + kd * (eX + eU) + eV
    bq = per([abs(b.quantized) for b in cfg.beta])
    db = per([abs(b.abs_error) for b in cfg.beta])
    aq = per([abs(a.quantized) for a in cfg.alpha])
    da = per([abs(a.abs_error) for a in cfg.alpha])
    dE = per([abs(e.abs_error) for e in cfg.E])
    vu = per([abs(p.v_u) for p in P])
    lam = per([p.u_leak for p in P])
    ey = bq * eVQ + db * (np.abs(v) + vu) + dE + eU + eY
    bound_u = aq * ey + da * (bq * (np.abs(v) + vu) + lam * np.abs(u)) + eU
    # on a spike v is replaced by c and u gets d: their representation errors
    bound_v = bound_v + per([abs(c.abs_error) for c in cfg.c])
    bound_u = bound_u + per([abs(d.abs_error) for d in cfg.d])
    return bound_v + 1e-9, bound_u + 1e-9
