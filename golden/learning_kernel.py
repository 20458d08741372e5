"""The compiled (numba) loop of the learning cuneate layer (:mod:`cuneate.golden.cuneate_layer`)
with its rules (:mod:`cuneate.golden.aidp`, :mod:`cuneate.golden.stdp`): the reference tick
loop's operations per CN and synapse, in the same order."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["run_layer"]

_KERNEL: dict = {}

#: rule codes of the loop
_CODES = {"none": 0, "aidp": 1, "stdp": 2}


def _kernel():
    if "run" in _KERNEL:
        return _KERNEL["run"]
    from numba import njit

    from .kernel import record_presentation

    @njit(nogil=True, cache=True)
    def run(ev_t, ev_s, off, n_ticks, win, src, S, w, flags, rule, dt, ks, g, iz, rp,
            snap_every, snaps, steps, counts, sp_p, sp_k, sp_j):
        M, K = src.shape
        a, b, c, d, A, B, C = iz[0], iz[1], iz[2], iz[3], iz[4], iz[5], iz[6]
        E = np.zeros(M)
        H = 0.0
        v = np.full(M, -65.0)
        u = b * v
        I = np.zeros(M)
        # AIDP: rp = kd, kr, alpha, theta, eta, wmax, w_pot, w_dep, slope, lat
        # STDP: rp = kp, km, a_plus, a_minus, wmax
        lat = int(rp[9]) if rule != 2 else 0
        cd = np.zeros((M, K))
        cr = np.zeros((M, K))
        L = np.zeros((M, K))
        ring = np.zeros((lat + 1, S), dtype=np.bool_)
        x = np.zeros(S)
        y = np.zeros(M)
        s = np.zeros(S, dtype=np.bool_)
        hit = np.zeros(M, dtype=np.bool_)
        wb = np.empty((M, K))
        n_sp = 0
        n_snap = 1
        drive_max = 0.0
        snaps[0] = w
        for q in range(off.shape[0] - 1):
            e = off[q]
            wb[:, :] = w
            for k in range(n_ticks):
                s[:] = False
                while e < off[q + 1] and ev_t[e] == k:
                    s[ev_s[e]] = True
                    e += 1
                nspk = 0.0
                for i in range(S):
                    nspk += s[i]
                for j in range(M):
                    I[j] = E[j] - g * H
                if rule == 1:
                    ring[k % (lat + 1)] = s
                    slot = (k - lat) % (lat + 1)
                    for j in range(M):
                        Z = I[j] - rp[3]
                        for m in range(K):
                            L[j, m] = L[j, m] + rp[2] * (cd[j, m] - cr[j, m]) * Z * dt
                            xin = w[j, m] * ring[slot, src[j, m]]
                            cd[j, m] = (cd[j, m] + xin) * rp[0]
                            cr[j, m] = (cr[j, m] + xin) * rp[1]
                for j in range(M):
                    acc = 0.0
                    for m in range(K):
                        acc = acc + w[j, m] * s[src[j, m]]
                    E[j] = (E[j] + acc) * ks
                H = (H + nspk) * ks
                for j in range(M):
                    vj, uj = v[j], u[j]
                    vn = vj + dt * (A * vj * vj + B * vj + C - uj + I[j])
                    un = uj + dt * (a * (b * vj - uj))
                    hit[j] = vn >= 30.0
                    v[j] = c if hit[j] else vn
                    u[j] = un + d if hit[j] else un
                if rule == 2 and flags[q]:
                    for j in range(M):
                        for m in range(K):
                            dw = -rp[3] * (y[j] if s[src[j, m]] else 0.0)
                            dw = dw + rp[2] * (x[src[j, m]] if hit[j] else 0.0)
                            w[j, m] = min(max(w[j, m] + dw, 0.0), rp[4])
                if rule == 2:
                    for i in range(S):
                        x[i] = (x[i] + s[i]) * rp[0]
                    for j in range(M):
                        y[j] = (y[j] + hit[j]) * rp[1]
                n_sp = record_presentation(hit, M, q, k, win, sp_p, sp_k, sp_j, n_sp, counts)
                if n_sp < 0:
                    return -1, n_snap, drive_max
            if rule == 1:
                for j in range(M):
                    tot = 0.0
                    for m in range(K):
                        tot = tot + L[j, m]
                        drive_max = max(drive_max, abs(L[j, m]))
                    mean = tot / K
                    if flags[q]:
                        for m in range(K):
                            D = L[j, m] - mean
                            wj = w[j, m]
                            if D > 0:
                                sg = 1.0 / (1.0 + math.exp((wj - rp[6]) / rp[8]))
                            else:
                                sg = 1.0 / (1.0 + math.exp(-(wj - rp[7]) / rp[8]))
                            w[j, m] = min(max(wj + rp[4] * D * sg, 0.0), rp[5])
                    for m in range(K):
                        L[j, m] = 0.0
            tot = 0.0
            for j in range(M):
                for m in range(K):
                    tot += abs(w[j, m] - wb[j, m])
            steps[q] = tot / (M * K)
            if snap_every > 0 and (q + 1) % snap_every == 0:
                snaps[n_snap] = w
                n_snap += 1
        return n_sp, n_snap, drive_max

    _KERNEL["run"] = run
    return run


def run_layer(pres, w, layer, rule, p, flags, snapshot_every):
    """Run the compiled loop (see :func:`cuneate.golden.cuneate_layer.simulate_layer`);
    returns the fields of its ``LayerResult`` in order (weights, counts, spike_pres,
    spike_tick, spike_cn, step, snapshots, drive_max)."""
    run = _kernel()
    src = np.ascontiguousarray(layer.sources, dtype=np.int64)
    M, K = src.shape
    dt = float(layer.dt_ms)
    if rule == "stdp":
        rp = np.array([math.exp(-dt / p.tau_plus_ms), math.exp(-dt / p.tau_minus_ms), p.a_plus,
                       p.a_minus, p.w_max, 0, 0, 0, 0, 0], dtype=np.float64)
    else:
        rp = np.array([math.exp(-dt / p.tau_decay_ms), math.exp(-dt / p.tau_rise_ms), p.alpha,
                       p.theta, p.eta, p.w_max, p.w_pot, p.w_dep, p.slope,
                       p.latency_ticks(dt)], dtype=np.float64)
    n_snap = 1 + (pres.n // snapshot_every if snapshot_every else 0)
    snaps = np.zeros((n_snap, M, K))
    steps = np.zeros(pres.n)
    counts = np.zeros((pres.n, M), dtype=np.int64)
    cap = max(1024, 4 * M * pres.n)
    while True:
        sp = [np.zeros(cap, dtype=np.int64) for _ in range(3)]
        w_run = w.copy()
        counts[:] = 0
        n_sp, got, drive_max = run(pres.ticks, pres.sources, pres.offsets, pres.n_ticks,
                                   pres.window_ticks, src, layer.n_sources, w_run, flags,
                                   _CODES[rule], dt, math.exp(-dt / layer.tau_syn_ms),
                                   float(layer.g_inh), np.array(layer.izhikevich()), rp,
                                   snapshot_every, snaps, steps, counts, *sp)
        if n_sp >= 0:
            break
        cap *= 4                      # the spike buffer filled: run again with a larger one
    idx = [0] + [(i + 1) * snapshot_every for i in range(got - 1)]
    return (w_run, counts.copy(), sp[0][:n_sp], sp[1][:n_sp], sp[2][:n_sp], steps,
            [(i, snaps[n].copy()) for n, i in enumerate(idx)], drive_max)
