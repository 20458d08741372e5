"""The compiled (numba) loop of the float64/float32 Izhikevich golden model: the operations of
:func:`cuneate.golden.izhikevich.step` per neuron, in the same order (no reassociation, so the
same bits), over every step of a run, the population split over threads."""

from __future__ import annotations

import os

import numpy as np

from .kernel import BLOCK, available, close_block, open_block, record, split_over_threads

__all__ = ["simulate_compiled", "block_kernel", "BLOCK", "W_V", "W_U", "W_I", "W_VPRE",
           "PARALLEL_MIN_NEURONS",
           "PARALLEL_MIN_NEURONS_TABLE"]

#: a callable current: one thread dispatch per step, so threads pay only for large populations
PARALLEL_MIN_NEURONS = 50_000
#: an array current: one dispatch per run, each thread its own blocks (from two half blocks on,
#: for runs of at least PARALLEL_MIN_UPDATES updates)
PARALLEL_MIN_NEURONS_TABLE = 512
PARALLEL_MIN_UPDATES = 2_000_000


_KERNEL: dict = {}

# rows of the scratch array of a block (each ``BLOCK`` long): state, current, v before reset,
# then the parameters per neuron when the sets differ
W_V, W_U, W_I, W_VPRE, W_P = 0, 1, 2, 3, 4
W_ROWS = W_P + 9


