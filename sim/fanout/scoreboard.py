"""The per-run check of the channel fan-out (its scoreboard): every afferent's current against
the bit-exact twin on the same channel samples (exact, clamp flags included), and against the
float64 golden model on the same quantized samples within the derived one-sample bound
(:meth:`~cuneate.hdl.fanout.FanoutConfig.golden_bound`); a clamp that acted must be one the
golden current needs (it lies outside the current format)."""

from __future__ import annotations

import numpy as np

from ...golden.fanout import RECTIFY, fanout_currents
from ...hdl.fanout import FanoutConfig, FanoutTwin

__all__ = ["FanoutChecker"]


class FanoutChecker:
    """Checks whole runs: :meth:`check` takes the raw channel samples the run read and the
    currents the DUT wrote (raw, per afferent)."""

    def __init__(self, cfg: FanoutConfig):
        self.cfg = cfg
        self.twin = FanoutTwin(cfg)
        self.gain = np.array([c.value for c in cfg.gains_])
        self.modes = [RECTIFY[m] for m in cfg.modes_]
        self.theta = np.array([np.nan if t is None else t for t in cfg.thresholds_])
        self.stats = {"runs_checked": 0, "currents_checked": 0, "twin_mismatches": 0,
                      "golden_violations": 0, "golden_max_ratio": 0.0,
                      "unneeded_clamps": 0, "clamps_low": 0, "clamps_high": 0,
                      "first_mismatch": None}

    def check(self, samples_raw, currents_raw) -> None:
        cfg, st = self.cfg, self.stats
        self.twin.samples[:] = np.asarray(samples_raw, dtype=np.int64)
        ref, below, above = self.twin.run()
        got = np.asarray(currents_raw, dtype=np.int64)
        bad = got != ref
        st["twin_mismatches"] += int(bad.sum())
        if bad.any() and st["first_mismatch"] is None:
            k = int(np.flatnonzero(bad)[0])
            st["first_mismatch"] = (f"run {st['runs_checked']} afferent {k}: DUT {got[k]}, twin "
                                    f"{ref[k]} (channel {cfg.channels_[k]}, sample "
                                    f"{samples_raw[cfg.channels_[k]]})")
        s = cfg.S.to_float(samples_raw)
        gold = fanout_currents(s, cfg.channels_, self.gain, self.modes, self.theta)
        clamped = below | above
        err = np.abs(cfg.I.to_float(got) - gold)
        bound = cfg.golden_bound(s)
        free = ~clamped
        st["golden_violations"] += int((err[free] > bound[free]).sum())
        if free.any():
            # an exact current (err 0) uses none of its bound, which may be 0 (no bit dropped)
            ratio = np.divide(err[free], bound[free], out=np.zeros(int(free.sum())),
                              where=err[free] > 0)
            st["golden_max_ratio"] = max(st["golden_max_ratio"], float(np.max(ratio)))
        need = (gold - bound < cfg.I.min_value) | (gold + bound > cfg.I.max_value)
        st["unneeded_clamps"] += int((clamped & ~need).sum())
        st["clamps_low"] += int(below.sum())
        st["clamps_high"] += int(above.sum())
        st["runs_checked"] += 1
        st["currents_checked"] += cfg.n_neurons

    def failures(self) -> list[str]:
        st = self.stats
        out = []
        for k in ("twin_mismatches", "golden_violations", "unneeded_clamps"):
            if st[k]:
                out.append(f"{st[k]} {k.replace('_', ' ')} ({st['first_mismatch']})")
        return out
