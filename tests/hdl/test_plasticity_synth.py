"""The learning layer on the ULX3S's FPGA (LFE5U-85F, CABGA381, speed 6; release lane: yosys
synth_ecp5 and nextpnr-ecp5 out of context): the example's layer (80 afferents, 16 CNs of 20
synapses) learning and frozen (``plastic=False``: the cost of learning in logic, block RAM,
multipliers and fmax), recorded in benchmarks/results/learning_synth.json
(benchmarks/learning.md)."""

import json
from pathlib import Path

import numpy as np
import pytest

from cuneate.hdl.flow.synth import available, nextpnr_ecp5, synthesize
from cuneate.hdl.plasticity import PlasticityConfig
from cuneate.hdl.plasticity.core import learning_verilog
from cuneate.golden.aidp import AidpParams


def example_layer(plastic: bool = True) -> PlasticityConfig:
    rng = np.random.default_rng(3)
    src = np.array([np.sort(rng.choice(80, 20, replace=False)) for _ in range(16)])
    return PlasticityConfig(n_sources=80, sources=src, weights=rng.uniform(0, 3.6, (16, 20)),
                            rule=AidpParams(eta=2e-6), plastic=plastic)


@pytest.mark.release
def test_the_cost_of_learning_on_the_ulx3s(tmp_path):
    if not available():
        pytest.skip("yowasp yosys / nextpnr-ecp5 not installed (synth extra)")
    out = {}
    for plastic in (True, False):
        cfg = example_layer(plastic)
        d = tmp_path / ("learning" if plastic else "frozen")
        d.mkdir()
        r = synthesize(learning_verilog(cfg, "learning_layer"), "learning_layer", "ecp5", d,
                       netlist=True, pack_registers=True)
        pnr = nextpnr_ecp5(d, r["netlist"], device="85k", package="CABGA381", speed=6,
                           seed=1, freq_mhz=100, out_of_context=True, timeout=3600)
        out["learning" if plastic else "frozen"] = {
            "cells": {k: r["cells"].get(k, 0) for k in ("LUT4", "TRELLIS_FF", "DP16KD",
                                                          "MULT18X18D", "CCU2C")},
            "summary": r["summary"], "fmax_mhz": pnr["min_fmax_mhz"],
            "critical_path": pnr["critical_path"], "utilization": pnr["utilization"],
            "synapse_word_bits": sum(f.width for _, f in cfg.synapse_fields),
            "cycles_per_tick": cfg.cycles_needed, "seconds": r["seconds"] + pnr["seconds"]}
        print(f"\n{'learning' if plastic else 'frozen'}: {out}")
    learn, frozen = out["learning"], out["frozen"]
    assert learn["cells"]["MULT18X18D"] > frozen["cells"]["MULT18X18D"]
    assert learn["fmax_mhz"] and learn["fmax_mhz"] >= 40.0
    res = Path(__file__).resolve().parents[2] / "benchmarks" / "results"
    res.mkdir(parents=True, exist_ok=True)
    (res / "learning_synth.json").write_text(json.dumps(out, indent=1, default=float) + "\n")
