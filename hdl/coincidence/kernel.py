"""Compiled (numba) kernel of the coincidence detector's twin.

A tick of :class:`cuneate.hdl.coincidence.CoincidenceTwin` - stamp the pending input spikes into the
history ring, sum each target's delayed weighted inputs (``accumulate``), the PSP current and
trace inputs (``psp_current``), the two trace decays (``trace_products`` / ``trace_update`` of
:mod:`cuneate.hdl.lib.synapses`) and the Izhikevich update (``operands`` .. ``update_state``) -
restated per target with the same integer operations in the same order, one compiled loop over a
whole run. The Izhikevich step is the Izhikevich kernel's
(:mod:`cuneate.hdl.izhikevich.kernel`) and the trace step the shared one
(:mod:`cuneate.hdl.lib.kernel`), so each integer operation is restated once. Proven bit-exact
against the stage-function twin by property tests (random states, traces and input sums) and
long runs (``tests/hdl/test_coincidence_kernel.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..izhikevich import kernel as izk
from ..lib.kernel import as_tuples, available, record, rounding_slots, trace_table
from .config import CLAMP_KINDS

assert len(CLAMP_KINDS) == 5                       # the run loop counts five kinds

__all__ = ["available", "CoincidenceConstants", "gather_constants", "update_arrays",
           "run_ticks"]

S_WSH = 0              # input-sum shift into trace fraction bits
R_I = 1                # rounding slots of the PSP current (4)
N_SCALARS = 5


@dataclass(frozen=True)
class CoincidenceConstants:
    """Everything the kernel needs of one :class:`CoincidenceConfig`."""
    sc: tuple               # N_SCALARS ints
    ttab: tuple             # 2 rows of N_TRACE_COLS ints: decay (xd) and rise (xr) traces
    iz: tuple               # the Izhikevich kernel's (table, scalars)
    delays: np.ndarray      # (n_targets, n_sources) int64
    weights: np.ndarray     # (n_targets, n_sources) int64, raw


def gather_constants(cfg) -> CoincidenceConstants:
    """The constants of a :class:`cuneate.hdl.coincidence.CoincidenceConfig`."""
    near = cfg.rounding == "nearest"
    sc = np.zeros(N_SCALARS, dtype=np.int64)
    sc[S_WSH] = cfg.wshift
    sc[R_I:R_I + 4] = rounding_slots(cfg.i_shift, near)
    if cfg.wshift < 0:
        raise ValueError("the compiled coincidence kernel needs weights with at most the "
                         "traces' fraction bits")
    return CoincidenceConstants(
        as_tuples(sc), as_tuples(trace_table(cfg.tview.traces, cfg.tview.V.frac_bits, near)),
        izk.gather_constants(cfg.iz), np.ascontiguousarray(cfg.delays, dtype=np.int64),
        np.ascontiguousarray(cfg.weights_raw, dtype=np.int64))


if available():
    from numba import njit

    from ..izhikevich.kernel import neuron_update as _iz_neuron
    from ..lib.kernel import rq as _rq
    from ..lib.kernel import trace_step

    _jit = dict(nogil=True, cache=True, error_model="numpy")

    @njit(inline="always", **_jit)
    def _target(v, u, xd, xr, a, s, sc, ttab, iztab, izsc):
        """One target update from its input sum ``a`` (raw weight LSBs). Returns
        (v', u', xd', xr', spike, clamp bits, current)."""
        i = _rq(xd - xr, sc, R_I)
        yd = xd + (a << sc[S_WSH])
        yr = xr + (a << sc[S_WSH])
        xd_new = trace_step(yd, ttab, 0)
        xr_new = trace_step(yr, ttab, 1)
        v_new, u_new, spike, clamp, _ = _iz_neuron(v, u, i, s, iztab, izsc)
        return v_new, u_new, xd_new, xr_new, spike, clamp, i

    @njit(**_jit)
    def _update_arrays(v, u, xd, xr, a, sel, sc, ttab, iztab, izsc, v_out, u_out, xd_out,
                       xr_out, spike, clamp, cur):
        for t in range(v.shape[0]):
            r = _target(v[t], u[t], xd[t], xr[t], a[t], sel[t], sc, ttab, iztab, izsc)
            v_out[t] = r[0]
            u_out[t] = r[1]
            xd_out[t] = r[2]
            xr_out[t] = r[3]
            spike[t] = r[4]
            clamp[t] = r[5]
            cur[t] = r[6]

    @njit(**_jit)
    def _run(v, u, xd, xr, sel, history, pend, tick0, delays, W, sc, ttab, iztab, izsc, k0,
             n_ticks, spk_k, spk_n, n_spk, totals, flags, fwords):
        """Ticks ``k0 .. n_ticks - 1`` in place; tick ``k`` stamps ``pend[k]`` into history
        slot ``(tick0 + k) mod D``. Returns (next tick, spikes recorded); stops early when the
        spike buffer could overflow."""
        M, S = W.shape
        D = history.shape[0]
        cap = spk_k.shape[0]
        acc = np.zeros(M, np.int64)
        uniform = len(iztab[0]) == 1          # one parameter set: no per-target gather
        for k in range(k0, n_ticks):
            if cap - n_spk < M:
                return k, n_spk
            hits = 0
            c0 = c1 = c2 = c3 = c4 = 0
            T = tick0 + k
            slot = T % D
            for s in range(S):
                history[slot, s] = pend[k, s]
            for t in range(M):                   # the tick's input sums first
                a = 0
                for s in range(S):
                    h = slot - delays[t, s]           # (T - delay) mod D, 0 <= delay < D
                    if history[h + D if h < 0 else h, s]:
                        a += W[t, s]
                acc[t] = a
            for t in range(M):
                r = _target(v[t], u[t], xd[t], xr[t], acc[t], 0 if uniform else sel[t], sc,
                            ttab, iztab, izsc)
                v[t] = r[0]
                u[t] = r[1]
                xd[t] = r[2]
                xr[t] = r[3]
                flags[t] = r[4]
                hits += r[4]
                cl = r[5]
                c0 += cl & 1
                c1 += (cl >> 1) & 1
                c2 += (cl >> 2) & 1
                c3 += (cl >> 3) & 1
                c4 += (cl >> 4) & 1
            if hits:
                n_spk = record(flags, fwords, k, spk_k, spk_n, n_spk)
            totals[0] += c0
            totals[1] += c1
            totals[2] += c2
            totals[3] += c3
            totals[4] += c4
        return n_ticks, n_spk


def update_arrays(consts: CoincidenceConstants, v, u, xd, xr, a, sel) -> dict:
    """One update of the given targets from any state (1-D int64 arrays); returns ``v``,
    ``u``, ``xd``, ``xr``, ``spike``, ``clamp`` (bits) and ``i`` (the PSP current)."""
    n = v.shape[0]
    out = {k: np.empty(n, np.int64) for k in ("v", "u", "xd", "xr", "clamp", "i")}
    out["spike"] = np.empty(n, np.bool_)
    tab, sc_iz = consts.iz
    _update_arrays(v, u, xd, xr, a, sel, consts.sc, consts.ttab, tab, sc_iz, out["v"],
                   out["u"], out["xd"], out["xr"], out["spike"], out["clamp"], out["i"])
    return out


def run_ticks(consts: CoincidenceConstants, v, u, xd, xr, sel, history, pending, tick0: int):
    """Run ``len(pending)`` ticks in place on the targets' state and the history ring
    (``pending`` (n_ticks, n_sources) bool: the spikes each tick stamps). Returns
    ``(spike_ticks, spike_targets, clamp_totals)``; ticks counted from 0 at this call."""
    M = v.shape[0]
    n_ticks = pending.shape[0]
    totals = np.zeros(len(CLAMP_KINDS), np.int64)
    cap = max(4 * M, 1024)
    spk_k, spk_n = np.empty(cap, np.int64), np.empty(cap, np.int64)
    tab, sc_iz = consts.iz
    flags = np.zeros((M + 7) // 8 * 8, np.bool_)           # whole words for record
    k, n_spk = 0, 0
    while k < n_ticks:
        k, n_spk = _run(v, u, xd, xr, sel, history, pending, tick0, consts.delays,
                        consts.weights, consts.sc, consts.ttab, tab, sc_iz, k, n_ticks, spk_k,
                        spk_n, n_spk, totals, flags, flags.view(np.uint64))
        if k < n_ticks:
            cap *= 2
            spk_k, spk_n = np.resize(spk_k, cap), np.resize(spk_n, cap)
    return spk_k[:n_spk], spk_n[:n_spk], totals
