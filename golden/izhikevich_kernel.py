"""The compiled (numba) loop of the float64/float32 Izhikevich golden model: the operations of
:func:`cuneate.golden.izhikevich.step` per neuron, in the same order (no reassociation, so the
same bits), over every step of a run, the population split over threads."""

from __future__ import annotations

import os

import numpy as np

from .kernel import record, split_over_threads

__all__ = ["simulate_compiled", "PARALLEL_MIN_NEURONS", "PARALLEL_MIN_NEURONS_TABLE"]

#: a callable current: one thread dispatch per step, so threads pay only for large populations
PARALLEL_MIN_NEURONS = 50_000
#: an array current: one dispatch per run
PARALLEL_MIN_NEURONS_TABLE = 2_000


_KERNEL: dict = {}


def _golden_kernel():
    if "run" in _KERNEL:
        return _KERNEL["run"]
    from numba import njit

    @njit(nogil=True, cache=True)
    def advance(v, u, Ir, sel, P, uniform, std_u, dt, half, vth, izh, flags, vpre):
        """One step of every neuron in place: the operations of step() in its order (no
        reassociation, so the same bits), branch-free so that it vectorizes. ``P`` holds the
        distinct parameter sets as tuples (values: no aliasing with the state), ``sel`` each
        neuron's set. Returns the number of spikes (flagged in ``flags``)."""
        pa, pb, pc, pd, pA, pB, pC, plam, pvu = P
        n_hit = 0
        for i in range(v.shape[0]):
            s = 0 if uniform else sel[i]
            I = Ir[i]
            vi = v[i]
            ui = u[i]
            A_, B_, C_ = pA[s], pB[s], pC[s]
            if izh:
                vh = vi + half * (A_ * vi * vi + B_ * vi + C_ - ui + I)
                vn = vh + half * (A_ * vh * vh + B_ * vh + C_ - ui + I)
                vx = vn
            else:
                vn = vi + dt * (A_ * vi * vi + B_ * vi + C_ - ui + I)
                vx = vi
            if std_u:
                un = ui + dt * (pa[s] * (pb[s] * vx - ui))
            else:
                un = ui + dt * (pa[s] * (pb[s] * (vx - pvu[s]) - plam[s] * ui))
            hit = vn >= vth
            vpre[i] = vn
            v[i] = pc[s] if hit else vn
            u[i] = un + pd[s] if hit else un
            flags[i] = hit
            n_hit += hit
        return n_hit

    @njit(nogil=True, cache=True)
    def out_of_bound(vbits, ubits, mask, bound_bits):
        """Any |v_pre| or |u| above the bound, infinite or NaN: on the magnitude bits a float
        orders like an integer and inf/NaN lie above every finite value (an integer OR
        reduction, which vectorizes)."""
        acc = bound_bits - bound_bits
        for i in range(vbits.shape[0]):
            acc |= (bound_bits - (vbits[i] & mask)) | (bound_bits - (ubits[i] & mask))
        return acc < 0

    @njit(nogil=True, cache=True)
    def run(v, u, Irows, sel, P, uniform, std_u, dt, half, vth, izh, k0, n_steps,
            spk_k, spk_n, n_spk, flags, fwords, vpre, ibuf, vbits, ubits, mask, bound_bits):
        """Steps k0 .. k0+n_steps-1 in place. Returns (steps done, spikes, first bad neuron
        or -1); stops before a step when the spike buffer could overflow, and after the
        step in which a state diverged. ``Irows`` is (1 or n_steps) x (1 or N) currents."""
        N = v.shape[0]
        rows, cols = Irows.shape
        cap = spk_k.shape[0]
        for j in range(n_steps):
            if cap - n_spk < N:
                return j, n_spk, -1
            k = k0 + j
            r = k if rows > 1 else 0
            if cols > 1:
                Ir = Irows[r]
            else:
                ibuf[:] = Irows[r, 0]
                Ir = ibuf
            n_hit = advance(v, u, Ir, sel, P, uniform, std_u, dt, half, vth, izh, flags, vpre)
            if n_hit:
                n_spk = record(flags, fwords, k, spk_k, spk_n, n_spk)
            if out_of_bound(vbits, ubits, mask, bound_bits):
                for i in range(N):
                    if (vbits[i] & mask) > bound_bits or (ubits[i] & mask) > bound_bits:
                        return j + 1, n_spk, i
        return n_steps, n_spk, -1

    _KERNEL["run"] = run
    _KERNEL["advance"] = advance
    _KERNEL["oob"] = out_of_bound
    _KERNEL["record"] = record
    return run


