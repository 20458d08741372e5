"""Spike-train metrics used to compare the golden model with the fixed-point engines.

A *spike train* is a 1-D sequence of spike times in **milliseconds**, finite and sorted
ascending (equal neighbouring times are allowed). Every public function validates its trains
and raises :class:`ValueError` naming the argument and the problem (not 1-D, not finite, not
sorted). All arithmetic is float64 NumPy.

Undefined quantities (latency of an empty train, ISI statistics of fewer than two spikes, a
fraction of zero spikes, errors of zero matched pairs) are reported as ``None``, never NaN.

Contents
--------
* counts and latency: :func:`spike_count_difference`, :func:`first_spike_latency_difference`;
* spike matching: :func:`matched_spike_errors`, :func:`fraction_within`;
* distances: :func:`victor_purpura` (+ :func:`victor_purpura_matrix`), :func:`van_rossum`;
* firing statistics: :func:`isi_stats`;
* reports: :func:`compare_trains`, :func:`compare_populations`.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "spike_count_difference",
    "first_spike_latency_difference",
    "matched_spike_errors",
    "fraction_within",
    "victor_purpura",
    "victor_purpura_matrix",
    "van_rossum",
    "isi_stats",
    "compare_trains",
    "compare_populations",
    "VP_Q_PER_MS",
]

#: The Victor-Purpura cost of moving a spike used for every figure the project reports:
#: q = 5/s (moving a spike by 200 ms costs as much as deleting it).
VP_Q_PER_MS = 0.005

# Tolerance factor turning a tick ``dt_ms`` into the "within +-1 tick" window, so that an error
# of exactly one tick computed in floating point still counts.
TICK_TOLERANCE = 1.0 + 1e-9

# Bound on the number of float64 kernel entries held at once by van Rossum's pair sums.
_PAIR_CHUNK = 1 << 22


# --------------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------------


def _train(x: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return ``x`` as a validated float64 spike train (1-D, finite, sorted ascending)."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: spike times must be numbers in ms ({exc})") from None
    if arr.ndim != 1:
        raise ValueError(f"{name}: spike train must be 1-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise ValueError(f"{name}: spike times must be finite, got {arr[bad]} at index {bad}")
    if arr.size > 1 and np.any(np.diff(arr) < 0):
        bad = int(np.flatnonzero(np.diff(arr) < 0)[0])
        raise ValueError(
            f"{name}: spike times must be sorted ascending, "
            f"got {arr[bad]} then {arr[bad + 1]} at index {bad}"
        )
    return arr


def _positive(
    value: float, name: str, *, allow_inf: bool = False, allow_zero: bool = False
) -> float:
    """Return ``value`` as a float after checking it is positive (optionally 0 or inf)."""
    v = float(value)
    if np.isnan(v) or v < 0 or (v == 0 and not allow_zero) or (np.isinf(v) and not allow_inf):
        allowed = "[0" if allow_zero else "(0"
        allowed += ", inf]" if allow_inf else ", inf)"
        raise ValueError(f"{name} must be in {allowed}, got {value!r}")
    return v


# --------------------------------------------------------------------------------------------
# counts and latency
# --------------------------------------------------------------------------------------------


def spike_count_difference(a_ms: ArrayLike, b_ms: ArrayLike) -> int:
    """Signed difference of spike counts, ``len(b) - len(a)``.

    Parameters
    ----------
    a_ms, b_ms : array_like
        Spike trains, spike times in ms (1-D, finite, sorted ascending).

    Returns
    -------
    int
        Number of spikes of ``b`` minus number of spikes of ``a`` (positive when ``b`` fires more).
    """
    return int(_train(b_ms, "b_ms").size - _train(a_ms, "a_ms").size)


def first_spike_latency_difference(a_ms: ArrayLike, b_ms: ArrayLike) -> float | None:
    """Difference of first-spike latencies, ``b[0] - a[0]``, in ms, of two spike trains (times
    in ms, 1-D, finite, sorted ascending).

    Returns
    -------
    float or None
        ``b[0] - a[0]`` in ms (positive when ``b`` fires later), or ``None`` if either train is
        empty (the latency is then undefined; NaN is never returned).
    """
    a, b = _train(a_ms, "a_ms"), _train(b_ms, "b_ms")
    if a.size == 0 or b.size == 0:
        return None
    return float(b[0] - a[0])


# --------------------------------------------------------------------------------------------
# spike matching
# --------------------------------------------------------------------------------------------


def _match(
    a: NDArray[np.float64], b: NDArray[np.float64], max_shift: float
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Indices ``(ia, ib)`` of the optimal monotone matching of sorted trains ``a`` and ``b``.

    Dynamic programme over prefixes: the value of cell ``(i, j)`` is the lexicographically best
    pair (most matched pairs, then least total ``|dt|``) for ``a[:i]`` and ``b[:j]``. Rows are
    filled one at a time; the diagonal/up choice is vectorized and the left-to-right propagation
    (skipping spikes of ``b``, which costs nothing) is a running maximum of an exact integer key
    ``count * (m + 1) + cost_rank``, where ``cost_rank`` ranks the row's costs (lower cost =>
    higher rank). A move table (1 = pair, 2 = skip a, 3 = skip b) is kept for the traceback.
    """
    n, m = a.size, b.size
    if n == 0 or m == 0:
        return np.empty(0, np.intp), np.empty(0, np.intp)
    width = m + 1
    count = np.zeros(width, np.int64)
    cost = np.zeros(width)
    move = np.full((n + 1, width), 2, np.int8)
    move[0, :] = 3
    for i in range(1, n + 1):
        d = np.abs(b - a[i - 1])
        d_count, d_cost = count[:-1] + 1, cost[:-1] + d
        u_count, u_cost = count[1:], cost[1:]
        better = (d_count > u_count) | ((d_count == u_count) & (d_cost <= u_cost))
        diag = (d <= max_shift) & better
        c_count = np.concatenate(([0], np.where(diag, d_count, u_count)))
        c_cost = np.concatenate(([0.0], np.where(diag, d_cost, u_cost)))
        order = np.argsort(c_cost, kind="stable")
        rank = np.empty(width, np.int64)
        rank[order] = np.arange(width - 1, -1, -1)
        key = c_count * width + rank
        best = np.maximum.accumulate(key)
        count = best // width
        cost = c_cost[order[width - 1 - best % width]]
        move[i, 1:] = np.where(diag, 1, 2)
        move[i, best > key] = 3
    ia, ib = [], []
    i, j = n, m
    while i > 0 and j > 0:
        mv = move[i, j]
        if mv == 1:
            ia.append(i - 1)
            ib.append(j - 1)
        i -= int(mv != 3)
        j -= int(mv != 2)
    return np.array(ia[::-1], np.intp), np.array(ib[::-1], np.intp)


