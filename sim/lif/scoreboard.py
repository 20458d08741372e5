"""The per-sweep check of the LIF core's updates (the LIF scoreboard): every update against the
bit-exact twin from the DUT's own previous state (zero mismatches) and against the float64
golden step within the bound derived from the formats (a flagged clamp is an expected
deviation, counted), synaptic traces included."""

from __future__ import annotations

import numpy as np

from ...hdl.lib.synapses import trace_golden_check
from ...hdl.lif import CLAMP_KINDS, LifConfig, LifTwin

__all__ = ["LifSweepChecker"]


class LifSweepChecker:
    """Checks whole sweeps of reported LIF updates against the twin (exact) and golden
    (bounded)."""

    def __init__(self, cfg: LifConfig):
        self.cfg = cfg
        self.twin = LifTwin(cfg)
        self.sel = np.asarray(cfg.neuron_sets, dtype=np.int64)
        self.prev_v = cfg.v_init_raw.copy()
        self.prev_ref = np.zeros(cfg.n_neurons, dtype=np.int64)
        self.prev_tr = np.zeros((len(cfg.traces), cfg.n_neurons), dtype=np.int64)
        self.stats = {"trace_golden_max_ratio": 0.0, "trace_bound_violations": 0,
                      "sweeps_checked": 0, "updates_checked": 0, "twin_mismatches": 0,
                      "golden_bound_violations": 0, "golden_max_ratio": 0.0,
                      "golden_max_err": 0.0, "spike_disagreements": 0,
                      "spike_disagreements_near_threshold": 0, "flagged_updates": 0,
                      "spikes": 0, "clamp_counts": {k: 0 for k in CLAMP_KINDS},
                      "clamp_sticky": 0, "first_mismatch": None}

    def check(self, v, ref, i, acc, spike, clamp, x, traces=None):
        cfg, st = self.cfg, self.stats
        v, ref, i, acc, clamp = (np.asarray(a, dtype=np.int64) for a in (v, ref, i, acc, clamp))
        spk = np.asarray(spike, dtype=bool)
        x = self.twin.delay_inputs(x)       # the input history (input_delays), if any
        out = self.twin.update(self.prev_v, self.prev_ref, i, x, self.sel, self.prev_tr)
        mism = ((out["v"] != v) | (out["ref"] != ref) | (out["spike"] != spk)
                | (out["clamp"] != clamp) | (out["acc"] != acc))
        if cfg.traces:
            traces = np.asarray(traces, dtype=np.int64)
            mism |= (out["traces"] != traces).any(axis=0)
            err, bnd = trace_golden_check(cfg, out["ys"], traces)
            st["trace_bound_violations"] += int((err > bnd).sum())
            st["trace_golden_max_ratio"] = max(st["trace_golden_max_ratio"],
                                               float((err / bnd).max()))
            self.prev_tr = traces.copy()
        st["twin_mismatches"] += int(mism.sum())
        if mism.any() and st["first_mismatch"] is None:
            k = int(np.flatnonzero(mism)[0])
            st["first_mismatch"] = (f"sweep {st['sweeps_checked']} neuron {k}: DUT v={v[k]} "
                                    f"ref={ref[k]} spike={spk[k]} acc={acc[k]} "
                                    f"clamp={clamp[k]}; twin v={out['v'][k]} "
                                    f"ref={out['ref'][k]} spike={out['spike'][k]} "
                                    f"acc={out['acc'][k]} clamp={out['clamp'][k]}")
        vf = cfg.V.to_float(self.prev_v)
        D = cfg.V.to_float(out["d"])
        gv, gspk, gpre = cfg.golden_step(vf, D, self.prev_ref, self.sel)
        bound = cfg.one_step_bound(vf, D, self.sel)
        clean = clamp == 0
        st["flagged_updates"] += int((~clean).sum())
        agree = (gspk == spk) & clean
        err = np.abs(cfg.V.to_float(v) - gv)[agree]
        st["golden_max_err"] = max(st["golden_max_err"], float(err.max(initial=0)))
        st["golden_max_ratio"] = max(st["golden_max_ratio"],
                                     float((err / bound[agree]).max(initial=0)))
        st["golden_bound_violations"] += int((err > bound[agree]).sum())
        th = np.array([s.v_th for s in cfg.sets])[self.sel]
        near = np.abs(gpre - th) <= bound + cfg.V.lsb
        differ = (gspk != spk) & clean
        st["spike_disagreements_near_threshold"] += int((differ & near).sum())
        st["spike_disagreements"] += int((differ & ~near).sum())
        for b, k in enumerate(CLAMP_KINDS):
            n = int(((clamp >> b) & 1).sum())
            st["clamp_counts"][k] += n
            if n:
                st["clamp_sticky"] |= 1 << b
        st["spikes"] += int(spk.sum())
        st["sweeps_checked"] += 1
        st["updates_checked"] += len(v)
        self.prev_v, self.prev_ref = v.copy(), ref.copy()

    def failures(self) -> list[str]:
        st, out = self.stats, []
        if st["twin_mismatches"]:
            out.append(f"RTL differs from the twin in {st['twin_mismatches']} updates "
                       f"({st['first_mismatch']})")
        if st["trace_bound_violations"]:
            out.append(f"{st['trace_bound_violations']} synaptic trace updates left the "
                       f"golden bound")
        if st["golden_bound_violations"]:
            out.append(f"{st['golden_bound_violations']} unflagged updates left the golden bound")
        if st["spike_disagreements"]:
            out.append(f"{st['spike_disagreements']} spike decisions differ from golden away "
                       f"from the threshold")
        return out
