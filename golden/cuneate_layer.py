"""A cuneate layer that learns, float64: Izhikevich cuneate neurons (CNs) on afferent synapses
with a lumped inhibitory interneuron, presented with jittered afferent spike patterns, learning
with AIDP (:mod:`cuneate.golden.aidp`) or pair-based STDP (:mod:`cuneate.golden.stdp`), or not
at all.

Equations
---------
``S`` afferents, ``M`` CNs of ``K`` synapses each: synapse ``m`` of CN ``j`` takes afferent
``src[j, m]`` (a fixed anatomy: each CN reaches a subset of the afferents) with weight ``w_jm``
(mV/ms). Excitation and the lumped inhibition are synaptic currents decaying with
``tau_syn`` = 6.4 ms (brief section 5b)::

    dE_j/dt = -E_j / tau_syn + sum_m w_jm sum_l delta(t - t_l^src[j,m])    (excitation)
    dH/dt   = -H / tau_syn + sum_i sum_l delta(t - t_l^i)                  (the interneuron)
    I_j     = E_j - g H                                                    (net drive, mV/ms)
    dv/dt   = A v^2 + B v + C - u + I_j,   du/dt = a (b v - u)             (Izhikevich CN)
    v >= 30 mV:  v <- c, u <- u + d

The interneuron is lumped (one for the layer): driven by every afferent with equal weights, its
inhibition ``g H`` grows with the stimulus's intensity, the same for every CN (the brief's
compound IPSP). ``I_j`` is also the CN's main calcium of AIDP.

Integration scheme, on a tick grid of ``dt`` (0.5 ms: 2 kHz): an afferent spike at ``t`` is
stamped with tick ``floor(t / dt)``. In tick ``k``, with every state as fetched at the tick's
start: ``I_j(k) = E_j(k) - g H(k)``; the learning rule's tick (AIDP: the calcium traces and the
drive integral; STDP: its pairs); the traces take the tick's spikes and decay exactly,
``E_j(k+1) = (E_j(k) + sum_m w_jm s_src(k)) exp(-dt/tau_syn)`` and ``H(k+1) = (H(k) + n(k))
exp(-dt/tau_syn)`` (``n(k)`` the afferent spikes of the tick), so a spike first drives the CN
one tick later; the CN takes one forward-Euler step with ``I_j(k)`` (both ``v`` and ``u`` from
the old state), and a spike of that step is reported in tick ``k`` (at ``(k + 1) dt`` ms).

Presentations (:func:`presentations`): a stimulus's afferent spike trains (its template) cut to
a window, every spike moved by its own Gaussian jitter, stamped on the grid (two spikes of one
afferent in one tick are one spike: counted as ``merged``), followed by a silent gap in which
the traces relax; presented in a given order. AIDP's window is one presentation (its step at the
presentation's end, gap included).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import aidp as gaidp
from . import stdp as gstdp
from .izhikevich import spike_times, to_params
from .validate import number

__all__ = ["LayerParams", "Presentations", "presentations", "LayerResult", "simulate_layer",
           "RULES", "V_TH"]

#: the learning rules a layer takes
RULES = ("none", "aidp", "stdp")
#: spike threshold of the Izhikevich CNs (mV)
V_TH = 30.0


@dataclass(frozen=True)
class LayerParams:
    """The layer: ``sources`` ``(M, K)`` afferent of each synapse, ``n_sources``, the tick
    ``dt_ms``, ``tau_syn_ms``, the inhibition ``g`` (mV/ms per unit of ``H``) and the CNs'
    Izhikevich parameter set (a preset name or parameters)."""

    sources: np.ndarray
    n_sources: int
    dt_ms: float = 0.5
    tau_syn_ms: float = 6.4
    g_inh: float = 0.3
    cn: object = "RS"

    def __post_init__(self):
        src = np.asarray(self.sources)
        if src.ndim != 2 or src.shape[0] < 1 or src.shape[1] < 1:
            raise ValueError(f"sources must be (n_cn, synapses per CN), got shape {src.shape}")
        if src.min() < 0 or src.max() >= self.n_sources:
            raise ValueError(f"a synapse's source is outside 0 .. {self.n_sources - 1}")
        for row in src:
            if len(np.unique(row)) != len(row):
                raise ValueError("a CN takes each afferent at most once")
        number(self.dt_ms, "dt_ms", positive=True)
        number(self.tau_syn_ms, "tau_syn_ms", positive=True)
        number(self.g_inh, "g_inh", nonneg=True)

    @property
    def n_cn(self) -> int:
        return int(np.shape(self.sources)[0])

    @property
    def synapses_per_cn(self) -> int:
        return int(np.shape(self.sources)[1])

    def izhikevich(self) -> tuple:
        """``(a, b, c, d, A, B, C)`` of the CNs (standard u-equation only)."""
        p = to_params(self.cn)
        if p.u_leak != 1.0 or p.v_u != 0.0:
            raise ValueError("the layer's CNs take the standard u-equation du/dt = a (b v - u)")
        return (p.a, p.b, p.c, p.d, p.A, p.B, p.C)


@dataclass
class Presentations:
    """Jittered presentations as events: presentation ``p`` holds the events
    ``offsets[p]:offsets[p+1]`` of ``(ticks, sources)`` (tick-major), each presentation
    ``n_ticks`` ticks (input in its first ``window_ticks``)."""

    ticks: np.ndarray
    sources: np.ndarray
    offsets: np.ndarray
    n_ticks: int
    window_ticks: int
    order: np.ndarray
    dt_ms: float
    merged: int = 0

    @property
    def n(self) -> int:
        return len(self.offsets) - 1

    def select(self, idx) -> "Presentations":
        """The presentations ``idx`` (in that order)."""
        idx = np.asarray(idx, dtype=np.int64)
        parts = [(self.ticks[self.offsets[p]:self.offsets[p + 1]],
                  self.sources[self.offsets[p]:self.offsets[p + 1]]) for p in idx]
        off = np.concatenate([[0], np.cumsum([len(t) for t, _ in parts])]).astype(np.int64)
        cat = (lambda k: np.concatenate([x[k] for x in parts]) if parts else
               np.zeros(0, np.int64))
        return Presentations(cat(0).astype(np.int64), cat(1).astype(np.int64), off,
                             self.n_ticks, self.window_ticks, self.order[idx], self.dt_ms)

    def dense(self, p: int, n_sources: int) -> np.ndarray:
        """Presentation ``p`` as ``(n_ticks, n_sources)`` bool."""
        out = np.zeros((self.n_ticks, n_sources), dtype=bool)
        a, b = self.offsets[p], self.offsets[p + 1]
        out[self.ticks[a:b], self.sources[a:b]] = True
        return out


def presentations(templates, order, window_ms, dt_ms: float, jitter_ms: float, gap_ms: float,
                  seed) -> Presentations:
    """Jittered presentations (see the module docstring): ``templates[c]`` a list of spike-time
    arrays (ms), one per afferent, of stimulus ``c``; ``order`` the stimulus of each
    presentation; spikes within ``window_ms = (t0, t1)`` after jitter count, at
    ``t - t0``; ``seed`` seeds the jitter (one generator for the whole sequence)."""
    t0, t1 = (float(x) for x in window_ms)
    dt = number(dt_ms, "dt_ms", positive=True)
    if not t1 > t0:
        raise ValueError(f"window_ms must be (t0, t1) with t1 > t0, got {window_ms!r}")
    number(jitter_ms, "jitter_ms", nonneg=True)
    gap = number(gap_ms, "gap_ms", nonneg=True)
    win = int(round((t1 - t0) / dt))
    n_ticks = win + int(round(gap / dt))
    rng = np.random.default_rng(seed)
    order = np.asarray(order, dtype=np.int64)
    ticks, srcs, off, merged = [], [], [0], 0
    reach = 6.0 * jitter_ms
    for c in order:
        tk, sr = [], []
        for i, st in enumerate(templates[c]):
            st = np.asarray(st, dtype=np.float64)
            st = st[(st >= t0 - reach) & (st < t1 + reach)]
            t = st + rng.normal(0.0, jitter_ms, st.size) if jitter_ms > 0 else st
            k = np.floor((t[(t >= t0) & (t < t1)] - t0) / dt).astype(np.int64)
            k = k[(k >= 0) & (k < win)]
            u = np.unique(k)
            merged += k.size - u.size
            tk.append(u)
            sr.append(np.full(u.size, i, dtype=np.int64))
        tk, sr = np.concatenate(tk), np.concatenate(sr)
        o = np.lexsort((sr, tk))
        ticks.append(tk[o])
        srcs.append(sr[o])
        off.append(off[-1] + tk.size)
    cat = (lambda xs: np.concatenate(xs) if xs else np.zeros(0, np.int64))
    return Presentations(cat(ticks), cat(srcs), np.asarray(off, dtype=np.int64), n_ticks, win,
                         order, dt, merged)


@dataclass
class LayerResult:
    """A layer's run: the final ``weights`` ``(M, K)``; per presentation the CNs' spike counts
    within the window (``counts``, ``(n, M)``), every CN spike (``spike_pres``, ``spike_tick``,
    ``spike_cn``), the mean absolute weight step (``step``) and the weights after it at every
    ``snapshot_every``-th presentation (``snapshots``: ``(index, (M, K))`` pairs, the initial
    weights first); ``drive_max``: the largest ``|L|`` an AIDP window reached."""

    weights: np.ndarray
    counts: np.ndarray
    spike_pres: np.ndarray
    spike_tick: np.ndarray
    spike_cn: np.ndarray
    step: np.ndarray
    snapshots: list = field(default_factory=list)
    drive_max: float = 0.0
    seconds: float = 0.0

    def trains(self, dt_ms: float, window_ticks: int | None = None) -> list[list[np.ndarray]]:
        """Spike times (ms from the presentation's start, ``(k + 1) dt``) per presentation per
        CN (within the first ``window_ticks`` ticks when given)."""
        M = self.counts.shape[1]
        keep = np.ones(self.spike_tick.size, bool) if window_ticks is None else \
            self.spike_tick < window_ticks
        out = [[np.zeros(0) for _ in range(M)] for _ in range(self.counts.shape[0])]
        for p, k, j in zip(self.spike_pres[keep], self.spike_tick[keep], self.spike_cn[keep]):
            out[p][j] = np.append(out[p][j], spike_times(k, dt_ms))
        return out


def _rule_args(rule, params, layer):
    if rule not in RULES:
        raise ValueError(f"unknown learning rule {rule!r}; known: {', '.join(RULES)}")
    if rule == "stdp":
        p = params if params is not None else gstdp.StdpParams()
        if not isinstance(p, gstdp.StdpParams):
            raise ValueError("rule 'stdp' takes StdpParams")
        return p
    p = params if params is not None else gaidp.AidpParams()
    if not isinstance(p, gaidp.AidpParams):
        raise ValueError(f"rule {rule!r} takes AidpParams")
    p.latency_ticks(layer.dt_ms)
    return p


def simulate_layer(pres: Presentations, w0, layer: LayerParams, rule: str = "aidp",
                   params=None, learn=True, snapshot_every: int = 0,
                   kernel: str | None = None) -> LayerResult:
    """Run the layer through every presentation of ``pres`` from the weights ``w0``
    (``(M, K)``, mV/ms). ``learn``: one flag per presentation (or one for all): AIDP applies
    its step at that presentation's end (else only clears the drives), STDP learns during it.
    ``kernel``: ``"numba"`` (the compiled loop, :mod:`cuneate.golden.learning_kernel`, default
    where numba is available) or ``"numpy"`` (the tick loop below, the reference)."""
    import time
    from .kernel import available
    p = _rule_args(rule, params, layer)
    w = np.array(w0, dtype=np.float64)
    if w.shape != np.shape(layer.sources):
        raise ValueError(f"w0 must have shape {np.shape(layer.sources)}, got {w.shape}")
    wmax = p.w_max
    if np.any(~np.isfinite(w)) or w.min() < 0 or w.max() > wmax:
        raise ValueError(f"w0 must lie in [0, w_max = {wmax:g}] mV/ms")
    if abs(pres.dt_ms - layer.dt_ms) > 1e-12:
        raise ValueError(f"the presentations' dt ({pres.dt_ms:g} ms) is not the layer's "
                         f"({layer.dt_ms:g} ms)")
    flags = np.broadcast_to(np.asarray(learn, dtype=bool), (pres.n,)).copy()
    kernel = kernel or ("numba" if available() else "numpy")
    t0 = time.perf_counter()
    if kernel == "numba":
        from .learning_kernel import run_layer
        res = LayerResult(*run_layer(pres, w, layer, rule, p, flags, snapshot_every))
    elif kernel == "numpy":
        res = _run_numpy(pres, w, layer, rule, p, flags, snapshot_every)
    else:
        raise ValueError(f"unknown kernel {kernel!r}; known: numba, numpy")
    res.seconds = time.perf_counter() - t0
    return res


def _run_numpy(pres, w, layer, rule, p, flags, snapshot_every) -> LayerResult:
    """The reference: one tick at a time, vectorized over CNs and synapses."""
    src = np.asarray(layer.sources, dtype=np.int64)
    M, K = src.shape
    S, dt = layer.n_sources, layer.dt_ms
    a, b, c, d, A, B, C = layer.izhikevich()
    ks = np.exp(-dt / layer.tau_syn_ms)
    E, H = np.zeros(M), 0.0
    v = np.full(M, -65.0)
    u = b * v
    if rule == "stdp":
        kp, km = np.exp(-dt / p.tau_plus_ms), np.exp(-dt / p.tau_minus_ms)
        x, y = np.zeros(S), np.zeros(M)
    else:
        kd, kr = np.exp(-dt / p.tau_decay_ms), np.exp(-dt / p.tau_rise_ms)
        lat = p.latency_ticks(dt)
        cd, cr, L = np.zeros((M, K)), np.zeros((M, K)), np.zeros((M, K))
        ring = np.zeros((lat + 1, S), dtype=bool)
    counts = np.zeros((pres.n, M), dtype=np.int64)
    sp_p, sp_k, sp_j, steps, snaps = [], [], [], np.zeros(pres.n), [(0, w.copy())]
    drive_max = 0.0
    for q in range(pres.n):
        spk = pres.dense(q, S)
        w_before = w.copy()
        for k in range(pres.n_ticks):
            s = spk[k]
            I = E - layer.g_inh * H
            if rule == "aidp":
                ring[k % (lat + 1)] = s
                sd = ring[(k - lat) % (lat + 1)]
                L = L + p.alpha * (cd - cr) * (I - p.theta)[:, None] * dt
                x_in = w * sd[src]
                cd, cr = (cd + x_in) * kd, (cr + x_in) * kr
            a_in = np.zeros(M)
            for m in range(K):                       # summed in synapse order, as the loops do
                a_in = a_in + w[:, m] * s[src[:, m]]
            E = (E + a_in) * ks
            H = (H + s.sum()) * ks
            vn = v + dt * (A * v * v + B * v + C - u + I)
            un = u + dt * (a * (b * v - u))
            hit = vn >= V_TH
            v, u = np.where(hit, c, vn), np.where(hit, un + d, un)
            if rule == "stdp" and flags[q]:
                w = gstdp.step(w, x[src], y, s[src], hit, p)
            if rule == "stdp":
                x, y = (x + s) * kp, (y + hit) * km
            for j in np.flatnonzero(hit):
                sp_p.append(q)
                sp_k.append(k)
                sp_j.append(j)
                counts[q, j] += k < pres.window_ticks
        if rule == "aidp":
            drive_max = max(drive_max, float(np.abs(L).max()))
            w = gaidp.window_step(w, L, p, bool(flags[q]))
            L = np.zeros((M, K))
        steps[q] = np.abs(w - w_before).mean()
        if snapshot_every and (q + 1) % snapshot_every == 0:
            snaps.append((q + 1, w.copy()))
    arr = (lambda xs: np.asarray(xs, dtype=np.int64))
    return LayerResult(w, counts, arr(sp_p), arr(sp_k), arr(sp_j), steps, snaps, drive_max)