def matched_spike_errors(
    a_ms: ArrayLike, b_ms: ArrayLike, max_shift_ms: float | None = None
) -> NDArray[np.float64]:
    """Timing errors ``b - a`` of optimally matched spike pairs, in ms.

    Matching rule: spikes are paired one-to-one and *in order* (if ``a[i]`` pairs with ``b[j]``
    and ``a[k]`` with ``b[l]``, then ``i < k`` iff ``j < l``); a pair is allowed only if
    ``|b[j] - a[i]| <= max_shift_ms``; spikes may stay unmatched. Among all such matchings the
    one with the **most pairs** is chosen and, among those, the one with the **least total
    |b - a|**. It is found exactly by an O(n m) dynamic programme (row-vectorized).

    Parameters
    ----------
    a_ms, b_ms : array_like
        Spike trains, spike times in ms (1-D, finite, sorted ascending); ``a`` is the reference.
    max_shift_ms : float, optional
        Largest allowed ``|b - a|`` of a pair, in ms (>= 0). ``None`` (default) means unbounded:
        then exactly ``min(len(a), len(b))`` pairs are formed.

    Returns
    -------
    numpy.ndarray of float64
        ``b_matched - a_matched`` in ms, one entry per pair, in spike order (empty if none).
    """
    a, b = _train(a_ms, "a_ms"), _train(b_ms, "b_ms")
    shift = (
        np.inf
        if max_shift_ms is None
        else _positive(max_shift_ms, "max_shift_ms", allow_inf=True, allow_zero=True)
    )
    ia, ib = _match(a, b, shift)
    return b[ib] - a[ia]


