"""The per-tick check of the learning layer (its scoreboard, used by its cocotb bench): every
synapse's integrate operation, every CN's update and every window's steps against the bit-exact
twin (exact, in lockstep), the CNs' updates against golden from the DUT's own previous state
(bounded, :class:`~cuneate.sim.izhikevich.scoreboard.SweepChecker`) and the calcium traces
against golden's exact decay from the same ``y`` (bounded,
:func:`~cuneate.hdl.lib.synapses.trace_golden_check`)."""

from __future__ import annotations

import numpy as np

from ...hdl.plasticity import PlasticityConfig
from ...hdl.plasticity.datapath import calcium_input
from ...hdl.plasticity.twin import PlasticityTwin
from ..izhikevich.scoreboard import TargetChecker

__all__ = ["LearningChecker", "SYN_FIELDS", "CN_FIELDS"]

#: what the bench reads of each synapse update and each CN update
SYN_FIELDS = ("w", "cd", "cr", "l", "clamp")
CN_FIELDS = ("v", "u", "e", "i", "inh", "a", "spike", "clamp")


class LearningChecker(TargetChecker):
    """Checks whole ticks and windows against the twin (exact) and golden (bounded)."""

    FAILURES = ("synapse_mismatches", "cn_mismatches", "window_mismatches",
                "calcium_golden_violations")

    def __init__(self, cfg: PlasticityConfig):
        super().__init__(cfg, {"ticks_checked": 0, "synapse_updates_checked": 0,
                               "cn_updates_checked": 0, "windows_checked": 0,
                               "synapse_mismatches": 0, "cn_mismatches": 0,
                               "window_mismatches": 0, "calcium_golden_violations": 0,
                               "calcium_golden_max_ratio": 0.0, "spikes": 0})
        self.twin = PlasticityTwin(cfg, kernel="stages")

    def _note(self, what: str) -> None:
        if self.stats["first_mismatch"] is None:
            self.stats["first_mismatch"] = what

    def _synapses(self, rows: dict, exp: dict, what: str, keys) -> int:
        bad = np.zeros(rows["w"].shape, dtype=bool)
        for k in keys:
            bad |= np.asarray(rows[k]) != np.asarray(exp[k])
        if bad.any():
            j, m = np.argwhere(bad)[0]
            self._note(f"{what}: synapse ({j}, {m}) DUT " + ", ".join(
                f"{k}={int(rows[k][j, m])}" for k in keys) + " twin " + ", ".join(
                f"{k}={int(exp[k][j, m])}" for k in keys))
        return int(bad.sum())

    def tick(self, events, syn: dict, cn: dict) -> None:
        """One tick: ``events`` the sources driven before it; ``syn`` ``{field: (M, K)}`` and
        ``cn`` ``{field: (M,)}`` the DUT's reported updates."""
        tw, st, cfg = self.twin, self.stats, self.cfg
        w0, cd0, cr0 = tw.w.copy(), tw.cd.copy(), tw.cr.copy()
        tw.spike_in(events)
        tw.tick()
        last = tw.last
        late = last["late"]
        exp = {"w": tw.w, "cd": tw.cd, "cr": tw.cr, "l": tw.L,
               "clamp": sum(np.asarray(last["syn"][k], dtype=np.int64) << b for b, k in
                            enumerate(("drive_low", "drive_high", "weight_low",
                                       "weight_high")))}
        st["synapse_mismatches"] += self._synapses(syn, exp, f"tick {st['ticks_checked']}",
                                                   SYN_FIELDS)
        want = {"e": last["E"], "i": last["i"], "inh": np.full(cfg.n_targets, last["inh"]),
                "a": last["a"]}
        bad = np.zeros(cfg.n_targets, dtype=bool)
        for k, x in want.items():
            bad |= np.asarray(cn[k]) != np.asarray(x)
        if bad.any():
            j = int(np.flatnonzero(bad)[0])
            self._note(f"tick {st['ticks_checked']} CN {j}: DUT " + ", ".join(
                f"{k}={int(cn[k][j])}" for k in want) + " twin " + ", ".join(
                f"{k}={int(np.asarray(x)[j])}" for k, x in want.items()))
        st["cn_mismatches"] += int(bad.sum())
        # the CNs against the twin and golden from the DUT's previous state
        self.iz.check(cn["v"], cn["u"], cn["i"], cn["spike"], cn["clamp"])
        # the calcium traces against golden's decay of the same y
        _, ys = calcium_input(cfg, cd0, cr0, w0, late[cfg.src])
        self.golden_traces("calcium", cfg.cview, [y.ravel() for y in ys],
                           [syn["cd"].ravel(), syn["cr"].ravel()])
        st["spikes"] += int(np.count_nonzero(cn["spike"]))
        st["ticks_checked"] += 1
        st["synapse_updates_checked"] += syn["w"].size
        st["cn_updates_checked"] += cfg.n_targets

    def window(self, apply: bool, syn: dict) -> None:
        """A window's end: ``syn`` the DUT's learn updates ``{field: (M, K)}``."""
        tw, st = self.twin, self.stats
        out = tw.learn(apply)
        exp = {"w": tw.w, "l": tw.L, "clamp": sum(np.asarray(out[k], dtype=np.int64) << b
                                                  for b, k in enumerate(
            ("drive_low", "drive_high", "weight_low", "weight_high")))}
        st["window_mismatches"] += self._synapses(syn, exp, f"window {st['windows_checked']}",
                                                  ("w", "l", "clamp"))
        st["windows_checked"] += 1
