"""Compiled (numba) kernel of the Izhikevich core's twin: the hot loop, fused per neuron.

The arithmetic is defined once by the stage functions of :mod:`cuneate.hdl.izhikevich.datapath`
(``operands``, ``multiply1``, ``multiply2``, ``update_state``); this module restates the same
integer operations per neuron, in the same order, for a compiled loop without temporaries.
It is proven bit-exact against the stage-function twin by property tests (randomized states,
currents and set indices over every rounding and parameter-set mix, saturating currents, every
clamp kind) and long runs (``tests/hdl/test_izhikevich_kernel.py``).

Constants are gathered once per configuration by :func:`gather_constants` into an int64 table
(one column per parameter set; a constant shared by the sets is simply repeated) and an int64
vector of scalars, so one compiled kernel serves every configuration. Overflow of the int64
intermediates is excluded once, at configuration time (``IzhikevichConfig._check_int64``
bounds the widest sum from the formats); the kernel does not test it per update.

All kernels release the GIL, so :func:`run_sweeps` splits large populations over threads
(neurons are independent within a sweep and between sweeps given their currents).
"""

from __future__ import annotations

import os

import numpy as np

from ..lib.kernel import (BLOCK, INT64_MAX, INT64_MIN, PARALLEL_MIN_NEURONS, available,
                          close_block, default_threads, open_block, record, rounding_slots,
                          split_over_threads)
from .config import CLAMP_KINDS, IzhikevichConfig

__all__ = ["available", "rounding_slots", "gather_constants", "update_arrays", "run_sweeps",
           "default_threads", "sweep_inplace", "sweep_scratch", "PARALLEL_MIN_NEURONS",
           "neuron_update", "specialized", "BLOCK"]

# table rows (per parameter set)
(T_WOFF, T_KA, T_BETA, T_ESH, T_LEAK, T_K0, T_D, T_SA, T_HA, T_ALPHA, T_C) = range(11)
# scalar slots
(S_NEAR, S_ICLAMP, S_ILO, S_IHI, S_SV, S_SVQ, S_POW2, S_SIU, S_SUX, S_SDTI, S_SU, S_KDT, S_SDX,
 S_SHB, S_SHY, S_YCLAMP, S_YLO, S_YHI, S_SHQ, S_SHP, S_HALFP, S_VTHSH, S_VFLSH, S_ULO, S_UHI,
 S_VFLOOR, S_B_VLOW, S_B_UHIGH, S_B_ULOW, S_B_CUR, S_B_Y) = range(31)
# rounding shifts, each as 4 slots (left shift, right shift, rounding-bit shift, bit mask)
R_SV, R_SVQ, R_SDTI, R_SU, R_SIU, R_SUX, R_SDX, R_SHQ = (31 + 4 * j for j in range(8))
N_SCALARS = 31 + 4 * 8