def fraction_within(a_ms: ArrayLike, b_ms: ArrayLike, tol_ms: float) -> float | None:
    """Fraction of the spikes of ``a`` that have a matched partner in ``b`` within ``tol_ms``.

    Uses the matching of :func:`matched_spike_errors` with ``max_shift_ms=tol_ms``, i.e. the
    largest number of in-order one-to-one pairs with ``|b - a| <= tol_ms``. For the "within
    +-1 tick" figure pass ``tol_ms = dt_ms * (1 + 1e-9)`` (see :func:`compare_trains`).

    Parameters
    ----------
    a_ms, b_ms : array_like
        Spike trains, spike times in ms (1-D, finite, sorted ascending); ``a`` is the reference.
    tol_ms : float
        Matching window half-width in ms (>= 0).

    Returns
    -------
    float or None
        ``n_matched / len(a)`` in [0, 1], or ``None`` if ``a`` is empty.
    """
    a = _train(a_ms, "a_ms")
    if a.size == 0:
        _train(b_ms, "b_ms")
        return None
    return matched_spike_errors(a, b_ms, tol_ms).size / a.size


# --------------------------------------------------------------------------------------------
# Victor-Purpura
# --------------------------------------------------------------------------------------------


def victor_purpura(a_ms: ArrayLike, b_ms: ArrayLike, q_per_ms: float) -> float:
    """Victor-Purpura spike-time distance (Victor & Purpura 1996, ``D^spike[q]``).

    The minimal total cost of turning ``a`` into ``b`` by deleting or inserting spikes (cost 1
    each) and shifting spikes (cost ``q * |dt|``). Computed by the O(n m) dynamic programme
    ``D[i, j] = min(D[i-1, j] + 1, D[i, j-1] + 1, D[i-1, j-1] + q |a_i - b_j|)`` with
    ``D[i, 0] = i`` and ``D[0, j] = j``, one row at a time: the up/diagonal candidates are
    vectorized and the left-to-right ``+1`` chain is ``minimum.accumulate(cand - j) + j``.

    Parameters
    ----------
    a_ms, b_ms : array_like
        Spike trains, spike times in ms (1-D, finite, sorted ascending).
    q_per_ms : float
        Cost per ms of shift, in 1/ms, in ``[0, inf]``. ``q = 0`` gives ``|len(a) - len(b)|``;
        ``q = inf`` forbids shifting except between exactly coincident spikes (which then cost
        0), giving ``len(a) + len(b) - 2 * (number of coincident pairs)``. Shifts longer than
        ``2 / q`` ms are never used (delete + insert is cheaper). Elephant's ``cost_factor`` is
        the same quantity: ``q_per_ms = cost_factor_in_Hz / 1000``.

    Returns
    -------
    float
        Dimensionless distance (>= 0).
    """
    a, b = _train(a_ms, "a_ms"), _train(b_ms, "b_ms")
    q = _positive(q_per_ms, "q_per_ms", allow_inf=True, allow_zero=True)
    if a.size < b.size:  # the row loop runs over the shorter train
        a, b = b, a
    n, m = a.size, b.size
    if m == 0:
        return float(n)
    j = np.arange(m + 1, dtype=np.float64)
    row = j.copy()  # D[0, :]
    for i in range(1, n + 1):
        d = np.abs(b - a[i - 1])
        shift = np.where(d == 0, 0.0, np.inf) if np.isinf(q) else q * d  # never inf * 0
        cand = np.empty(m + 1)
        cand[0] = i
        cand[1:] = np.minimum(row[1:] + 1.0, row[:-1] + shift)
        row = np.minimum.accumulate(cand - j) + j
    return float(row[-1])


