"""Compiled (numba) kernel of the learning layer's twin.

A tick of :class:`~cuneate.hdl.plasticity.PlasticityTwin` - the stamp and the delayed words,
the interneuron (``interneuron`` and its trace), each CN's net drive and main calcium
(``net_drive``, ``main_calcium``), every synapse's integrate operation
(:func:`~cuneate.hdl.plasticity.datapath.synapse_step`: ``calcium_input``, the calcium traces,
``drive_product``, ``integrate``, ``contribution``), the excitation's trace and the Izhikevich
update - and a window's end (``compensated``, ``step_index``, ``weight_delta``,
``weight_update``), restated per CN and synapse with the same integer operations, one compiled
loop over whole presentations. The Izhikevich step is the Izhikevich kernel's and the trace
step the shared one (:mod:`cuneate.hdl.lib.kernel`). Proven bit-exact against the stage
functions by tests on random presentations (``tests/hdl/test_plasticity.py``).
"""

from __future__ import annotations

import numpy as np

from ..izhikevich import kernel as izk
from ..lib.kernel import as_tuples, available, rounding_slots, trace_table
from .config import CLAMP_KINDS

__all__ = ["available", "gather_constants", "run_presentations"]

# scalar slots
(S_WSH, S_K, S_LMIN, S_LMAX, S_WMAX, S_SIGSH, S_NB, S_ILO, S_IHI, S_THETA, S_G, S_F,
 S_LAT) = range(13)
R_C, R_Q, R_D, R_T, R_HQ, R_G, R_E = (13 + 4 * k for k in range(7))
N_SCALARS = 13 + 4 * 7

assert len(CLAMP_KINDS) == 9                       # the loop counts nine kinds


def gather_constants(cfg) -> tuple:
    """The constants of a :class:`~cuneate.hdl.plasticity.PlasticityConfig`: ``(scalars,
    calcium traces, excitation trace, interneuron trace, Izhikevich (table, scalars))``."""
    near = cfg.rounding == "nearest"
    F = cfg.trace_frac_bits
    sc = np.zeros(N_SCALARS, dtype=np.int64)
    sc[S_WSH], sc[S_K] = cfg.wshift, cfg.n_synapses
    sc[S_LMIN], sc[S_LMAX], sc[S_WMAX] = cfg.L.min_raw, cfg.L.max_raw, cfg.w_max_raw
    sc[S_SIGSH], sc[S_NB] = cfg.sig_shift, cfg.sigmoid_bits
    sc[S_ILO], sc[S_IHI], sc[S_THETA] = cfg.i_lim_raw[0], cfg.i_lim_raw[1], cfg.theta_raw
    sc[S_G], sc[S_F], sc[S_LAT] = cfg.G.raw, F, cfg.latency_ticks
    for slot, shift in ((R_C, cfg.c_shift), (R_Q, cfg.q_shift), (R_D, cfg.d_shift),
                        (R_T, cfg.T_frac), (R_HQ, F - cfg.HQ.frac_bits), (R_G, cfg.g_shift),
                        (R_E, cfg.e_shift)):
        sc[slot:slot + 4] = rounding_slots(shift, near)
    return (as_tuples(sc), as_tuples(trace_table(cfg.calcium, F, near)),
            as_tuples(trace_table([cfg.exc], F, near)),
            as_tuples(trace_table([cfg.inh], F, near)), izk.gather_constants(cfg.iz))


