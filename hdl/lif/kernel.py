"""Compiled (numba) kernel of the LIF core's twin (the synaptic-trace step is the shared one of
:mod:`cuneate.hdl.lib.kernel`).

The arithmetic is defined once by the stage functions of :mod:`cuneate.hdl.lif.datapath`
(``gather_input``, ``leak_operand``, ``leak_product``, ``update_state``) and
:mod:`cuneate.hdl.lib.synapses`
(``trace_inputs``, ``trace_products``, ``trace_update``); this module restates the same integer
operations per neuron, in the same order, as one compiled loop over a whole program of sweeps
(currents and input spikes per sweep) without temporaries. It is proven bit-exact against the
stage-function twin by property tests (random states, currents over the whole current format,
input-spike vectors, set indices, every form, decay, rounding, clamp and synapse option) and by
long runs (``tests/hdl/test_lif_kernel.py``).

Constants are gathered once per configuration (:func:`gather_constants`): a per-set int64 table,
a vector of scalars, a per-trace table and the weight matrix. A narrowing of the stage functions
(``narrow``) is proven at construction never to act and is the identity on the twin; the kernel
leaves it out. Overflow of int64 is excluded by the formats (every intermediate is a few bits
wider than the state).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lib.kernel import (INT64_MAX, INT64_MIN, as_tuples, available, default_threads, record,
                          rounding_slots, split_over_threads, trace_table)
from .config import CLAMP_KINDS, LifConfig

__all__ = ["available", "LifConstants", "gather_constants", "update_arrays", "run_program"]

# per-set table rows
(T_REST, T_K, T_KSH, T_TH, T_RESET, T_NREF) = range(6)
# scalars
(S_NEAR, S_ICLAMP, S_ILO, S_IHI, S_ISH, S_WSH, S_SYN, S_DCLAMP, S_DLO, S_DHI, S_CONT, S_KSHIFT,
 S_VCLAMP, S_VMIN, S_VMAX, S_REF, S_B_CUR, S_B_IN, S_B_VLOW) = range(19)
R_X = 19                                  # rounding slots of the leak operand (4)
R_P = 23                                  # rounding slots of the leak product (4)
N_SCALARS = 27
assert CLAMP_KINDS == ("current", "input", "v_low")    # the run loop counts in this order


@dataclass(frozen=True)
class LifConstants:
    """Everything the kernel needs of one :class:`LifConfig` (ints as nested tuples)."""
    tab: tuple               # 6 rows of n_sets
    sc: tuple                # N_SCALARS
    ttab: tuple              # n_traces rows of N_TRACE_COLS; one dummy row without synapses
    exc: np.ndarray          # (n_inputs,) bool: source adds to the AMPA traces
    tab_array: np.ndarray    # ``tab`` as an int64 array (per-neuron gathers vectorize)


def gather_constants(cfg: LifConfig) -> LifConstants:
    """The configuration's constants for the kernel. Raises ``ValueError`` for a configuration
    the kernel does not cover (a current or weight format with more fraction bits than the
    state, a current-based synapse, input delays), which then runs on the stage functions."""
    near = cfg.rounding == "nearest"
    fv = cfg.V.frac_bits
    ish, wsh = fv - cfg.I.frac_bits, fv - cfg.W.frac_bits
    if ish < 0 or wsh < 0:
        raise ValueError("the compiled LIF kernel needs current and weight formats with at "
                         "most the state's fraction bits")
    if cfg.syn_alpha is not None or cfg.max_input_delay:
        raise ValueError("the compiled LIF kernel covers neither the current-based synapse nor "
                         "input delays")
    n_sets = len(cfg.sets)
    tab = np.zeros((6, n_sets), dtype=np.int64)
    for s in range(n_sets):
        tab[T_REST, s] = cfg.REST[s].raw
        tab[T_K, s] = cfg.K[s].raw if cfg.k_shift is None else 0
        tab[T_KSH, s] = cfg.k_shift[s] if cfg.k_shift is not None else 0
        tab[T_TH, s] = cfg.th_cmp_raw[s]
        tab[T_RESET, s] = cfg.RESET[s].raw
        tab[T_NREF, s] = cfg.n_ref[s]
    sc = np.zeros(N_SCALARS, dtype=np.int64)
    sc[S_NEAR] = int(near)
    sc[S_ICLAMP] = int(cfg.current_clamp)
    sc[S_ILO], sc[S_IHI] = ((cfg.i_lo_raw, cfg.i_hi_raw) if cfg.current_clamp
                            else (INT64_MIN, INT64_MAX))
    sc[S_ISH], sc[S_WSH] = ish, wsh
    sc[S_SYN] = int(cfg.synapses)
    sc[S_DCLAMP] = int(cfg.input_clamp)
    sc[S_DLO], sc[S_DHI] = ((cfg.d_lo_raw, cfg.d_hi_raw) if cfg.input_clamp
                            else (INT64_MIN, INT64_MAX))
    sc[S_CONT] = int(cfg.form == "continuous")
    sc[S_KSHIFT] = int(cfg.k_shift is not None)
    sc[S_VCLAMP] = int(cfg.v_clamp)
    sc[S_VMIN], sc[S_VMAX] = ((cfg.V.min_raw, cfg.V.max_raw) if cfg.v_clamp
                              else (INT64_MIN, INT64_MAX))
    sc[S_REF] = int(cfg.ref_bits > 0)
    for slot, kind in ((S_B_CUR, "current"), (S_B_IN, "input"), (S_B_VLOW, "v_low")):
        sc[slot] = CLAMP_KINDS.index(kind)
    if cfg.X is not None:
        sc[R_X:R_X + 4] = rounding_slots(fv - cfg.X.frac_bits, near)
    if cfg.k_shift is None:
        sc[R_P:R_P + 4] = rounding_slots(cfg.product_shift, near)
    exc = np.asarray(cfg.input_exc, dtype=np.bool_) if cfg.n_inputs else np.zeros(0, np.bool_)
    return LifConstants(as_tuples(tab), as_tuples(sc), as_tuples(trace_table(cfg.traces, fv, near)),
                        exc, tab)


# ----------------------------------------------------------------------------------------------
if available():
    from numba import njit

    from ..lib.kernel import rq as _rq
    from ..lib.kernel import trace_step

    _jit = dict(nogil=True, cache=True, error_model="numpy")

    @njit(inline="always", **_jit)
    def _input(I, acc_a, acc_g, i_syn, sc):
        """Stage 3, ``gather_input``: the clamped current plus the input (the summed weights
        ``acc_a`` of the active sources, or with synapses the trace current ``i_syn``), clamped
        where an input limit is built. Clamps that are not built have levels no int64 passes.
        Returns (D, current flag, input flag)."""
        f_cur = (I < sc[S_ILO]) | (I > sc[S_IHI])
        I = min(max(I, sc[S_ILO]), sc[S_IHI])
        if sc[S_SYN]:
            D = (I << sc[S_ISH]) + i_syn
        else:
            D = (I << sc[S_ISH]) + (acc_a << sc[S_WSH])
        f_in = (D < sc[S_DLO]) | (D > sc[S_DHI])
        return min(max(D, sc[S_DLO]), sc[S_DHI]), f_cur, f_in

    @njit(inline="always", **_jit)
    def _set_consts(tab, s):
        """The constants of parameter set ``s`` (rows of ``tab``, in ``T_*`` order)."""
        return (tab[T_REST][s], tab[T_K][s], tab[T_KSH][s], tab[T_TH][s], tab[T_RESET][s],
                tab[T_NREF][s])

    @njit(inline="always", **_jit)
    def _neuron_consts(pn, i):
        """Neuron ``i``'s set constants from the per-neuron table ``pn`` (6, n)."""
        return (pn[T_REST, i], pn[T_K, i], pn[T_KSH, i], pn[T_TH, i], pn[T_RESET, i],
                pn[T_NREF, i])

    @njit(inline="always", **_jit)
    def _leak_update(v, ref, D, pc, sc):
        """Stages 3-5: ``leak_operand``, ``leak_product``, ``update_state``; ``pc`` holds the
        neuron's set constants (:func:`_set_consts`). Returns (v', ref', spike, v_low,
        v_pre)."""
        x = v - pc[T_REST] - D if sc[S_CONT] else v
        x = _rq(x, sc, R_X)
        if sc[S_KSHIFT]:                   # a per-set shift >= 1
            sh = pc[T_KSH]
            d = (x >> sh) + ((x >> (sh - 1)) & sc[S_NEAR])
        else:
            d = _rq(x * pc[T_K], sc, R_P)
        v_pre = v - d if sc[S_CONT] else v - d + D
        frozen = (ref != 0) & (sc[S_REF] != 0)
        spike = (v_pre >= pc[T_TH]) & ~frozen
        v_low = (v_pre < sc[S_VMIN]) & ~spike & ~frozen
        kept = min(max(v_pre, sc[S_VMIN]), sc[S_VMAX])
        v_new = pc[T_RESET] if (frozen | spike) else kept
        if sc[S_REF]:
            ref_new = ref - 1 if frozen else (pc[T_NREF] if spike else 0)
        else:
            ref_new = ref
        return v_new, ref_new, spike, v_low, v_pre

    @njit(inline="always", **_jit)
    def _clamp_bits(f_cur, f_in, v_low, sc):
        return ((np.int64(f_cur) << sc[S_B_CUR]) | (np.int64(f_in) << sc[S_B_IN])
                | (np.int64(v_low) << sc[S_B_VLOW]))

    @njit(inline="always", **_jit)
    def _traces(tr, sum_a, sum_g, i_syn, sc, ttab):
        """Every neuron's trace current ``I_syn`` (traces as fetched) into ``i_syn``, and its
        four traces decayed in place (``trace_inputs`` .. ``trace_update``)."""
        wsh = sc[S_WSH]
        for i in range(tr.shape[1]):
            t0, t1, t2, t3 = tr[0, i], tr[1, i], tr[2, i], tr[3, i]
            i_syn[i] = (t0 - t1) - (t2 - t3)
            a_sh, g_sh = sum_a[i] << wsh, sum_g[i] << wsh
            tr[0, i] = trace_step(t0 + a_sh, ttab, 0)
            tr[1, i] = trace_step(t1 + a_sh, ttab, 1)
            tr[2, i] = trace_step(t2 + g_sh, ttab, 2)
            tr[3, i] = trace_step(t3 + g_sh, ttab, 3)

    @njit(**_jit)
    def _update_arrays(v, ref, I, sel, x, W, exc, tr, tab, sc, ttab,
                       v_out, ref_out, spike, clamp, v_pre, d_out, acc_out):
        n, F = W.shape
        sum_a, sum_g, i_syn = np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, np.int64)
        for i in range(n):
            for f in range(F):
                if x[f]:
                    if exc[f] or not sc[S_SYN]:
                        sum_a[i] += W[i, f]
                    else:
                        sum_g[i] += W[i, f]
        if sc[S_SYN]:
            _traces(tr, sum_a, sum_g, i_syn, sc, ttab)
        for i in range(n):
            D, f_cur, f_in = _input(I[i], sum_a[i], sum_g[i], i_syn[i], sc)
            a, b, c, v_low, e = _leak_update(v[i], ref[i], D, _set_consts(tab, sel[i]), sc)
            v_out[i] = a
            ref_out[i] = b
            spike[i] = c
            clamp[i] = _clamp_bits(f_cur, f_in, v_low, sc)
            v_pre[i] = e
            d_out[i] = D
            acc_out[i] = sum_a[i] - sum_g[i]

    @njit(inline="always", **_jit)
    def _input_sums(W, act, n_act, out):
        """``out[i] = sum_j W[i, act[j]]`` over the ``n_act`` active sources."""
        for i in range(out.shape[0]):
            t = 0
            for j in range(n_act):
                t += W[i, act[j]]
            out[i] = t

    @njit(**_jit)
    def _run(v, ref, tr, I, per_sweep, sel, W, exc, X, has_x, tab, tab_a, sc, ttab, k0, n_sweeps,
             spk_k, spk_n, n_spk, totals, last, flags, fwords):
        """Sweeps ``k0 .. n_sweeps - 1`` of a program, in place. ``I`` is (n_sweeps, N) when
        ``per_sweep`` else (1, N); ``X`` (n_sweeps, F) input spikes when ``has_x``. Spikes are
        appended to (spk_k, spk_n) from ``n_spk``; stops early (before a sweep) when the buffer
        could overflow. Returns (next sweep, spikes recorded)."""
        N = v.shape[0]
        F = W.shape[1]
        act_a = np.empty(F, np.int64)
        act_g = np.empty(F, np.int64)
        sum_a = np.zeros(N, np.int64)
        sum_g = np.zeros(N, np.int64)
        held_a = held_g = False           # the sums hold a previous tick's inputs
        i_syn = np.zeros(N, np.int64)
        cap = spk_k.shape[0]
        syn = sc[S_SYN] != 0
        uniform = len(tab[0]) == 1        # one parameter set: constants, no per-neuron gather
        pn = np.empty((6, N if not uniform else 0), np.int64)
        if not uniform:                   # else each neuron's set constants, gathered once
            for r in range(6):
                for i in range(N):
                    pn[r, i] = tab_a[r, sel[i]]
        for k in range(k0, n_sweeps):
            if cap - n_spk < N:
                return k, n_spk
            na = 0
            ng = 0
            if has_x:
                for f in range(F):
                    if X[k, f]:
                        if exc[f] or not syn:
                            act_a[na] = f
                            na += 1
                        else:
                            act_g[ng] = f
                            ng += 1
            row = k if per_sweep else 0
            # the tick's input sums first (a separate loop keeps the update loop simple)
            if na or held_a:
                _input_sums(W, act_a, na, sum_a)
                held_a = na != 0
            if ng or held_g:
                _input_sums(W, act_g, ng, sum_g)
                held_g = ng != 0
            c0 = c1 = c2 = 0
            hits = 0
            if syn:                        # the traces first: I_syn of this tick, decays
                _traces(tr, sum_a, sum_g, i_syn, sc, ttab)
            for i in range(N):
                D, f_cur, f_in = _input(I[row, i], sum_a[i], sum_g[i], i_syn[i], sc)
                pc = _set_consts(tab, 0) if uniform else _neuron_consts(pn, i)
                a, b, spk, v_low, _ = _leak_update(v[i], ref[i], D, pc, sc)
                v[i] = a
                ref[i] = b
                flags[i] = spk
                hits += spk
                c0 += f_cur
                c1 += f_in
                c2 += v_low
            if hits:
                n_spk = record(flags, fwords, k, spk_k, spk_n, n_spk)
            last[0] = c0
            last[1] = c1
            last[2] = c2
            totals[0] += c0
            totals[1] += c1
            totals[2] += c2
        return n_sweeps, n_spk


