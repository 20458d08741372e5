"""The per-sweep check of the Izhikevich core's updates, shared by every scoreboard.

A scoreboard collects the updates of one whole sweep as the DUT reports them (``upd_v``,
``upd_u``, ``upd_current``, ``upd_spike``, ``upd_clamp``) and hands them to
:meth:`SweepChecker.check`, which verifies them vectorized:

* **twin, exact:** the bit-exact twin advanced from the DUT's own previous state with the current
  the DUT reports it used must give the same ``v``, ``u``, spike and clamp flags - zero
  mismatches allowed;
* **golden, bounded:** the float64 forward-Euler step from the same state must lie within the
  one-step bound derived from the formats, for every update that no clamp touched. A clamped
  update is an expected deviation (it is flagged, identically in twin and DUT, and counted); an
  unflagged one outside the bound is a failure. A spike decision may differ from golden only
  where golden's pre-reset ``v`` is within the bound of the threshold;
* **counters:** the per-sweep clamp counters and spike count the DUT reports must equal the sums
  of the flags of that sweep, and the sticky flags their running OR.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...hdl.izhikevich import CLAMP_KINDS, IzhikevichConfig, IzhikevichTwin
from ...hdl.lib.synapses import trace_golden_check

__all__ = ["SweepChecker", "SweepStats", "TargetChecker"]


@dataclass
class SweepStats:
    """Running totals of a scoreboard (JSON-friendly through :meth:`to_dict`)."""

    sweeps_checked: int = 0
    updates_checked: int = 0
    twin_mismatches: int = 0
    flag_mismatches: int = 0
    golden_v_max_err: float = 0.0
    golden_u_max_err: float = 0.0
    golden_v_max_ratio: float = 0.0
    golden_u_max_ratio: float = 0.0
    golden_bound_violations: int = 0
    spike_disagreements_near_threshold: int = 0
    spike_disagreements: int = 0
    flagged_updates: int = 0
    spikes: int = 0
    clamp_counts: dict = field(default_factory=lambda: {k: 0 for k in CLAMP_KINDS})
    clamp_sticky: int = 0
    first_mismatch: str | None = None

    def to_dict(self) -> dict:
        return dict(self.__dict__)


class SweepChecker:
    """Checks whole sweeps of reported updates against the twin and golden.

    Parameters
    ----------
    config
        The core configuration the DUT was generated from.
    """

    def __init__(self, config: IzhikevichConfig):
        self.cfg = config
        self.twin = IzhikevichTwin(config)
        self.sel = np.asarray(config.neuron_sets, dtype=np.int64)
        self.prev_v = np.asarray(config.v_init_raw, dtype=np.int64).copy()
        self.prev_u = np.asarray(config.u_init_raw, dtype=np.int64).copy()
        self.stats = SweepStats()

    def check(self, v, u, i, spike, clamp, sel=None) -> dict:
        """Check one sweep (arrays of raw values indexed by neuron); returns the twin's
        expected outputs. ``sel`` defaults to the configuration's neuron sets."""
        cfg, st = self.cfg, self.stats
        sel = self.sel if sel is None else np.asarray(sel, dtype=np.int64)
        v, u, i, clamp = (np.asarray(x, dtype=np.int64) for x in (v, u, i, clamp))
        spk = np.asarray(spike, dtype=bool)
        out = self.twin.update(self.prev_v, self.prev_u, i, sel)
        mism = (out["v"] != v) | (out["u"] != u) | (out["spike"] != spk)
        fmism = out["clamp"] != clamp
        st.twin_mismatches += int(mism.sum())
        st.flag_mismatches += int(fmism.sum())
        if (mism | fmism).any() and st.first_mismatch is None:
            k = int(np.flatnonzero(mism | fmism)[0])
            st.first_mismatch = (f"sweep {st.sweeps_checked} neuron {k}: DUT v={v[k]} u={u[k]} "
                                 f"spike={bool(spk[k])} clamp={clamp[k]:#x}, twin "
                                 f"v={out['v'][k]} u={out['u'][k]} spike={bool(out['spike'][k])} "
                                 f"clamp={int(out['clamp'][k]):#x}")
        # golden one step from the DUT's own previous state; clamped updates are expected
        # deviations
        vf, uf = cfg.V.to_float(self.prev_v), cfg.U.to_float(self.prev_u)
        If = cfg.I.to_float(i)
        gv, gu, gspk, gv_pre = cfg.golden_step(vf, uf, If, sel)
        bv, bu = cfg.one_step_bound(vf, uf, If, sel)
        fv, fu = cfg.V.to_float(v), cfg.U.to_float(u)
        clean = clamp == 0
        st.flagged_updates += int((~clean).sum())
        agree = (gspk == spk) & clean
        ev = np.abs(fv - gv)[agree]
        eu = np.abs(fu - gu)[agree]
        st.golden_v_max_err = max(st.golden_v_max_err, float(ev.max(initial=0)))
        st.golden_u_max_err = max(st.golden_u_max_err, float(eu.max(initial=0)))
        st.golden_v_max_ratio = max(st.golden_v_max_ratio,
                                    float((ev / bv[agree]).max(initial=0)))
        st.golden_u_max_ratio = max(st.golden_u_max_ratio,
                                    float((eu / bu[agree]).max(initial=0)))
        st.golden_bound_violations += int((ev > bv[agree]).sum() + (eu > bu[agree]).sum())
        differ = (gspk != spk) & clean
        near = np.abs(gv_pre - cfg.v_th) <= bv
        st.spike_disagreements_near_threshold += int((differ & near).sum())
        st.spike_disagreements += int((differ & ~near).sum())
        for b, k in enumerate(CLAMP_KINDS):
            n = int(((clamp >> b) & 1).sum())
            st.clamp_counts[k] += n
            if n:
                st.clamp_sticky |= 1 << b
        st.spikes += int(spk.sum())
        st.sweeps_checked += 1
        st.updates_checked += len(v)
        self.prev_v, self.prev_u = v.copy(), u.copy()
        return out

    @staticmethod
    def sweep_clamp_sums(clamp) -> dict:
        """Per-kind number of clamped updates in one sweep's flags."""
        clamp = np.asarray(clamp, dtype=np.int64)
        return {k: int(((clamp >> b) & 1).sum()) for b, k in enumerate(CLAMP_KINDS)}

    def failures(self) -> list[str]:
        """What failed, as readable lines (empty when the sweeps checked are all correct)."""
        st, out = self.stats, []
        if st.twin_mismatches:
            out.append(f"RTL differs from the twin in {st.twin_mismatches} updates "
                       f"({st.first_mismatch})")
        if st.flag_mismatches:
            out.append(f"clamp flags differ from the twin in {st.flag_mismatches} updates "
                       f"({st.first_mismatch})")
        if st.golden_bound_violations:
            out.append(f"{st.golden_bound_violations} unflagged updates left the golden bound")
        if st.spike_disagreements:
            out.append(f"{st.spike_disagreements} spike decisions differ from golden away "
                       f"from the threshold")
        return out