if available():
    from numba import njit

    from ...golden.kernel import record_presentation
    from ..izhikevich.kernel import neuron_update as _iz_neuron
    from ..lib.kernel import rq as _rq
    from ..lib.kernel import trace_step

    _jit = dict(nogil=True, cache=True, error_model="numpy")

    @njit(**_jit)
    def _run(w, cd, cr, L, v, u, E, state, delayed, sel, src, table, ev_t, ev_s, off,
             n_ticks, win, flags, sc, ctab, etab, htab, iztab, izsc, counts, sp_p, sp_k,
             sp_j, totals, spike_words):
        """Every presentation in place; returns the spikes recorded (-1: the buffer filled).
        ``state`` holds ``[H, ticks, learns]``; ``delayed`` the delayed spike words."""
        M, K = w.shape
        S = delayed.shape[1]
        lat = sc[S_LAT]
        n_sp = 0
        s = np.zeros(S, np.bool_)
        late = np.zeros(S, np.bool_)
        z = np.zeros(M, np.int64)
        i0 = np.zeros(M, np.int64)
        uniform = len(iztab[0]) == 1
        F = sc[S_F]
        for q in range(off.shape[0] - 1):
            e = off[q]
            for k in range(n_ticks):
                s[:] = False
                while e < off[q + 1] and ev_t[e] == k:
                    s[ev_s[e]] = True
                    e += 1
                if lat > 0:
                    for i in range(S):
                        late[i] = delayed[lat - 1, i]
                    for d in range(lat - 1, 0, -1):
                        for i in range(S):
                            delayed[d, i] = delayed[d - 1, i]
                    for i in range(S):
                        delayed[0, i] = s[i]
                else:
                    for i in range(S):
                        late[i] = s[i]
                n = 0
                for i in range(S):
                    n += s[i]
                H = state[0]
                inh = _rq(_rq(H, sc, R_HQ) * sc[S_G], sc, R_G)
                state[0] = trace_step(H + (n << F), htab, 0)
                c0 = c1 = 0
                for j in range(M):
                    ij = _rq(E[j], sc, R_E) - inh
                    i0[j] = ij
                    z[j] = min(max(ij, sc[S_ILO]), sc[S_IHI]) - sc[S_THETA]
                    a = 0
                    for m in range(K):
                        wj = w[j, m]
                        si = src[j, m]
                        if s[si]:
                            a += wj
                        x = (wj << sc[S_WSH]) if late[si] else 0
                        C = cd[j, m] - cr[j, m]
                        cd[j, m] = trace_step(cd[j, m] + x, ctab, 0)
                        cr[j, m] = trace_step(cr[j, m] + x, ctab, 1)
                        lsum = L[j, m] + _rq(_rq(C, sc, R_C) * z[j], sc, R_Q)
                        if lsum < sc[S_LMIN]:
                            lsum = sc[S_LMIN]
                            c0 += 1
                        elif lsum > sc[S_LMAX]:
                            lsum = sc[S_LMAX]
                            c1 += 1
                        L[j, m] = lsum
                    E[j] = trace_step(E[j] + (a << sc[S_WSH]), etab, 0)
                    r = _iz_neuron(v[j], u[j], i0[j], 0 if uniform else sel[j], iztab, izsc)
                    v[j] = r[0]
                    u[j] = r[1]
                    cl = r[3]
                    for b in range(5):
                        totals[b] += (cl >> b) & 1
                    spike_words[j] = r[2]
                totals[5] += c0
                totals[6] += c1
                n_sp = record_presentation(spike_words, M, q, k, win, sp_p, sp_k, sp_j, n_sp,
                                           counts)
                if n_sp < 0:
                    return -1
                state[1] += 1
            # the window's end
            for j in range(M):
                tot = 0
                for m in range(K):
                    tot += L[j, m]
                if flags[q]:
                    for m in range(K):
                        dq = _rq(L[j, m] * sc[S_K] - tot, sc, R_D)
                        idx = (w[j, m] >> sc[S_SIGSH]) + ((1 << sc[S_NB]) if dq > 0 else 0)
                        wn = w[j, m] + _rq(dq * table[idx], sc, R_T)
                        if wn < 0:
                            wn = 0
                            totals[7] += 1
                        elif wn > sc[S_WMAX]:
                            wn = sc[S_WMAX]
                            totals[8] += 1
                        w[j, m] = wn
                for m in range(K):
                    L[j, m] = 0
            state[2] += 1
        return n_sp


def run_presentations(twin, pres, flags) -> dict:
    """Run presentations on ``twin``'s state in place (see
    :meth:`~cuneate.hdl.plasticity.PlasticityTwin.run`)."""
    from ..lib.fixed import tally_clamps
    cfg = twin.cfg
    if twin.pending.any():
        raise ValueError("the compiled run starts from a tick boundary: no spikes pending")
    sc, ctab, etab, htab, (iztab, izsc) = gather_constants(cfg)
    M = cfg.n_targets
    counts = np.zeros((pres.n, M), np.int64)
    totals = np.zeros(len(CLAMP_KINDS), np.int64)
    cap = max(1024, 8 * M * pres.n)
    snapshot = (twin.w.copy(), twin.cd.copy(), twin.cr.copy(), twin.L.copy(), twin.v.copy(),
                twin.u.copy(), twin.E.copy(), twin.H, twin.delayed.copy())
    while True:
        sp = [np.zeros(cap, np.int64) for _ in range(3)]
        state = np.array([twin.H, twin.ticks, twin.learns], dtype=np.int64)
        delayed = np.ascontiguousarray(twin.delayed.reshape(-1, cfg.n_sources)
                                       if cfg.latency_ticks else np.zeros((1, cfg.n_sources),
                                                                          bool))
        n_sp = _run(twin.w, twin.cd, twin.cr, twin.L, twin.v, twin.u, twin.E, state, delayed,
                    twin.sel, np.ascontiguousarray(cfg.src), twin.table, pres.ticks,
                    pres.sources, pres.offsets, pres.n_ticks, pres.window_ticks, flags, sc, ctab,
                    etab, htab, iztab, izsc, counts, *sp, totals, np.zeros(M, np.bool_))
        if n_sp >= 0:
            break
        (twin.w, twin.cd, twin.cr, twin.L, twin.v, twin.u, twin.E, twin.H,
         twin.delayed) = (x.copy() if isinstance(x, np.ndarray) else x for x in snapshot)
        counts[:] = 0
        totals[:] = 0
        cap *= 4
    twin.H, twin.ticks, twin.learns = int(state[0]), int(state[1]), int(state[2])
    if cfg.latency_ticks:
        twin.delayed = delayed.astype(bool)
    tally_clamps(twin, CLAMP_KINDS, totals)
    return {"spike_pres": sp[0][:n_sp], "spike_tick": sp[1][:n_sp], "spike_cn": sp[2][:n_sp],
            "counts": counts}