def update_arrays(consts: LifConstants, v, ref, I, sel, x, W, traces):
    """One update of the given neurons by the kernel (1-D int64 arrays; ``x`` the tick's
    input-spike vector, ``W`` the (n, n_inputs) raw weights, ``traces`` (4, n) or None).
    Returns a dict like :meth:`cuneate.hdl.lif.LifTwin.update` (``v``, ``ref``, ``spike``,
    ``clamp``, ``v_pre``, ``d``, ``acc`` and ``traces`` with synapses)."""
    n = v.shape[0]
    tr = (np.zeros((1, n), np.int64) if traces is None
          else np.array(traces, dtype=np.int64, order="C"))
    out = {k: np.empty(n, np.int64) for k in ("v", "ref", "clamp", "v_pre", "d", "acc")}
    out["spike"] = np.empty(n, np.bool_)
    xs = np.zeros(W.shape[1], np.bool_) if x is None else np.asarray(x, dtype=np.bool_)
    _update_arrays(v, ref, I, sel, xs, W, consts.exc, tr, consts.tab, consts.sc, consts.ttab,
                   out["v"], out["ref"], out["spike"], out["clamp"], out["v_pre"], out["d"],
                   out["acc"])
    if traces is not None:
        out["traces"] = tr
    return out


def run_program(consts: LifConstants, v, ref, traces, I, sel, W, inputs, n_sweeps: int,
                threads: int | None = None):
    """``n_sweeps`` sweeps in place on ``v``, ``ref``, ``traces`` (int64; ``traces`` (4, n) or
    a dummy (1, n)). ``I``: raw currents, (n,) for the whole run or (n_sweeps, n) per sweep;
    ``inputs``: (n_sweeps, n_inputs) input spikes or None. Populations of at least
    :data:`~cuneate.hdl.lib.kernel.PARALLEL_MIN_NEURONS` are split over ``threads``
    (default: all cores) contiguous chunks, each run by the GIL-free kernel (neurons are
    independent given their currents and input spikes).

    Returns ``(spike_sweeps, spike_neurons, totals, last)``: every spike as (sweep, neuron),
    clamp counts per kind over the run and in its last sweep."""
    N = v.shape[0]
    per_sweep = I.ndim == 2
    I2 = I if per_sweep else I.reshape(1, N)
    has_x = inputs is not None
    X = np.asarray(inputs, dtype=np.bool_) if has_x else np.zeros((1, 1), np.bool_)
    threads = default_threads(N) if threads is None else max(1, min(int(threads), N))
    syn = bool(consts.sc[S_SYN])

    def chunk(lo, hi):
        n = hi - lo
        vv, rr, ss, ww = v[lo:hi], ref[lo:hi], sel[lo:hi], W[lo:hi]
        tt = traces[:, lo:hi] if syn else traces[:1, lo:hi]
        totals = np.zeros(len(CLAMP_KINDS), np.int64)
        last = np.zeros(len(CLAMP_KINDS), np.int64)
        cap = max(4 * n, 1024)
        spk_k, spk_n = np.empty(cap, np.int64), np.empty(cap, np.int64)
        flags = np.zeros((n + 7) // 8 * 8, np.bool_)       # whole words for record
        k, n_spk = 0, 0
        while k < n_sweeps:
            k, n_spk = _run(vv, rr, tt, I2[:, lo:hi], per_sweep, ss, ww, consts.exc, X, has_x,
                            consts.tab, consts.tab_array, consts.sc, consts.ttab, k, n_sweeps,
                            spk_k, spk_n, n_spk, totals, last, flags,
                            flags.view(np.uint64))
            if k < n_sweeps:                   # buffer full: grow and go on
                cap *= 2
                spk_k, spk_n = np.resize(spk_k, cap), np.resize(spk_n, cap)
        return spk_k[:n_spk], spk_n[:n_spk] + lo, totals, last

    return split_over_threads(chunk, N, threads if n_sweeps else 1)