class TargetChecker:
    """What the checker of a block with Izhikevich target neurons shares (the coincidence
    detector's, the learning layer's): :attr:`iz`, a :class:`SweepChecker` of the first
    ``cfg.n_targets`` neurons of ``cfg.iz`` (the padding is never reported); :attr:`stats`,
    ``stats`` and ``first_mismatch``; the golden check of traces (:meth:`golden_traces`) and
    :meth:`failures`, each nonzero count of :attr:`FAILURES` a line."""

    #: the counts of :attr:`stats` that are failures (beside the targets' own)
    FAILURES: tuple = ()

    def __init__(self, cfg, stats: dict):
        self.cfg = cfg
        M = cfg.n_targets
        self.iz = SweepChecker(cfg.iz)
        self.iz.prev_v, self.iz.prev_u = self.iz.prev_v[:M], self.iz.prev_u[:M]
        self.iz.sel = self.iz.sel[:M]
        self.stats = stats | {"first_mismatch": None}

    def golden_traces(self, name: str, view, ys, traces) -> None:
        """Traces against golden's exact decay of the same ``ys``
        (:func:`~cuneate.hdl.lib.synapses.trace_golden_check`), counted as
        ``<name>_golden_violations`` and ``<name>_golden_max_ratio``."""
        st = self.stats
        errs, bounds = trace_golden_check(view, ys, traces)
        st[f"{name}_golden_violations"] += int((errs > bounds).sum())
        st[f"{name}_golden_max_ratio"] = max(st[f"{name}_golden_max_ratio"],
                                             float((errs / bounds).max()))

    def failures(self) -> list[str]:
        st, out = self.stats, list(self.iz.failures())
        for k in self.FAILURES:
            if st[k]:
                out.append(f"{st[k]} {k.replace('_', ' ')} ({st['first_mismatch']})")
        return out