def simulate_compiled(prm, v, u, current, I_of, n_steps, n_neurons, dt_ms, scheme, dtype,
                      state_bound, progress, threads, v_th):
    """The compiled loop over steps and neurons, in place on ``v`` and ``u``; the same spikes
    and state as the NumPy loop of :func:`cuneate.golden.izhikevich.simulate`. Returns
    ``(spike steps, spike neurons, divergence)``: the spikes per thread slice, and ``None`` or
    the first divergence as ``(step, neuron, v_pre, u)``."""
    run = _golden_kernel()
    cast = dtype.type
    std_u = bool(np.all(prm.u_leak == 1.0) and np.all(prm.v_u == 0.0))
    dt, half, vth = cast(dt_ms), cast(0.5) * cast(dt_ms), cast(v_th)
    izh = scheme == "izhikevich"
    ibits = np.dtype(f"i{dtype.itemsize}")
    mask = ibits.type(np.iinfo(ibits).max)               # all bits but the sign
    bound_bits = np.asarray(abs(state_bound), dtype=dtype).view(ibits)[()]
    # the distinct parameter sets (few) and each neuron's index into them: the loop streams
    # v, u, I and one small index per neuron, the constants stay in cache
    rows = np.stack([prm.a, prm.b, prm.c, prm.d, prm.A, prm.B, prm.C, prm.u_leak, prm.v_u], 1)
    ubits = np.dtype(f"u{dtype.itemsize}")            # distinct to the bit (0.0 vs -0.0)
    uniq, sel = np.unique(np.ascontiguousarray(rows).view(ubits), axis=0, return_inverse=True)
    uniq = uniq.view(dtype)
    sel = sel.reshape(-1).astype(np.int64)
    per_set = tuple(tuple(cast(x) for x in uniq[:, j]) for j in range(9))
    uniform = len(uniq) == 1
    if threads is None:
        least = PARALLEL_MIN_NEURONS if callable(current) else PARALLEL_MIN_NEURONS_TABLE
        threads = min(os.cpu_count() or 1, 2) if n_neurons >= least else 1
    threads = max(1, min(int(threads), n_neurons))

    # currents as a 2-D table read by (step, neuron), rows/columns of length 1 broadcast
    table = None
    if not callable(current):
        arr = np.asarray(current, dtype=dtype)
        table = arr.reshape(1, 1) if arr.ndim == 0 else \
            arr.reshape(-1, 1) if arr.ndim == 1 else arr
        if table.strides[0] == 0:                       # one row broadcast over the steps
            table = table[:1]

    def chunk(lo, hi):
        vv, uu = v[lo:hi], u[lo:hi]
        ss = sel[lo:hi]
        n = hi - lo
        cap = max(4 * n, 4096)
        spk_k, spk_n = np.empty(cap, np.int64), np.empty(cap, np.int64)
        flags = np.zeros((n + 7) // 8 * 8, np.bool_)
        vpre, ibuf = np.empty(n, dtype), np.empty(n, dtype)
        vbits, ubits = vpre.view(ibits), uu.view(ibits)
        n_spk, done = 0, 0
        block = 1000 if progress is not None and threads == 1 else max(n_steps, 1)
        while done < n_steps:
            todo = min(block, n_steps - done)
            if table is None:
                todo = 1
                val = np.asarray(I_of(done), dtype=dtype)
                tab = val.reshape(1, 1) if val.ndim == 0 else val[lo:hi].reshape(1, -1)
            else:
                tab = table if table.shape[1] == 1 else table[:, lo:hi]
            tab = np.ascontiguousarray(tab)
            d_, n_spk, bad = run(vv, uu, tab, ss, per_set, uniform, std_u, dt, half, vth, izh,
                                 done, todo, spk_k, spk_n, n_spk, flags, flags.view(np.uint64),
                                 vpre, ibuf, vbits, ubits, mask, bound_bits)
            if bad >= 0:
                return None, None, (done + d_ - 1, lo + bad, float(vpre[bad]),
                                    float(uu[bad]))
            done += d_
            if d_ < todo:                               # spike buffer full: grow it
                cap *= 2
                spk_k, spk_n = np.resize(spk_k, cap), np.resize(spk_n, cap)
            if progress is not None and threads == 1 and done % 1000 == 0 and d_:
                progress(done)
        return spk_k[:n_spk], spk_n[:n_spk] + lo, None

    with np.errstate(over="ignore", invalid="ignore"):
        parts = split_over_threads(chunk, n_neurons, threads)
    bads = [p[2] for p in parts if p[2] is not None]
    if bads:
        return None, None, min(bads)
    if progress is not None and threads > 1:
        for k in range(1000, n_steps + 1, 1000):
            progress(k)
    return [p[0] for p in parts], [p[1] for p in parts], None