def gather_constants(cfg: IzhikevichConfig) -> tuple[np.ndarray, np.ndarray]:
    """The configuration's constants as ``(table, scalars)`` for the kernel (int64)."""
    near = cfg.rounding == "nearest"
    n_sets = len(cfg.params)
    half_y = (1 << (cfg.shift_y - 1)) if near else 0
    tab = np.zeros((11, n_sets), dtype=np.int64)
    for s in range(n_sets):
        sa = cfg.shift_a[s]
        tab[:, s] = [cfg.woff[s].raw, cfg.KA[s].raw, cfg.beta[s].raw,
                     (cfg.E[s].raw << cfg.shift_b) - half_y, cfg.u_leak[s], cfg.K0[s].raw,
                     cfg.d[s].raw, sa, (1 << (sa - 1)) if near else 0, cfg.alpha[s].raw,
                     cfg.c[s].raw]
    sc = np.zeros(N_SCALARS, dtype=np.int64)
    sc[S_NEAR] = int(near)
    sc[S_ICLAMP] = int(cfg.current_clamp)
    sc[S_ILO], sc[S_IHI] = cfg.i_lo_raw, cfg.i_hi_raw
    sc[S_SV] = cfg.V.frac_bits - cfg.W.frac_bits
    sc[S_SVQ] = cfg.V.frac_bits - cfg.VQ.frac_bits
    if cfg.dt_shift is not None:
        s = cfg.dt_shift
        sc[S_POW2] = 1
        sc[S_SDTI] = cfg.I.frac_bits + s - cfg.V.frac_bits
        sc[S_SU] = cfg.U.frac_bits + s - cfg.V.frac_bits
    else:
        sc[S_SIU] = cfg.I.frac_bits - cfg.U.frac_bits
        sc[S_SUX] = cfg.U.frac_bits - cfg.X.frac_bits
        sc[S_KDT] = cfg.KDT.raw
        sc[S_SDX] = cfg.X.frac_bits + cfg.KDT.frac_bits - cfg.V.frac_bits
    sc[S_SHB], sc[S_SHY] = cfg.shift_b, cfg.shift_y
    Y, by = cfg.Y, cfg.bounds_y
    sc[S_YCLAMP] = int(not (Y.min_raw <= by[0] <= by[1] <= Y.max_raw))
    sc[S_YLO], sc[S_YHI] = Y.min_raw, Y.max_raw
    sc[S_SHQ], sc[S_SHP] = cfg.shift_q, cfg.shift_p
    sc[S_HALFP] = (1 << (cfg.shift_p - 1)) if near else 0
    sc[S_VTHSH] = cfg.VTH.raw << cfg.shift_p
    sc[S_VFLSH] = cfg.v_floor_raw << cfg.shift_p
    sc[S_ULO], sc[S_UHI] = cfg.u_lo_raw, cfg.u_hi_raw
    sc[S_VFLOOR] = cfg.v_floor_raw
    if not sc[S_ICLAMP]:                  # no clamp: levels no int64 can pass
        sc[S_ILO], sc[S_IHI] = INT64_MIN, INT64_MAX
    if not sc[S_YCLAMP]:
        sc[S_YLO], sc[S_YHI] = INT64_MIN, INT64_MAX
    for slot, shift in ((R_SV, S_SV), (R_SVQ, S_SVQ), (R_SDTI, S_SDTI), (R_SU, S_SU),
                        (R_SIU, S_SIU), (R_SUX, S_SUX), (R_SDX, S_SDX), (R_SHQ, S_SHQ)):
        sc[slot:slot + 4] = rounding_slots(int(sc[shift]), near)
    for slot, kind in zip((S_B_VLOW, S_B_UHIGH, S_B_ULOW, S_B_CUR, S_B_Y),
                          ("v_low", "u_high", "u_low", "current", "y")):
        sc[slot] = CLAMP_KINDS.index(kind)
    return (tuple(tuple(int(x) for x in row) for row in tab), tuple(int(x) for x in sc))


# ----------------------------------------------------------------------------------------------
# the kernels (compiled on first use, cached on disk)