if available():
    # module-level functions (not closures), so that numba's disk cache finds them again
    from numba import njit

    @njit(nogil=True, cache=True, inline="always")
    def update(vi, ui, I, a, b, c, d, A_, B_, C_, lam, vu, std_u, izh, dt, half, vth):
        """One update of one neuron: the operations of step() in its order (no
        reassociation, so the same bits), branch-free. Returns (v', u', v before reset)."""
        if izh:
            vh = vi + half * (A_ * vi * vi + B_ * vi + C_ - ui + I)
            vn = vh + half * (A_ * vh * vh + B_ * vh + C_ - ui + I)
            vx = vn
        else:
            vn = vi + dt * (A_ * vi * vi + B_ * vi + C_ - ui + I)
            vx = vi
        if std_u:
            un = ui + dt * (a * (b * vx - ui))
        else:
            un = ui + dt * (a * (b * (vx - vu) - lam * ui))
        hit = vn >= vth
        return (c if hit else vn), (un + d if hit else un), vn

    @njit(nogil=True, cache=True)
    def advance(v, u, Ir, sel, P, uniform, std_u, dt, half, vth, izh, flags, vpre):
        """One step of every neuron in place. ``P`` holds the distinct parameter sets as
        tuples (values: no aliasing with the state), ``sel`` each neuron's set. Returns the
        number of spikes (flagged in ``flags``)."""
        pa, pb, pc, pd, pA, pB, pC, plam, pvu = P
        n_hit = 0
        for i in range(v.shape[0]):
            s = 0 if uniform else sel[i]
            vn, un, vp = update(v[i], u[i], Ir[i], pa[s], pb[s], pc[s], pd[s], pA[s], pB[s],
                                pC[s], plam[s], pvu[s], std_u, izh, dt, half, vth)
            vpre[i] = vp
            v[i] = vn
            u[i] = un
            hit = vp >= vth
            flags[i] = hit
            n_hit += hit
        return n_hit

    @njit(nogil=True, cache=True, inline="always")
    def block_loop(w, flags, n, P, uniform, std_u, izh, dt, half, vth, bound, track):
        nh = 0
        nbad = 0
        a, b, c, d, A_, B_, C_, lam, vu = P[0]
        for i in range(n):
            if not uniform:             # the neuron's own set, from the parameter rows
                a, b, c, d = w[4 * BLOCK + i], w[5 * BLOCK + i], w[6 * BLOCK + i], \
                    w[7 * BLOCK + i]
                A_, B_, C_ = w[8 * BLOCK + i], w[9 * BLOCK + i], w[10 * BLOCK + i]
                lam, vu = w[11 * BLOCK + i], w[12 * BLOCK + i]
            vn, un, vp = update(w[i], w[BLOCK + i], w[2 * BLOCK + i], a, b, c, d, A_, B_, C_,
                                lam, vu, std_u, izh, dt, half, vth)
            w[i] = vn
            w[BLOCK + i] = un
            w[3 * BLOCK + i] = vp
            hit = vp >= vth
            flags[i] = hit
            nh += hit
            nbad += not (abs(vp) <= bound and abs(un) <= bound)
            if track:
                x = w[4 * BLOCK + i]
                w[4 * BLOCK + i] = vn if vn < x else x
                x = w[5 * BLOCK + i]
                w[5 * BLOCK + i] = un if un < x else x
                x = w[6 * BLOCK + i]
                w[6 * BLOCK + i] = un if un > x else x
                x = w[7 * BLOCK + i]
                w[7 * BLOCK + i] = vp if vp > x else x
        return nh, nbad

    @njit(nogil=True, cache=True)
    def block_steps(w, flags, n, P, uniform, std_u, izh, dt, half, vth, bound, track):
        """One step of the ``n`` neurons of a block held in the scratch ``w`` (rows of
        ``BLOCK``), in place, spikes flagged in ``flags``. Returns (spikes, states out of the
        bound): a bound exceeded, infinite or NaN fails ``|x| <= bound``. With ``track``
        (one parameter set, Euler) rows ``W_P`` to ``W_P + 3`` keep the running minimum of
        v and of u and maximum of u and of v before reset. One set or several, the scheme, the
        u-equation's form and ``track`` are constants of each loop (so that each vectorizes)."""
        if track:
            if std_u:
                return block_loop(w, flags, n, P, True, True, False, dt, half, vth, bound,
                                  True)
            return block_loop(w, flags, n, P, True, False, False, dt, half, vth, bound, True)
        if uniform:
            return scheme_loop(w, flags, n, P, True, std_u, izh, dt, half, vth, bound)
        return scheme_loop(w, flags, n, P, False, std_u, izh, dt, half, vth, bound)

    @njit(nogil=True, cache=True, inline="always")
    def scheme_loop(w, flags, n, P, uniform, std_u, izh, dt, half, vth, bound):
        if izh:
            if std_u:
                return block_loop(w, flags, n, P, uniform, True, True, dt, half, vth, bound,
                                  False)
            return block_loop(w, flags, n, P, uniform, False, True, dt, half, vth, bound,
                              False)
        if std_u:
            return block_loop(w, flags, n, P, uniform, True, False, dt, half, vth, bound,
                              False)
        return block_loop(w, flags, n, P, uniform, False, False, dt, half, vth, bound, False)

    @njit(nogil=True, cache=True)
    def run(v, u, Irows, ioff, P, prm, uniform, std_u, dt, half, vth, izh, k0, k1, b0, kb0,
            spk_k, spk_n, n_spk, w, flags, fwords, bound, bad, bad_state):
        """Steps ``k0 .. k1 - 1`` of every neuron in place, a block of ``BLOCK`` neurons at a
        time through every step (from step ``kb0`` for block ``b0``: a resumed call).
        ``Irows`` is (1 or steps) x (1 or more) currents (neuron ``i``'s in column
        ``ioff + i`` when there are several), ``prm`` (9, N) the per-neuron
        parameters when the sets differ. Spikes are appended to (spk_k, spk_n) from
        ``n_spk``, per neuron in step order. Stops before a block's step when the buffer
        could overflow: returns (block, step, spikes) to resume from, ``(blocks, k1, spikes)``
        when done. A block stops after a step whose state left the bound; ``bad`` keeps the
        first such (step, neuron) over the blocks (later blocks stop at that step),
        ``bad_state`` its v before reset and u."""
        N = v.shape[0]
        rows, cols = Irows.shape
        nb = (N + BLOCK - 1) // BLOCK
        cap = spk_k.shape[0]
        for blk in range(b0, nb):
            lo = blk * BLOCK
            n = min(N, lo + BLOCK) - lo
            open_block(w, flags, v, u, lo, n)
            if not uniform:
                for j in range(9):
                    for i in range(n):
                        w[(W_P + j) * BLOCK + i] = prm[j, ioff + lo + i]
            first = True
            for k in range(kb0 if blk == b0 else k0, k1):
                if k > bad[0]:
                    break
                if cap - n_spk < n:
                    close_block(w, v, u, lo, n)
                    return blk, k, n_spk
                if first or rows > 1:
                    r = k if rows > 1 else 0
                    for i in range(n):
                        w[2 * BLOCK + i] = Irows[r, ioff + lo + i if cols > 1 else 0]
                    first = False
                nh, nbad = block_steps(w, flags, n, P, uniform, std_u, izh, dt, half, vth,
                                       bound, False)
                if nbad:
                    for i in range(n):
                        vp, uu = w[3 * BLOCK + i], w[BLOCK + i]
                        if not (abs(vp) <= bound and abs(uu) <= bound):
                            if k < bad[0]:
                                bad[0], bad[1] = k, lo + i
                                bad_state[0], bad_state[1] = vp, uu
                            break
                    break
                if nh:
                    n_spk = record(flags[:(n + 7) // 8 * 8], fwords[:(n + 7) // 8], k, spk_k,
                                   spk_n, n_spk, lo)
            close_block(w, v, u, lo, n)
        return nb, k1, n_spk


    @njit(nogil=True, cache=True)
    def first_bad(vpre, u, bound):
        """Index of the first neuron whose v before reset or u left the bound (infinite or
        NaN included), or -1."""
        nbad = 0
        for i in range(u.shape[0]):
            nbad += not (abs(vpre[i]) <= bound and abs(u[i]) <= bound)
        if nbad:
            for i in range(u.shape[0]):
                if not (abs(vpre[i]) <= bound and abs(u[i]) <= bound):
                    return i
        return -1

    _KERNEL.update(run=run, advance=advance, update=update, block_steps=block_steps,
                   first_bad=first_bad)


def _golden_kernel():
    return _KERNEL["run"]


def block_kernel():
    """The compiled step of a block of neurons held in a scratch array (``block_steps(w,
    flags, n, P, uniform, std_u, izh, dt, half, vth, bound, track)``: rows ``W_V``, ``W_U``,
    ``W_I``, ``W_VPRE`` of :data:`BLOCK` each, then the extremes tracked; the operations of
    :func:`cuneate.golden.izhikevich.step` per neuron, in its order), for other compiled loops
    that step the golden model (the state-range search)."""
    _golden_kernel()
    return _KERNEL["block_steps"]


def simulate_compiled(prm, v, u, current, I_of, n_steps, n_neurons, dt_ms, scheme, dtype,
                      state_bound, progress, threads, v_th):
    """The compiled loop over steps and neurons, in place on ``v`` and ``u``; the same spikes
    and state as the NumPy loop of :func:`cuneate.golden.izhikevich.simulate`. Returns
    ``(spike steps, spike neurons, divergence)``: the spikes per thread slice (per neuron in
    step order), and ``None`` or the first divergence as ``(step, neuron, v_pre, u)``.

    An array current runs a block of :data:`BLOCK` neurons through every step at a time (the
    block stays in L1; the loop over it vectorizes), the population split over threads; a
    callable current is evaluated per step, every neuron stepped per call."""
    run = _golden_kernel()
    cast = dtype.type
    std_u = bool(np.all(prm.u_leak == 1.0) and np.all(prm.v_u == 0.0))
    dt, half, vth = cast(dt_ms), cast(0.5) * cast(dt_ms), cast(v_th)
    izh = scheme == "izhikevich"
    bound = cast(abs(state_bound))
    # the distinct parameter sets (few) and each neuron's index into them
    rows = np.stack([prm.a, prm.b, prm.c, prm.d, prm.A, prm.B, prm.C, prm.u_leak, prm.v_u], 1)
    ubits = np.dtype(f"u{dtype.itemsize}")            # distinct to the bit (0.0 vs -0.0)
    bits = np.ascontiguousarray(rows).view(ubits)
    if np.all(bits == bits[:1]):
        uniq, sel = rows[:1], np.zeros(n_neurons, np.int64)
    else:
        uniq, sel = np.unique(bits, axis=0, return_inverse=True)
        uniq = uniq.view(dtype)
        sel = sel.reshape(-1).astype(np.int64)
    uniform = len(uniq) == 1
    per_set = tuple(tuple(cast(x) for x in uniq[:, j]) for j in range(9))   # by coefficient
    sets = tuple(tuple(cast(x) for x in uniq[s]) for s in range(len(uniq)))  # by set
    per_neuron = np.ascontiguousarray(rows.T, dtype=dtype) if not uniform else \
        np.zeros((9, 1), dtype)
    if threads is None:
        least = PARALLEL_MIN_NEURONS if callable(current) else PARALLEL_MIN_NEURONS_TABLE
        long = callable(current) or n_neurons * n_steps >= PARALLEL_MIN_UPDATES
        threads = min(os.cpu_count() or 1, 2) if n_neurons >= least and long else 1
    threads = max(1, min(int(threads), n_neurons))

    # currents as a 2-D table read by (step, neuron), rows/columns of length 1 broadcast
    table = None
    if not callable(current):
        arr = np.asarray(current, dtype=dtype)
        table = arr.reshape(1, 1) if arr.ndim == 0 else \
            arr.reshape(-1, 1) if arr.ndim == 1 else arr
        if table.strides[0] == 0:                       # one row broadcast over the steps
            table = table[:1]
        table = np.ascontiguousarray(table)
    report = progress is not None and threads == 1

    def grow(spk_k, spk_n):
        cap = 2 * spk_k.shape[0]
        return np.resize(spk_k, cap), np.resize(spk_n, cap)

    def chunk_table(lo, hi):
        vv, uu = v[lo:hi], u[lo:hi]
        n = hi - lo
        spk_k, spk_n = np.empty(max(4 * n, 4096), np.int64), np.empty(max(4 * n, 4096),
                                                                      np.int64)
        w = np.zeros(W_ROWS * BLOCK, dtype)
        flags = np.zeros(BLOCK, np.bool_)
        bad = np.array([np.iinfo(np.int64).max, -1], np.int64)
        bad_state = np.zeros(2, dtype)
        n_spk, done = 0, 0
        span = 1000 if report else max(n_steps, 1)
        nb = (n + BLOCK - 1) // BLOCK
        while done < n_steps:
            k1 = min(done + span, n_steps)
            b, k = 0, done
            while True:
                b, k, n_spk = run(vv, uu, table, lo, sets, per_neuron, uniform, std_u, dt,
                                  half, vth, izh, done, k1, b, k, spk_k, spk_n, n_spk, w, flags,
                                  flags.view(np.uint64), bound,
                                  bad, bad_state)
                if b >= nb:
                    break
                spk_k, spk_n = grow(spk_k, spk_n)
            if bad[1] >= 0:
                return None, None, (int(bad[0]), lo + int(bad[1]), float(bad_state[0]),
                                    float(bad_state[1]))
            done = k1
            if report and done % 1000 == 0:
                progress(done)
        return spk_k[:n_spk], spk_n[:n_spk] + lo, None

    def chunk_callable(lo, hi):
        advance, first_bad = _KERNEL["advance"], _KERNEL["first_bad"]
        vv, uu, ss = v[lo:hi], u[lo:hi], sel[lo:hi]
        n = hi - lo
        spk_k, spk_n = np.empty(max(4 * n, 4096), np.int64), np.empty(max(4 * n, 4096),
                                                                      np.int64)
        flags = np.zeros((n + 7) // 8 * 8, np.bool_)
        fwords = flags.view(np.uint64)
        vpre, ibuf = np.empty(n, dtype), np.empty(n, dtype)
        n_spk = 0
        for k in range(n_steps):
            val = np.asarray(I_of(k), dtype=dtype)
            if val.ndim == 0:
                ibuf[:] = val
                Ir = ibuf
            else:
                Ir = np.ascontiguousarray(val[lo:hi])
            if spk_k.shape[0] - n_spk < n:
                spk_k, spk_n = grow(spk_k, spk_n)
            if advance(vv, uu, Ir, ss, per_set, uniform, std_u, dt, half, vth, izh, flags,
                       vpre):
                n_spk = record(flags, fwords, k, spk_k, spk_n, n_spk)
            i = first_bad(vpre, uu, bound)
            if i >= 0:
                return None, None, (k, lo + i, float(vpre[i]), float(uu[i]))
            if report and (k + 1) % 1000 == 0:
                progress(k + 1)
        return spk_k[:n_spk], spk_n[:n_spk] + lo, None

    with np.errstate(over="ignore", invalid="ignore"):
        parts = split_over_threads(chunk_callable if table is None else chunk_table,
                                   n_neurons, threads)
    bads = [p[2] for p in parts if p[2] is not None]
    if bads:
        return None, None, min(bads)
    if progress is not None and threads > 1:
        for k in range(1000, n_steps + 1, 1000):
            progress(k)
    return [p[0] for p in parts], [p[1] for p in parts], None
