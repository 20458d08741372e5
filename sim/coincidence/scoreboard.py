"""The per-tick check of the coincidence detector's target updates (its scoreboard, used by the
detector's bench and the network's): the input sums from the delayed history, the traces and
PSP current and the Izhikevich update against the bit-exact twin from the DUT's own previous
state (exact), and the float64 golden steps within their derived bounds."""

from __future__ import annotations

import numpy as np

from ...hdl.coincidence import CoincidenceConfig, CoincidenceTwin
from ..izhikevich.scoreboard import TargetChecker

__all__ = ["CoincidenceChecker"]


class CoincidenceChecker(TargetChecker):
    """Checks the updates of whole ticks against the twin (exact) and golden (bounded)."""

    FAILURES = ("input_mismatches", "trace_mismatches", "current_mismatches",
                "trace_golden_violations")

    def __init__(self, cfg: CoincidenceConfig):
        super().__init__(cfg, {"ticks_checked": 0, "updates_checked": 0, "input_mismatches": 0,
                               "trace_mismatches": 0, "current_mismatches": 0,
                               "trace_golden_violations": 0, "trace_golden_max_ratio": 0.0})
        M = cfg.n_targets
        self.ref = CoincidenceTwin(cfg)         # history and inputs; state from the DUT
        self.sel = np.asarray(cfg.target_sets_, dtype=np.int64)
        self.prev_xd = np.zeros(M, dtype=np.int64)
        self.prev_xr = np.zeros(M, dtype=np.int64)

    def check(self, events, rows) -> None:
        """``events``: sources driven before this tick; ``rows``: dict of arrays by target."""
        st = self.stats
        self.ref.spike_in(events)
        a = self.ref.stamp()
        out = self.ref.update(self.iz.prev_v, self.iz.prev_u, self.prev_xd, self.prev_xr, a,
                              self.sel)
        bad_a = rows["a"] != a
        bad_t = (rows["xd"] != out["xd"]) | (rows["xr"] != out["xr"])
        bad_i = rows["i"] != out["i"]
        st["input_mismatches"] += int(bad_a.sum())
        st["trace_mismatches"] += int(bad_t.sum())
        st["current_mismatches"] += int(bad_i.sum())
        if (bad_a | bad_t | bad_i).any() and st["first_mismatch"] is None:
            k = int(np.flatnonzero(bad_a | bad_t | bad_i)[0])
            st["first_mismatch"] = (f"tick {st['ticks_checked']} target {k}: DUT a={rows['a'][k]}"
                                    f" xd={rows['xd'][k]} xr={rows['xr'][k]} i={rows['i'][k]};"
                                    f" twin a={a[k]} xd={out['xd'][k]} xr={out['xr'][k]} "
                                    f"i={out['i'][k]}")
        self.golden_traces("trace", self.cfg.tview, out["ys"], [rows["xd"], rows["xr"]])
        self.iz.check(rows["v"], rows["u"], rows["i"], rows["spike"], rows["clamp"], self.sel)
        self.prev_xd, self.prev_xr = rows["xd"].copy(), rows["xr"].copy()
        self.ref.ticks += 1
        st["ticks_checked"] += 1
        st["updates_checked"] += self.cfg.n_targets
