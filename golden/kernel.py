"""Compiled-loop (numba) helpers shared by the golden models' loops and the twins' kernels.

:func:`available` says whether numba is importable (every compiled loop has a NumPy fallback);
:func:`record` appends the neurons a sweep flagged to a spike buffer; :func:`split_over_threads`
runs a GIL-free loop on contiguous slices of a population and joins the slices' spikes. The
twins (``cuneate.hdl.*.kernel``) build on these; they live here, at the bottom of the layers,
because the golden models use them too.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

__all__ = ["available", "record", "record_presentation", "split_over_threads", "thread_slices",
           "by_neuron", "BLOCK", "open_block", "close_block"]

#: neurons a compiled loop keeps in L1 and takes through every step of a run at a time: their
#: state and inputs in one scratch array of rows ``BLOCK`` long (constant row offsets, so the
#: compiler sees the rows cannot overlap and the loop over the block vectorizes)
BLOCK = 512

try:                                   # numba is a dependency; keep the models usable without it
    import numba
    from numba import njit
except ImportError:                    # pragma: no cover
    numba = None


def available() -> bool:
    """True when numba is importable (the compiled loops can be used)."""
    return numba is not None


if numba is not None:
    @njit(nogil=True, cache=True)
    def record(flags, fwords, k, spk_k, spk_n, n_spk, offset=0):
        """Append the neurons flagged in ``flags`` (bool, length a multiple of 8; ``fwords``
        its uint64 view, so words that are all zero are skipped), numbered from ``offset``,
        as spikes of step ``k`` to ``(spk_k, spk_n)`` from position ``n_spk``; returns the new
        count."""
        for w in range(fwords.shape[0]):
            if fwords[w]:
                for i in range(8 * w, 8 * w + 8):
                    if flags[i]:
                        spk_k[n_spk] = k
                        spk_n[n_spk] = offset + i
                        n_spk += 1
        return n_spk

    @njit(nogil=True, cache=True, inline="always")
    def record_presentation(hit, M, q, k, win, sp_p, sp_k, sp_j, n_sp, counts):
        """Append the targets ``j < M`` with ``hit[j]`` as spikes of presentation ``q``'s tick
        ``k`` to ``(sp_p, sp_k, sp_j)`` from position ``n_sp``, counting those of ticks before
        ``win`` in ``counts[q, j]``; returns the new count, -1 once the buffers are full."""
        for j in range(M):
            if hit[j]:
                if n_sp == sp_p.shape[0]:
                    return -1
                sp_p[n_sp] = q
                sp_k[n_sp] = k
                sp_j[n_sp] = j
                n_sp += 1
                if k < win:
                    counts[q, j] += 1
        return n_sp

    @njit(nogil=True, cache=True, inline="always")
    def open_block(w, flags, v, u, lo, n):
        """Neurons ``lo .. lo + n - 1`` into a block: v and u into rows 0 and 1 of the
        scratch ``w``, the spike flags past ``n`` cleared."""
        for i in range(n):
            w[i] = v[lo + i]
            w[BLOCK + i] = u[lo + i]
        for i in range(n, BLOCK):
            flags[i] = False

    @njit(nogil=True, cache=True, inline="always")
    def close_block(w, v, u, lo, n):
        """A block's v and u (rows 0 and 1 of ``w``) back to neurons ``lo ..``."""
        for i in range(n):
            v[lo + i] = w[i]
            u[lo + i] = w[BLOCK + i]

    @njit(nogil=True, cache=True)
    def _count_sort(ks, ns, n):
        """Stable counting sort of ``ks`` by ``ns`` (0 <= ns < n): (sorted ks, bounds)."""
        bounds = np.zeros(n + 1, np.int64)
        for j in range(ns.shape[0]):
            bounds[ns[j] + 1] += 1
        for i in range(n):
            bounds[i + 1] += bounds[i]
        pos = bounds[:-1].copy()
        out = np.empty_like(ks)
        for j in range(ns.shape[0]):
            out[pos[ns[j]]] = ks[j]
            pos[ns[j]] += 1
        return out, bounds
else:                                  # pragma: no cover
    record = _count_sort = open_block = close_block = None


def by_neuron(ks: np.ndarray, ns: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Spikes (step ``ks[j]`` of neuron ``ns[j]``) grouped by neuron, each neuron's steps in
    increasing order: ``(steps, bounds)`` with neuron ``i``'s at ``steps[bounds[i]:bounds[i +
    1]]``. A stable counting sort by neuron (linear); a producer that gave some neuron's
    spikes out of step order is sorted by (neuron, step) instead."""
    ks = np.ascontiguousarray(ks, dtype=np.int64)
    ns = np.ascontiguousarray(ns, dtype=np.int64)
    if _count_sort is not None:
        out, bounds = _count_sort(ks, ns, n)
    else:                              # pragma: no cover
        order = np.argsort(ns, kind="stable")
        out, bounds = ks[order], np.searchsorted(ns[order], np.arange(n + 1))
    if out.size > 1:
        first = np.zeros(out.size, bool)
        first[bounds[:-1][bounds[:-1] < out.size]] = True
        if np.any((np.diff(out) <= 0) & ~first[1:]):
            order = np.lexsort((ks, ns))
            out = ks[order]
    return out, bounds


def thread_slices(n: int, threads: int) -> list[tuple[int, int]]:
    """``threads`` contiguous ``(lo, hi)`` slices covering ``0 .. n``."""
    if threads <= 1:
        return [(0, n)]
    edges = np.linspace(0, n, threads + 1).astype(int)
    return list(zip(edges[:-1].tolist(), edges[1:].tolist()))


def split_over_threads(chunk, n: int, threads: int) -> list:
    """Run ``chunk(lo, hi)`` on ``threads`` contiguous slices of ``n`` neurons (one call when
    ``threads == 1``, else a thread pool: the loops release the GIL); returns the chunks'
    results in slice order."""
    slices = thread_slices(n, threads)
    if len(slices) == 1:
        return [chunk(0, n)]
    with ThreadPoolExecutor(len(slices)) as pool:
        return list(pool.map(lambda s: chunk(*s), slices))
