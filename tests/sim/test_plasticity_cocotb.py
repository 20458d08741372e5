"""The learning layer's generated Verilog on Icarus and Verilator: the per-cycle scoreboard
(every synapse update, every CN update and every window's steps against the twin, golden
bounded, the counters and each clamp kind's counter), with a host write read back."""

import json

import pytest

from cuneate.golden.aidp import AidpParams
from cuneate.hdl.plasticity import PlasticityConfig
from cuneate.hdl.plasticity.core import learning_verilog
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS

#: 2 CNs of 3 synapses over 6 afferents, a strong step (both weight clamps act), a calcium
#: latency of 2 ticks; 24 ticks, a window's end every 8 (with the step every other time)
LAYER = dict(n_sources=6, sources=[[0, 2, 5], [1, 2, 4]],
             weights=[[5.5, 0.2, 3.0], [1.0, 4.0, 0.0]],
             rule=AidpParams(eta=5e-3, latency_ms=1.0), g_inh=0.2, clock_hz=2000.0 * 60)


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", [
    pytest.param(s, marks=pytest.mark.long if s == "verilator" else ()) for s in SIMULATORS])
def test_scoreboard(simulator, build_root):
    cfg = PlasticityConfig(**LAYER)
    bd = build_root / f"learning_{simulator}"
    bd.mkdir(parents=True, exist_ok=True)
    src = bd / "learning_layer.v"
    src.write_text(learning_verilog(cfg, lowered=simulator == "icarus"))
    spec = {"layer": cfg.to_kwargs(), "ticks": 24, "window": 8, "event_p": 0.6, "seed": 2}
    r = run_cocotb(simulator, [src], "learning_layer", "cuneate.sim.plasticity.bench", bd,
                   config=spec, testcase="scoreboard").report
    iz = r.pop("izhikevich")
    print(f"\n{simulator}: " + json.dumps(r))
    assert r["ticks_checked"] == 24 and r["windows_checked"] == 3
    assert r["synapse_updates_checked"] == 24 * 6 and r["cn_updates_checked"] == 48
    assert r["synapse_mismatches"] == r["cn_mismatches"] == r["window_mismatches"] == 0
    assert iz["twin_mismatches"] == iz["flag_mismatches"] == 0
    assert iz["golden_bound_violations"] == 0 and iz["spike_disagreements"] == 0
    assert r["calcium_golden_violations"] == 0 and 0 < r["calcium_golden_max_ratio"] <= 1
    assert r["spikes"] > 0 and r["weights_changed"] > 0
    assert r["clamp_counts"]["weight_high"] > 0 and r["clamp_counts"]["weight_low"] > 0