if available():
    from numba import njit

    from ..lib.kernel import rq as _rq

    _jit = dict(nogil=True, cache=True, error_model="numpy")

    @njit(inline="always", **_jit)
    def neuron_update(v, u, I, s, tab, sc):
        """One update of one neuron: returns (v', u', spike, clamp bits, v_pre). Written
        without branches (selects, min/max) so that a loop over neurons can vectorize."""
        # --- operands (a clamp that is not built has levels no int64 passes)
        i_lo, i_hi = I < sc[S_ILO], I > sc[S_IHI]
        I = min(max(I, sc[S_ILO]), sc[S_IHI])
        wq = _rq(v + tab[T_WOFF][s], sc, R_SV)
        vq = _rq(v, sc, R_SVQ)
        # --- multiply 1
        q = wq * tab[T_KA][s]
        bvp = vq * tab[T_BETA][s]
        uy = ((u << sc[S_SHB]) & -tab[T_LEAK][s]) + tab[T_ESH][s]
        dx_pow2 = _rq(I, sc, R_SDTI) - _rq(u, sc, R_SU)
        dx_mul = _rq(_rq(_rq(I, sc, R_SIU) - u, sc, R_SUX) * sc[S_KDT], sc, R_SDX)
        dx = dx_pow2 if sc[S_POW2] != 0 else dx_mul
        # --- multiply 2
        qq = _rq(q, sc, R_SHQ)
        y_full = (bvp - uy) >> sc[S_SHY]
        y_lo, y_hi = y_full < sc[S_YLO], y_full > sc[S_YHI]
        y = min(max(y_full, sc[S_YLO]), sc[S_YHI])
        vb_sh = ((v + dx + tab[T_K0][s]) << sc[S_SHP]) + sc[S_HALFP]
        sa = tab[T_SA][s]
        p = qq * wq
        m = y * tab[T_ALPHA][s]
        # --- update
        v_pre = (vb_sh + p) >> sc[S_SHP]
        spike = vb_sh - sc[S_VTHSH] + p >= 0
        under = vb_sh - sc[S_VFLSH] + p < 0
        u_base = u + tab[T_D][s] if spike else u
        u_pre = ((u_base << sa) + tab[T_HA][s] + m) >> sa
        u_low, u_high = u_pre < sc[S_ULO], u_pre > sc[S_UHI]
        u_new = min(max(u_pre, sc[S_ULO]), sc[S_UHI])
        v_low = under and not spike
        v_new = tab[T_C][s] if spike else (sc[S_VFLOOR] if under else v_pre)
        clamp = ((np.int64(v_low) << sc[S_B_VLOW]) | (np.int64(u_high) << sc[S_B_UHIGH])
                 | (np.int64(u_low) << sc[S_B_ULOW])
                 | (np.int64(i_lo | i_hi) << sc[S_B_CUR])
                 | (np.int64(y_lo | y_hi) << sc[S_B_Y]))
        return v_new, u_new, spike, clamp, v_pre

    @njit(**_jit)
    def _update_arrays(v, u, I, sel, tab, sc, v_out, u_out, spike, clamp, v_pre):
        for i in range(v.shape[0]):
            a, b, c, d, e = neuron_update(v[i], u[i], I[i], sel[i], tab, sc)
            v_out[i] = a
            u_out[i] = b
            spike[i] = c
            clamp[i] = d
            v_pre[i] = e

    @njit(inline="always", **_jit)
    def _add_counts(into, c0, c1, c2, c3, c4):
        into[0] += c0
        into[1] += c1
        into[2] += c2
        into[3] += c3
        into[4] += c4

    @njit(inline="always", **_jit)
    def _block_loop(w, flags, n, tab, sc, uniform):
        """One sweep of the ``n`` neurons of a block held in the scratch ``w`` (rows of
        ``BLOCK``: v, u, I, set), in place; spikes flagged in ``flags``. Returns the spikes
        and the clamps per kind (``uniform``: one parameter set, a constant of each loop)."""
        nh = c0 = c1 = c2 = c3 = c4 = 0
        for i in range(n):
            a, b, c, d, _ = neuron_update(w[i], w[BLOCK + i], w[2 * BLOCK + i],
                                          0 if uniform else w[3 * BLOCK + i], tab, sc)
            w[i] = a
            w[BLOCK + i] = b
            flags[i] = c
            nh += c
            c0 += d & 1
            c1 += (d >> 1) & 1
            c2 += (d >> 2) & 1
            c3 += (d >> 3) & 1
            c4 += (d >> 4) & 1
        return nh, c0, c1, c2, c3, c4

    @njit(inline="always", **_jit)
    def _blocks(v, u, I, sel, tab, sc, k0, k1, b0, kb0, spk_k, spk_n, n_spk, w, flags,
                fwords, totals, last, k_last):
        N = v.shape[0]
        nb = (N + BLOCK - 1) // BLOCK
        cap = spk_k.shape[0]
        uniform = len(tab[0]) == 1
        for blk in range(b0, nb):
            lo = blk * BLOCK
            n = min(N, lo + BLOCK) - lo
            open_block(w, flags, v, u, lo, n)
            for i in range(n):
                w[2 * BLOCK + i] = I[lo + i]
                w[3 * BLOCK + i] = sel[lo + i]
            for k in range(kb0 if blk == b0 else k0, k1):
                if cap - n_spk < n:
                    close_block(w, v, u, lo, n)
                    return blk, k, n_spk
                if uniform:             # a constant of each loop: the set index folds away
                    nh, c0, c1, c2, c3, c4 = _block_loop(w, flags, n, tab, sc, True)
                else:
                    nh, c0, c1, c2, c3, c4 = _block_loop(w, flags, n, tab, sc, False)
                _add_counts(totals, c0, c1, c2, c3, c4)
                if k == k_last:
                    _add_counts(last, c0, c1, c2, c3, c4)
                if nh:
                    n_spk = record(flags[:(n + 7) // 8 * 8], fwords[:(n + 7) // 8], k, spk_k,
                                   spk_n, n_spk, lo)
            close_block(w, v, u, lo, n)
        return nb, k1, n_spk

    @njit(**_jit)
    def _sweep_blocks(v, u, I, sel, tab, sc, spike, counts, w, flags, fwords, ks, ns, last):
        """One sweep of every neuron by the blocked loop; ``spike`` and ``counts`` filled."""
        counts[:] = 0
        _, _, n_spk = _blocks(v, u, I, sel, tab, sc, 0, 1, 0, 0, ks, ns, 0, w, flags, fwords,
                              counts, last, -1)
        spike[:] = False
        for j in range(n_spk):
            spike[ns[j]] = True
        return n_spk

    @njit(**_jit)
    def _run_blocks(v, u, I, sel, tab, sc, k0, k1, b0, kb0, spk_k, spk_n, n_spk, w, flags,
                    fwords, totals, last, k_last):
        """Sweeps ``k0 .. k1 - 1`` with constant currents, in place, a block of ``BLOCK``
        neurons at a time through every sweep (from sweep ``kb0`` for block ``b0``: a
        resumed call); spikes appended to (spk_k, spk_n) from ``n_spk``, per neuron in sweep
        order; clamps per kind added to ``totals`` (and to ``last`` in sweep ``k_last``).
        Stops before a block's sweep when the buffer could overflow: returns (block, sweep,
        spikes) to resume from, ``(blocks, k1, spikes)`` when done."""
        return _blocks(v, u, I, sel, tab, sc, k0, k1, b0, kb0, spk_k, spk_n, n_spk, w, flags,
                       fwords, totals, last, k_last)


_SPECIAL: dict = {}


def specialized(cfg_consts):
    """:func:`_run_blocks` compiled for one configuration: its constants are compile-time
    constants of the loop (shifts by immediates, the rounding, clamps and dt form that the
    configuration does not use folded away), the same operations otherwise. Compiled on
    first use (about 2 s) and cached on disk per configuration."""
    fn = _SPECIAL.get(cfg_consts)
    if fn is None:
        tab, sc = cfg_consts             # the closure's only cells: tuples of ints, so the
                                         # disk cache keys on the configuration's constants

        @njit(**_jit)
        def run_special(v, u, I, sel, tab_, sc_, k0, k1, b0, kb0, spk_k, spk_n, n_spk, w,
                        flags, fwords, totals, last, k_last):
            return _blocks(v, u, I, sel, tab, sc, k0, k1, b0, kb0, spk_k, spk_n, n_spk, w,
                           flags, fwords, totals, last, k_last)
        fn = _SPECIAL[cfg_consts] = run_special
    return fn


def update_arrays(cfg_consts, v, u, I, sel):
    """One update of the given neurons (1-D int64 arrays of equal length), by the kernel.
    Returns ``(v, u, spike, clamp_bits, v_pre)``."""
    tab, sc = cfg_consts
    n = v.shape[0]
    v_out, u_out = np.empty(n, np.int64), np.empty(n, np.int64)
    spike, clamp, v_pre = np.empty(n, np.bool_), np.empty(n, np.int64), np.empty(n, np.int64)
    _update_arrays(v, u, I, sel, tab, sc, v_out, u_out, spike, clamp, v_pre)
    return v_out, u_out, spike, clamp, v_pre


def sweep_scratch(n_neurons: int) -> tuple:
    """The working arrays of :func:`sweep_inplace` for ``n_neurons`` (kept by the caller
    across sweeps)."""
    flags = np.zeros(BLOCK, np.bool_)
    return (np.empty(4 * BLOCK, np.int64), flags, flags.view(np.uint64),
            np.empty(n_neurons + BLOCK, np.int64), np.empty(n_neurons + BLOCK, np.int64),
            np.zeros(len(CLAMP_KINDS), np.int64))


def sweep_inplace(cfg_consts, v, u, I, sel, spike, counts, scratch=None) -> int:
    """One sweep of every neuron in place (the blocked loop for one sweep); ``spike`` (bool)
    and ``counts`` (per clamp kind) are filled. Returns the number of spikes. ``scratch``:
    :func:`sweep_scratch` of the population, reused across sweeps."""
    tab, sc = cfg_consts
    w, flags, fwords, ks, ns, last = scratch or sweep_scratch(v.shape[0])
    return int(_sweep_blocks(v, u, I, sel, tab, sc, spike, counts, w, flags, fwords, ks, ns,
                             last))


def run_sweeps(cfg_consts, v, u, I, sel, n_sweeps: int, k0: int = 0,
               threads: int | None = None, special: bool = False):
    """``n_sweeps`` sweeps with constant currents ``I``, in place on ``v``, ``u``.

    Returns ``(spike_sweeps, spike_neurons, totals, last)``: every spike as (sweep index from
    ``k0``, neuron), per neuron in sweep order, the clamp counts per kind over the run and in
    its last sweep. Neurons run a block of :data:`BLOCK` at a time through every sweep (the
    block stays in L1, the loop over it vectorizes); the population is split over
    ``threads`` contiguous chunks, each run by the GIL-free kernel (default: every core, at
    most 2, from :data:`BLOCK` neurons and 2e6 updates on, else :func:`default_threads`).
    ``special``: the loop compiled for this configuration (:func:`specialized`).
    """
    tab, sc = cfg_consts
    N = v.shape[0]
    nk = len(CLAMP_KINDS)
    if threads is None:          # each thread its own blocks: from two half blocks on
        long = N >= BLOCK and N * n_sweeps >= 2_000_000
        threads = min(os.cpu_count() or 1, 2) if long else default_threads(N)
    threads = max(1, min(int(threads), N))
    run = specialized(cfg_consts) if special else _run_blocks

    def chunk(lo, hi):
        vv, uu, II, ss = v[lo:hi], u[lo:hi], I[lo:hi], sel[lo:hi]
        n = hi - lo
        cap = max(4 * n, 1024)
        spk_k, spk_n = np.empty(cap, np.int64), np.empty(cap, np.int64)
        totals, last = np.zeros(nk, np.int64), np.zeros(nk, np.int64)
        w = np.zeros(4 * BLOCK, np.int64)
        flags = np.zeros(BLOCK, np.bool_)
        nb = (n + BLOCK - 1) // BLOCK
        b, k, n_spk = 0, 0, 0
        while True:
            b, k, n_spk = run(vv, uu, II, ss, tab, sc, 0, n_sweeps, b, k, spk_k, spk_n, n_spk,
                              w, flags, flags.view(np.uint64), totals, last, n_sweeps - 1)
            if b >= nb:
                break
            cap *= 2                    # buffer full: grow and go on
            spk_k = np.resize(spk_k, cap)
            spk_n = np.resize(spk_n, cap)
        return spk_k[:n_spk] + k0, spk_n[:n_spk] + lo, totals, last

    return split_over_threads(chunk, N, threads if n_sweeps else 1)