def victor_purpura_matrix(trains: Sequence[ArrayLike], q_per_ms: float) -> NDArray[np.float64]:
    """Pairwise Victor-Purpura distances of several spike trains.

    Parameters
    ----------
    trains : sequence of array_like
        Spike trains, spike times in ms (each 1-D, finite, sorted ascending).
    q_per_ms : float
        Cost per ms of shift, in 1/ms (see :func:`victor_purpura`).

    Returns
    -------
    numpy.ndarray of float64, shape (k, k)
        Symmetric matrix with zero diagonal; entry ``[i, j]`` is ``victor_purpura(trains[i],
        trains[j], q_per_ms)`` (the same dynamic programme; compiled and run over the pairs in
        parallel by :mod:`cuneate.golden.metrics_kernel` when numba is available, the minima
        then taken in another order: equal to within rounding).
    """
    ts = [_train(t, f"trains[{i}]") for i, t in enumerate(trains)]
    q = _positive(q_per_ms, "q_per_ms", allow_inf=True, allow_zero=True)
    from .kernel import available
    if available():
        from .metrics_kernel import vp_matrix_compiled
        return vp_matrix_compiled(ts, q)
    out = np.zeros((len(ts), len(ts)))
    for i in range(len(ts)):
        for k in range(i + 1, len(ts)):
            out[i, k] = out[k, i] = victor_purpura(ts[i], ts[k], q_per_ms)
    return out


# --------------------------------------------------------------------------------------------
# van Rossum
# --------------------------------------------------------------------------------------------


