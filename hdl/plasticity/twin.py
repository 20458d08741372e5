"""The bit-exact integer twin of the learning layer: the stage functions of
:mod:`cuneate.hdl.plasticity.datapath` (the synapses' one-step specification
:func:`~cuneate.hdl.plasticity.datapath.synapse_step` vectorized over every synapse), the shared
traces and the Izhikevich twin's update, on NumPy int64 arrays; or the compiled restatement of
all of them (:mod:`cuneate.hdl.plasticity.kernel`) for whole protocols."""

from __future__ import annotations

import numpy as np

from ..izhikevich import IzhikevichTwin
from ..lib.events import SpikeEvents
from ..lib.fixed import tally_clamps
from ..lib.kernel import choose_kernel
from ..lib.synapses import trace_products, trace_update
from . import datapath as dp
from .config import CLAMP_KINDS, CN_CLAMP_KINDS, OPS, SYNAPSE_CLAMP_KINDS, PlasticityConfig

__all__ = ["PlasticityTwin"]


class PlasticityTwin(SpikeEvents):
    """Bit-exact NumPy model of :class:`~cuneate.hdl.plasticity.LearningLayer`.

    State: the synapses' ``w``, ``cd``, ``cr``, ``L`` (``(M, K)`` raw), the CNs' ``v``, ``u``,
    ``E``, the interneuron ``H``, the delayed spike words, the pending spikes. :meth:`tick` and
    :meth:`learn` run the stage functions (and record the last tick's updates in
    :attr:`last`); :meth:`run` runs presentations through the compiled kernel when
    ``kernel="numba"``.
    """

    KERNELS = ("stages", "numba")

    def __init__(self, config: PlasticityConfig | None = None, kernel: str | None = None,
                 **kwargs):
        from . import kernel as _k
        self.cfg = cfg = config or PlasticityConfig(**kwargs)
        self.kernel = choose_kernel(kernel, self.KERNELS)
        self._k = _k
        M, K, S = cfg.n_targets, cfg.n_synapses, cfg.n_sources
        self.iz = IzhikevichTwin(cfg.iz, kernel="stages")
        self.sel = np.asarray(cfg.target_sets_, dtype=np.int64)
        self.table = np.asarray(cfg.step_table, dtype=np.int64)
        self.src = cfg.src
        self.w = cfg.weights_raw.astype(np.int64).copy()
        self.cd = np.zeros((M, K), np.int64)
        self.cr = np.zeros((M, K), np.int64)
        self.L = np.zeros((M, K), np.int64)
        self.v = np.asarray(cfg.iz.v_init_raw, dtype=np.int64)[:M].copy()
        self.u = np.asarray(cfg.iz.u_init_raw, dtype=np.int64)[:M].copy()
        self.E = np.zeros(M, np.int64)
        self.H = 0
        self.delayed = np.zeros((cfg.latency_ticks, S), dtype=bool)
        self.pending = np.zeros(S, dtype=bool)
        self.ticks = 0
        self.learns = 0
        self.events = 0
        self.merged = 0
        self.clamp_sticky = 0
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}
        self.last: dict = {}

    # --------------------------------------------------------------------------- one step
    def lookup(self, index):
        return self.table[np.asarray(index)]

    def synapses(self, op, spike=False, late=False, z=0, total=0, apply=False, weight=0):
        """One operation on every synapse (broadcast operands); returns
        :func:`~cuneate.hdl.plasticity.datapath.synapse_step`'s dict (state unchanged)."""
        return dp.synapse_step(self.cfg, op, self.w, self.cd, self.cr, self.L,
                               np.asarray(spike, bool), np.asarray(late, bool),
                               np.asarray(z, np.int64), np.asarray(total, np.int64),
                               bool(apply), np.asarray(weight, np.int64), self.lookup)

    def _take(self, out) -> None:
        self.w, self.cd, self.cr, self.L = (np.asarray(out[k], dtype=np.int64)
                                            for k in ("w", "cd", "cr", "L"))
        counts = [np.count_nonzero(out[k]) for k in SYNAPSE_CLAMP_KINDS]
        tally_clamps(self, CLAMP_KINDS, [0] * len(CN_CLAMP_KINDS) + counts)

    # --------------------------------------------------------------------------- inputs
    def tick(self) -> np.ndarray:
        """Stamp the pending spikes and run one tick; returns the CNs' spike vector."""
        cfg = self.cfg
        s = self.pending
        self.pending = np.zeros(cfg.n_sources, dtype=bool)
        late = self.delayed[-1].copy() if cfg.latency_ticks else s
        if cfg.latency_ticks:
            self.delayed = np.roll(self.delayed, 1, axis=0)
            self.delayed[0] = s
        inh, y_h = dp.interneuron(cfg, np.int64(self.H), np.int64(s.sum()))
        (h_new,) = trace_update(cfg.hview, [y_h], trace_products(cfg.hview, [y_h]))
        i0, _ = dp.net_drive(cfg, self.E, inh, 0)
        z = dp.main_calcium(cfg, i0)
        syn = self.synapses(OPS["integrate"], s[self.src], late[self.src], z[:, None])
        a = np.asarray(syn["contrib"], dtype=np.int64).sum(axis=1)
        i, y_e = dp.net_drive(cfg, self.E, inh, a)
        (e_new,) = trace_update(cfg.eview, [y_e], trace_products(cfg.eview, [y_e]))
        out = self.iz.update(self.v, self.u, i, self.sel)
        self.last = {"syn": syn, "z": z, "a": a, "i": i, "inh": int(inh), "E": e_new,
                     "cn": out, "s": s, "late": late}
        self._take(syn)
        self.v, self.u = out["v"].astype(np.int64), out["u"].astype(np.int64)
        self.E = np.asarray(e_new, dtype=np.int64)
        self.H = int(h_new)
        tally_clamps(self, CLAMP_KINDS, [np.count_nonzero(out[k]) for k in CN_CLAMP_KINDS]
                     + [0] * len(SYNAPSE_CLAMP_KINDS))
        self.ticks += 1
        return np.asarray(out["spike"], dtype=bool)

    def learn(self, apply: bool = True) -> dict:
        """A window's end: each CN's drives summed, then every synapse's learn operation.
        Returns the step's outputs."""
        total = self.L.sum(axis=1, keepdims=True)
        out = self.synapses(OPS["learn"], total=total, apply=apply and self.cfg.plastic)
        self._take(out)
        self.learns += 1
        return out

    def write_weight(self, addr: int, raw: int) -> None:
        """The host's weight write of synapse ``addr`` (``j K + m``)."""
        j, m = divmod(int(addr), self.cfg.n_synapses)
        self.w[j, m], self.cd[j, m], self.cr[j, m], self.L[j, m] = int(raw), 0, 0, 0

    def read_weight(self, addr: int) -> int:
        j, m = divmod(int(addr), self.cfg.n_synapses)
        return int(self.w[j, m])

    @property
    def weights(self) -> np.ndarray:
        """The weights in mV/ms."""
        return self.w * self.cfg.W.lsb

    # --------------------------------------------------------------------------- runs
    def run(self, pres, learn=True) -> dict:
        """Run presentations (:class:`~cuneate.golden.cuneate_layer.Presentations`): each
        presentation's ticks (its spikes stamped with their ticks), then its window's end
        (with the step when ``learn`` says so: one flag per presentation, or one for all).
        Returns ``spike_pres``, ``spike_tick``, ``spike_cn`` (every CN spike) and ``counts``
        (``(n, M)``, within the window) and ``weights`` after each presentation's step when
        asked by ``snapshot_every``."""
        flags = np.broadcast_to(np.asarray(learn, dtype=bool), (pres.n,)).copy()
        flags &= bool(self.cfg.plastic)               # a frozen layer's windows change nothing
        if self.kernel == "numba":
            return self._k.run_presentations(self, pres, flags)
        M = self.cfg.n_targets
        counts = np.zeros((pres.n, M), np.int64)
        sp = ([], [], [])
        for q in range(pres.n):
            a, b = pres.offsets[q], pres.offsets[q + 1]
            ev_t, ev_s = pres.ticks[a:b], pres.sources[a:b]
            e = 0
            for k in range(pres.n_ticks):
                while e < len(ev_t) and ev_t[e] == k:
                    self.spike_in(ev_s[e])
                    e += 1
                for j in np.flatnonzero(self.tick()):
                    sp[0].append(q)
                    sp[1].append(k)
                    sp[2].append(j)
                    counts[q, j] += k < pres.window_ticks
            self.learn(bool(flags[q]))
        arr = (lambda x: np.asarray(x, dtype=np.int64))
        return {"spike_pres": arr(sp[0]), "spike_tick": arr(sp[1]), "spike_cn": arr(sp[2]),
                "counts": counts}
