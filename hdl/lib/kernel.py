"""Compiled-loop (numba) helpers shared by the twins' kernels.

Each twin has a kernel (``cuneate.hdl.<block>.kernel``) that restates its block's stage
functions per neuron, in the same order, as one compiled loop. What every kernel needs is here:
the branch-free rounding shift (:func:`rq`, constants as four slots from
:func:`rounding_slots`), constants as nested tuples (:func:`as_tuples`: the loop keeps them in
registers), thread counts, and the join of per-thread spike buffers.
"""

from __future__ import annotations

import os

import numpy as np

from ...golden import kernel as gk
from ...golden.kernel import BLOCK, available, close_block, open_block, record

__all__ = ["available", "choose_kernel", "record", "BLOCK", "open_block", "close_block", "rs", "rq", "rounding_slots", "as_tuples", "default_threads",
           "split_over_threads", "trace_table", "trace_step", "PARALLEL_MIN_NEURONS",
           "INT64_MIN", "INT64_MAX", "TR_Y", "TR_K", "TR_P", "N_TRACE_COLS"]

#: Below this many neurons a sweep is too short for threads to pay (measured on 2 cores: from
#: 2500 neurons on, two threads give 1.7-1.8x).
PARALLEL_MIN_NEURONS = 2_000
INT64_MIN, INT64_MAX = -(1 << 63), (1 << 63) - 1
# synaptic trace table columns: operand rounding (4), k, product rounding (4)
TR_Y, TR_K, TR_P = 0, 4, 5
N_TRACE_COLS = 9

if available():
    from numba import njit

    _jit = dict(nogil=True, cache=True, error_model="numpy")

    @njit(inline="always", **_jit)
    def rs(x, s, near):
        """round_shift(x, s): rounding to nearest (ties up) or truncation; s <= 0 shifts left."""
        if s <= 0:
            return x << (-s)
        r = x >> s
        if near:
            r += (x >> (s - 1)) & 1
        return r

    @njit(inline="always", **_jit)
    def rq(x, sc, j):
        """round_shift(x, shift) without branches: ``(x << ls) >> rs`` plus, when rounding
        to nearest and rs > 0, the first dropped bit (slots j .. j+3 of ``sc``)."""
        y = x << sc[j]
        return (y >> sc[j + 1]) + ((y >> sc[j + 2]) & sc[j + 3])

    @njit(inline="always", **_jit)
    def trace_step(y, ttab, j):
        """``y - round(k round(y))`` of synaptic trace ``j`` (``trace_products`` +
        ``trace_update`` of :mod:`cuneate.hdl.lib.synapses`)."""
        yq = rq(y, ttab[j], TR_Y)
        return y - rq(yq * ttab[j][TR_K], ttab[j], TR_P)
else:                                  # pragma: no cover
    rs = rq = trace_step = None


def choose_kernel(kernel: str | None, known: tuple, numba_default: bool = True) -> str:
    """A twin's kernel: ``kernel`` (one of ``known``; ``"numba"`` refused without numba), or
    for None ``"numba"`` when numba is available and ``numba_default``, else ``"stages"``."""
    if kernel is not None and kernel not in known:
        raise ValueError(f"unknown twin kernel {kernel!r}; known: {', '.join(known)}")
    if kernel == "numba" and not available():
        raise ValueError("twin kernel 'numba' needs numba installed")
    return kernel or ("numba" if available() and numba_default else "stages")


def rounding_slots(shift: int, near: bool) -> list[int]:
    """The four kernel slots of ``round_shift(x, shift)`` (see :func:`rq`): left shift, right
    shift, the shift that brings the first dropped bit to bit 0, and its mask (0 when
    truncating or not shifting right)."""
    r = max(shift, 0)
    return [max(-shift, 0), r, max(r - 1, 0), int(near and r > 0)]


def as_tuples(a: np.ndarray) -> tuple:
    """Constants as (nested) tuples of ints: the compiled loop keeps them in registers (an
    array could alias the state being written, so its loads would stay in the loop)."""
    a = np.asarray(a)
    if a.ndim == 1:
        return tuple(int(x) for x in a)
    return tuple(as_tuples(row) for row in a)


def default_threads(n_neurons: int) -> int:
    """Threads a kernel uses by default: all cores for large populations, else 1."""
    if n_neurons < PARALLEL_MIN_NEURONS:
        return 1
    return max(1, min(os.cpu_count() or 1, n_neurons // (PARALLEL_MIN_NEURONS // 2)))


def split_over_threads(chunk, n: int, threads: int):
    """Run ``chunk(lo, hi)`` on ``threads`` contiguous slices of ``n`` neurons and join the
    results: each chunk returns ``(spike_sweeps, spike_neurons, totals, last)`` with neuron
    indices already offset by ``lo``."""
    parts = gk.split_over_threads(chunk, n, threads)
    return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
            sum(p[2] for p in parts), sum(p[3] for p in parts))


def trace_table(specs, v_frac_bits: int, near: bool) -> np.ndarray:
    """Kernel table of synaptic traces (:class:`cuneate.hdl.lib.synapses.TraceSpec`), one row
    per trace (a dummy row when there are none)."""
    rows = [rounding_slots(v_frac_bits - s.Y.frac_bits, near) + [s.K.raw]
            + rounding_slots(s.product_shift, near) for s in specs]
    return np.array(rows or [[0] * N_TRACE_COLS], dtype=np.int64)