def _kernel_sum(x: NDArray[np.float64], y: NDArray[np.float64], tau: float) -> float:
    """``sum_{i,j} exp(-|x_i - y_j| / tau)``, in memory-bounded chunks of ``x``."""
    if x.size == 0 or y.size == 0:
        return 0.0
    step = max(1, _PAIR_CHUNK // y.size)
    chunks = (x[k : k + step, None] - y[None, :] for k in range(0, x.size, step))
    return float(sum(np.exp(-np.abs(c) / tau).sum() for c in chunks))


def van_rossum(
    a_ms: ArrayLike, b_ms: ArrayLike, tau_ms: float, dt_ms: float | None = None
) -> float:
    """Van Rossum distance (van Rossum 2001) with a causal exponential kernel.

    Each train is filtered with ``h(t) = exp(-t / tau) H(t)`` and
    ``D^2 = (1 / tau) * integral (f_a(t) - f_b(t))^2 dt``, which in closed form is::

        D^2 = 1/2 * (sum_aa + sum_bb - 2 sum_ab),   sum_xy = sum_{i,j} exp(-|x_i - y_j| / tau)

    Normalization: the paper's. One spike against an empty train gives ``D = sqrt(1/2)``; two
    single spikes far apart give ``D = 1``. Elephant's ``van_rossum_distance`` is ``sqrt(2)``
    times this value.

    Parameters
    ----------
    a_ms, b_ms : array_like
        Spike trains, spike times in ms (1-D, finite, sorted ascending).
    tau_ms : float
        Kernel time constant in ms, in ``(0, inf]``; ``inf`` gives ``|len(a) - len(b)| / sqrt(2)``.
    dt_ms : float, optional
        ``None`` (default): exact closed form above (O(n m), vectorized). A step in ms: the
        discrete-time version that samples ``f_a - f_b`` on the grid ``t0 + k dt_ms`` (``t0`` the
        first spike of either train) and integrates the exponential decay exactly between grid
        points, i.e. each spike acts from the first grid point at or after it. It equals the
        closed form when all spikes lie on the grid (e.g. engine output at tick times).

    Returns
    -------
    float
        Dimensionless distance (>= 0).
    """
    a, b = _train(a_ms, "a_ms"), _train(b_ms, "b_ms")
    tau = _positive(tau_ms, "tau_ms", allow_inf=True)
    if dt_ms is None:
        d2 = 0.5 * (_kernel_sum(a, a, tau) + _kernel_sum(b, b, tau) - 2.0 * _kernel_sum(a, b, tau))
        return float(np.sqrt(max(d2, 0.0)))
    dt = _positive(dt_ms, "dt_ms")
    if np.isinf(tau):
        return float(abs(a.size - b.size) / np.sqrt(2.0))
    if a.size + b.size == 0:
        return 0.0
    t0 = min(x[0] for x in (a, b) if x.size)
    t_end = max(x[-1] for x in (a, b) if x.size)
    n_steps = int(np.ceil((t_end - t0) / dt - 1e-9))
    x = np.zeros(n_steps + 1)  # x[k]: decayed weight of spikes in (t_{k-1}, t_k] sampled at t_k
    for train, sign in ((a, 1.0), (b, -1.0)):
        k = np.clip(np.ceil((train - t0) / dt - 1e-9).astype(np.int64), 0, n_steps)
        np.add.at(x, k, sign * np.exp(-(t0 + k * dt - train) / tau))
    from scipy.signal import lfilter

    h = lfilter([1.0], [1.0, -np.exp(-dt / tau)], x)  # f_a - f_b at the grid points
    d2 = 0.5 * (-np.expm1(-2.0 * dt / tau) * np.sum(h[:-1] ** 2) + h[-1] ** 2)
    return float(np.sqrt(d2))


# --------------------------------------------------------------------------------------------
# ISI statistics
# --------------------------------------------------------------------------------------------


def isi_stats(spikes_ms: ArrayLike, duration_ms: float | None = None) -> dict[str, Any]:
    """Inter-spike-interval statistics of one spike train.

    Parameters
    ----------
    spikes_ms : array_like
        Spike train, spike times in ms (1-D, finite, sorted ascending).
    duration_ms : float, optional
        Length of the observation window in ms (> 0), used only for the rate.

    Returns
    -------
    dict
        ``"n_spikes"`` (int); ``"mean_isi_ms"`` (float, ms); ``"std_isi_ms"`` (float, ms,
        population std, ``ddof=0``); ``"cv_isi"`` (``std / mean``, dimensionless);
        ``"rate_hz"`` (``1000 * n_spikes / duration_ms``, spikes per second). The ISI entries
        are ``None`` with fewer than 2 spikes (``cv_isi`` also when the mean ISI is 0);
        ``rate_hz`` is ``None`` when ``duration_ms`` is not given.
    """
    s = _train(spikes_ms, "spikes_ms")
    rate = None if duration_ms is None else 1000.0 * s.size / _positive(duration_ms, "duration_ms")
    out: dict[str, Any] = dict(
        n_spikes=int(s.size), mean_isi_ms=None, std_isi_ms=None, cv_isi=None, rate_hz=rate
    )
    if s.size >= 2:
        isi = np.diff(s)
        mean, std = float(isi.mean()), float(isi.std())
        out.update(mean_isi_ms=mean, std_isi_ms=std, cv_isi=std / mean if mean > 0 else None)
    return out


# --------------------------------------------------------------------------------------------
# comparison reports
# --------------------------------------------------------------------------------------------


def compare_trains(
    a_ms: ArrayLike,
    b_ms: ArrayLike,
    dt_ms: float,
    q_per_ms: float = 0.005,
    max_shift_ms: float | None = None,
) -> dict[str, Any]:
    """Summary of how spike train ``b`` (e.g. a fixed-point engine) differs from ``a`` (golden).

    Parameters
    ----------
    a_ms, b_ms : array_like
        Spike trains, spike times in ms (1-D, finite, sorted ascending); ``a`` is the reference.
    dt_ms : float
        Simulation tick in ms; "within +-1 tick" means ``|b - a| <= dt_ms * (1 + 1e-9)``.
    q_per_ms : float, default 0.005
        Victor-Purpura cost per ms of shift, in 1/ms (0.005/ms: shifts up to 400 ms are used).
    max_shift_ms : float, optional
        Window of the matching behind the error figures (see :func:`matched_spike_errors`);
        ``None`` pairs ``min(n_a, n_b)`` spikes.

    Returns
    -------
    dict
        ``n_a``, ``n_b``, ``count_difference`` (``n_b - n_a``), ``first_spike_latency_diff_ms``
        (or ``None``), ``n_matched``, ``mean_abs_error_ms`` and ``max_abs_error_ms`` over the
        matched pairs (``None`` if no pair), ``n_within_tick`` (pairs of the +-1-tick matching),
        ``fraction_within_tick`` (``n_within_tick / n_a``, ``None`` if ``n_a == 0``),
        ``vp_distance`` (Victor-Purpura at ``q_per_ms``).
    """
    a, b = _train(a_ms, "a_ms"), _train(b_ms, "b_ms")
    tol = _positive(dt_ms, "dt_ms") * TICK_TOLERANCE
    err = np.abs(matched_spike_errors(a, b, max_shift_ms))
    n_within = matched_spike_errors(a, b, tol).size
    return {
        "n_a": int(a.size),
        "n_b": int(b.size),
        "count_difference": int(b.size - a.size),
        "first_spike_latency_diff_ms": first_spike_latency_difference(a, b),
        "n_matched": int(err.size),
        "mean_abs_error_ms": float(err.mean()) if err.size else None,
        "max_abs_error_ms": float(err.max()) if err.size else None,
        "n_within_tick": int(n_within),
        "fraction_within_tick": n_within / a.size if a.size else None,
        "vp_distance": victor_purpura(a, b, q_per_ms),
    }


def compare_populations(
    list_a: Sequence[ArrayLike],
    list_b: Sequence[ArrayLike],
    dt_ms: float,
    q_per_ms: float = 0.005,
) -> dict[str, Any]:
    """Compare two populations train by train (``list_a[k]`` against ``list_b[k]``).

    Parameters
    ----------
    list_a, list_b : sequence of array_like
        Equally long lists of spike trains, spike times in ms; ``list_a`` is the reference.
    dt_ms : float
        Simulation tick in ms (see :func:`compare_trains`).
    q_per_ms : float, default 0.005
        Victor-Purpura cost per ms of shift, in 1/ms.

    Returns
    -------
    dict
        ``per_train``: list of :func:`compare_trains` dicts. Totals: ``n_trains``, ``total_a``,
        ``total_b`` (summed spike counts), ``counts_equal`` (every train has ``n_a == n_b``),
        ``fraction_within_tick`` (all spikes of ``list_a`` matched within +-1 tick over all
        spikes of ``list_a``; ``None`` if there are none), ``max_abs_error_ms`` (largest matched
        error over trains, ``None`` if no pair), ``mean_vp_distance`` (``None`` for no trains).
    """
    if len(list_a) != len(list_b):
        raise ValueError(f"populations differ in size: {len(list_a)} trains vs {len(list_b)}")
    per = [compare_trains(a, b, dt_ms, q_per_ms) for a, b in zip(list_a, list_b)]
    total_a = sum(r["n_a"] for r in per)
    errors = [r["max_abs_error_ms"] for r in per if r["max_abs_error_ms"] is not None]
    return {
        "per_train": per,
        "n_trains": len(per),
        "total_a": total_a,
        "total_b": sum(r["n_b"] for r in per),
        "counts_equal": all(r["n_a"] == r["n_b"] for r in per),
        "fraction_within_tick": sum(r["n_within_tick"] for r in per) / total_a if total_a else None,
        "max_abs_error_ms": max(errors) if errors else None,
        "mean_vp_distance": float(np.mean([r["vp_distance"] for r in per])) if per else None,
    }
