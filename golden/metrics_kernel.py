"""The compiled (numba) Victor-Purpura distance matrix: the dynamic programme of
:func:`cuneate.golden.metrics.victor_purpura` (``D[i, j] = min(D[i-1, j] + 1, D[i, j-1] + 1,
D[i-1, j-1] + q |a_i - b_j|)``, one row held), one pair per iteration of a parallel loop over
the pairs of the upper triangle. Spike times are read from one flat array with offsets, so a
matrix of thousands of trains costs one call."""

from __future__ import annotations

import numpy as np

__all__ = ["vp_matrix_compiled", "vp_cross_compiled"]

_KERNEL: dict = {}


def _kernels():
    if _KERNEL:
        return _KERNEL
    from numba import njit, prange

    @njit(nogil=True, cache=True)
    def pair(flat, a0, a1, b0, b1, q, inf_q, row):
        n, m = a1 - a0, b1 - b0
        if n == 0:
            return float(m)
        if m == 0:
            return float(n)
        for j in range(m + 1):
            row[j] = j
        for i in range(1, n + 1):
            diag = row[0]
            row[0] = i
            ai = flat[a0 + i - 1]
            for j in range(1, m + 1):
                up = row[j]
                d = ai - flat[b0 + j - 1]
                if d < 0:
                    d = -d
                if inf_q:
                    shift = diag if d == 0.0 else np.inf
                else:
                    shift = diag + q * d
                x = up + 1.0
                left = row[j - 1] + 1.0
                if left < x:
                    x = left
                if shift < x:
                    x = shift
                diag = up
                row[j] = x
        return row[m]

    @njit(parallel=True, cache=True)
    def matrix(flat, off, pi, pj, q, inf_q, longest, out):
        for p in prange(pi.size):
            i, j = pi[p], pj[p]
            row = np.empty(longest + 1)
            # the row runs over the shorter train (the distance is symmetric)
            if off[i + 1] - off[i] >= off[j + 1] - off[j]:
                d = pair(flat, off[i], off[i + 1], off[j], off[j + 1], q, inf_q, row)
            else:
                d = pair(flat, off[j], off[j + 1], off[i], off[i + 1], q, inf_q, row)
            out[i, j] = d
            out[j, i] = d

    @njit(parallel=True, cache=True)
    def cross(flat, off, n_a, q, inf_q, longest, out):
        n_b = off.size - 1 - n_a
        for p in prange(n_a * n_b):
            i, j = p // n_b, n_a + p % n_b
            row = np.empty(longest + 1)
            if off[i + 1] - off[i] >= off[j + 1] - off[j]:
                out[i, j - n_a] = pair(flat, off[i], off[i + 1], off[j], off[j + 1], q, inf_q,
                                       row)
            else:
                out[i, j - n_a] = pair(flat, off[j], off[j + 1], off[i], off[i + 1], q, inf_q,
                                       row)

    _KERNEL.update(matrix=matrix, cross=cross)
    return _KERNEL


def _flat(trains):
    lens = np.array([len(t) for t in trains], dtype=np.int64)
    off = np.zeros(lens.size + 1, dtype=np.int64)
    np.cumsum(lens, out=off[1:])
    flat = np.concatenate([np.asarray(t, dtype=np.float64) for t in trains]) if lens.sum() \
        else np.zeros(0)
    return flat, off, int(lens.max()) if lens.size else 0


def vp_matrix_compiled(trains, q_per_ms: float) -> np.ndarray:
    """The symmetric matrix of Victor-Purpura distances of validated, sorted ``trains``."""
    flat, off, longest = _flat(trains)
    k = len(trains)
    pi, pj = np.triu_indices(k, 1)
    out = np.zeros((k, k))
    inf_q = bool(np.isinf(q_per_ms))
    _kernels()["matrix"](flat, off, pi.astype(np.int64), pj.astype(np.int64),
                         0.0 if inf_q else float(q_per_ms), inf_q, longest, out)
    return out


def vp_cross_compiled(a_trains, b_trains, q_per_ms: float) -> np.ndarray:
    """``(len(a), len(b))``: the distance of every train of ``a_trains`` to every one of
    ``b_trains``."""
    flat, off, longest = _flat(list(a_trains) + list(b_trains))
    out = np.zeros((len(a_trains), len(b_trains)))
    inf_q = bool(np.isinf(q_per_ms))
    _kernels()["cross"](flat, off, len(a_trains), 0.0 if inf_q else float(q_per_ms), inf_q,
                        longest, out)
    return out
