"""The bit-exact integer twin of the coincidence detector: its stage functions, the synaptic
trace stages and the Izhikevich twin's update over NumPy int64 arrays (one element per target),
or the compiled restatement of all three (:mod:`cuneate.hdl.coincidence.kernel`)."""

from __future__ import annotations

import numpy as np

from ...golden.izhikevich import group_spikes, spike_times
from ..izhikevich import IzhikevichTwin
from ..lib.events import SpikeEvents
from ..lib.fixed import tally_clamps
from ..lib.kernel import choose_kernel
from ..lib.synapses import trace_products, trace_update
from .config import CLAMP_KINDS, CoincidenceConfig
from .datapath import accumulate, history_slot, psp_current

__all__ = ["CoincidenceTwin"]


class CoincidenceTwin(SpikeEvents):
    """Bit-exact NumPy model of :class:`CoincidenceDetector` (int64, vectorized over targets).

    Two implementations of :meth:`tick` and :meth:`run` compute the same bits: ``kernel=
    "stages"`` (the stage functions over NumPy arrays, the Izhikevich step included) and
    ``kernel="numba"`` (the compiled loop of :mod:`cuneate.hdl.coincidence.kernel`, proven
    bit-exact against the stages by property tests and long runs; the default whenever numba
    is available). :meth:`update` always runs the stage functions.
    """

    KERNELS = ("stages", "numba")

    def __init__(self, config: CoincidenceConfig | None = None, kernel: str | None = None,
                 **kwargs):
        from . import kernel as _k
        self.cfg = cfg = config or CoincidenceConfig(**kwargs)
        M, S, D = cfg.n_targets, cfg.n_sources, cfg.max_delay_ticks
        self.kernel = choose_kernel(kernel, self.KERNELS)
        self._k = _k
        self._consts = _k.gather_constants(cfg) if self.kernel == "numba" else None
        self.iz = IzhikevichTwin(cfg.iz, kernel="stages" if self.kernel == "stages" else None)
        self.sel = np.asarray(cfg.target_sets_, dtype=np.int64)
        self.v = np.asarray(cfg.iz.v_init_raw, dtype=np.int64)[:M].copy()
        self.u = np.asarray(cfg.iz.u_init_raw, dtype=np.int64)[:M].copy()
        self.xd = np.zeros(M, dtype=np.int64)
        self.xr = np.zeros(M, dtype=np.int64)
        self.history = np.zeros((D, S), dtype=bool)
        self.pending = np.zeros(S, dtype=bool)
        self.ticks = 0
        self.events = 0
        self.merged = 0
        self.clamp_sticky = 0
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}

    def inputs(self) -> np.ndarray:
        """``a`` (raw weight LSBs) of every target at the current tick (history stamped)."""
        cfg = self.cfg
        D = cfg.max_delay_ticks
        idx = history_slot(self.ticks % D, cfg.delays, D)
        bits = self.history[idx, np.arange(cfg.n_sources)[None, :]]
        a = np.zeros(cfg.n_targets, dtype=np.int64)
        for s in range(cfg.n_sources):
            a = accumulate(a, bits[:, s], cfg.weights_raw[:, s])
        return a

    def update(self, v, u, xd, xr, a, sel=None) -> dict:
        """One update of the given targets from any state (raw arrays)."""
        cfg = self.cfg
        sel = self.sel if sel is None else np.asarray(sel, dtype=np.int64)
        v, u, xd, xr, a = (np.asarray(x, dtype=np.int64) for x in (v, u, xd, xr, a))
        i, ys = psp_current(cfg, xd, xr, a)
        ps = trace_products(cfg.tview, ys)
        xs = trace_update(cfg.tview, ys, ps)
        out = self.iz.update(v, u, i, sel)
        out.update(xd=np.asarray(xs[0], dtype=np.int64), xr=np.asarray(xs[1], dtype=np.int64),
                   i=i, a=a, ys=ys)
        return out

    def stamp(self) -> np.ndarray:
        """Write the pending spikes into this tick's history slot; returns ``a`` (raw weight
        LSBs) of every target for this tick."""
        self.history[self.ticks % self.cfg.max_delay_ticks] = self.pending
        self.pending = np.zeros(self.cfg.n_sources, dtype=bool)
        return self.inputs()

    def run_pending(self, pending) -> tuple[np.ndarray, np.ndarray]:
        """Run ``len(pending)`` ticks, tick ``k`` stamping the sources set in ``pending[k]``
        (``(n_ticks, n_sources)`` bool; spikes already pending join the first tick). Returns
        every output spike as ``(ticks, targets)``, ticks counted from 0 at this call."""
        cfg = self.cfg
        pend = np.array(pending, dtype=bool, order="C")
        if pend.ndim != 2 or pend.shape[1] != cfg.n_sources:
            raise ValueError(f"pending spikes must have shape (n_ticks, {cfg.n_sources})")
        if len(pend):
            pend[0] |= self.pending
            self.pending = np.zeros(cfg.n_sources, dtype=bool)
        if self.kernel == "numba":
            ks, ns, totals = self._k.run_ticks(self._consts, self.v, self.u, self.xd, self.xr,
                                               self.sel, self.history, pend, self.ticks)
            self.ticks += len(pend)
            tally_clamps(self, CLAMP_KINDS, totals)
            return ks, ns
        hits_k, hits_n = [], []
        for k, row in enumerate(pend):
            self.pending = row.copy()
            idx = np.flatnonzero(self.tick())
            hits_k.append(np.full(idx.size, k, dtype=np.int64))
            hits_n.append(idx)
        if not hits_k:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return np.concatenate(hits_k), np.concatenate(hits_n)

    def tick(self) -> np.ndarray:
        """Stamp the pending spikes, update every target once; returns the spike vector."""
        if self.kernel == "numba":
            pend = self.pending.reshape(1, -1).copy()
            self.pending = np.zeros(self.cfg.n_sources, dtype=bool)
            _, ns = self.run_pending(pend)
            spk = np.zeros(self.cfg.n_targets, dtype=bool)
            spk[ns] = True
            return spk
        out = self.update(self.v, self.u, self.xd, self.xr, self.stamp())
        self.v, self.u = out["v"].astype(np.int64), out["u"].astype(np.int64)
        self.xd, self.xr = out["xd"], out["xr"]
        tally_clamps(self, CLAMP_KINDS, [np.count_nonzero(out[k]) for k in CLAMP_KINDS])
        self.ticks += 1
        return np.asarray(out["spike"], dtype=bool)

    def run(self, input_ticks, n_ticks: int) -> list[np.ndarray]:
        """Run ``n_ticks`` with input spikes given per source as arrays of the tick each is
        stamped with; returns spike times (ms) per target ((T + 1) dt for tick T)."""
        S = self.cfg.n_sources
        if len(input_ticks) > S:
            raise ValueError(f"spike source {len(input_ticks) - 1} is outside 0 .. {S - 1}")
        counts = np.zeros((n_ticks, S), dtype=np.int64)
        for s, ts in enumerate(input_ticks):
            ts = np.asarray(ts, dtype=np.int64)
            ts = ts[(ts >= 0) & (ts < n_ticks)]          # events of later ticks are not sent
            np.add.at(counts[:, s], ts, 1)
        self.events += int(counts.sum())
        self.merged += int(np.maximum(counts - 1, 0).sum())
        if n_ticks:
            self.merged += int(np.count_nonzero(self.pending & (counts[0] > 0)))
        ks, ns = self.run_pending(counts > 0)
        steps = group_spikes([ks], [ns], self.cfg.n_targets)
        return [spike_times(h, self.cfg.dt_ms) for h in steps]
