"""The coincidence detector's generated Verilog on Icarus and Verilator: every update of every
target checked against the twin (exact) and golden (bounded), and the engine run equal to the
twin spike for spike."""

import json

import numpy as np
import pytest

from cuneate.hdl.coincidence import CoincidenceConfig, CoincidenceTwin, coincidence_verilog
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS

CASES = {
    # small history and mixed parameter sets: delays wrap around the ring many times
    "mixed": {"detector": dict(n_sources=4, n_targets=3,
                               delays_ticks=[[0, 3, 1, 0], [2, 0, 0, 5], [7, 7, 0, 0]],
                               max_delay_ticks=8, param_sets=("RS", "FS"),
                               target_sets=[0, 1, 0]),
              "ticks": 300, "event_p": 0.4},
    # the brief's detector: 32 ms history, J = 8, delays up to 20 ms, sparse inputs
    "brief": {"detector": dict(n_sources=4, n_targets=3,
                               delays_ticks=[[320, 320, 0, 0], [0, 0, 0, 0], [0, 0, 320, 320]]),
              "ticks": 1200, "event_p": 0.02},
}


def _src(cfg, simulator, build_dir):
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "coincidence_detector.v"
    # Icarus 11 simulates the yosys-lowered netlist of the same design (see lowered_verilog)
    src.write_text(coincidence_verilog(cfg, lowered=simulator == "icarus"))
    return src


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator,case", [
    # Verilator's mixed case runs in the long lane (Icarus runs it in the default lane)
    pytest.param(s, c, id=f"{s}-{c}",
                 marks=pytest.mark.long if (s, c) == ("verilator", "mixed") else ())
    for s in SIMULATORS for c in CASES])
def test_scoreboard(simulator, case, build_root):
    spec = dict(CASES[case], seed=3)
    cfg = CoincidenceConfig(**spec["detector"])
    bd = build_root / f"cuneate_{case}_{simulator}"
    run = run_cocotb(simulator, [_src(cfg, simulator, bd)], "coincidence_detector",
                     "cuneate.sim.coincidence.bench", bd,
                     config=spec | {"detector": cfg.to_kwargs()}, testcase="scoreboard")
    r = run.report
    iz = r.pop("izhikevich")
    print(f"\n{simulator} {case}: " + json.dumps(r))
    assert r["ticks_checked"] == spec["ticks"]
    assert r["updates_checked"] == spec["ticks"] * cfg.n_targets == iz["updates_checked"]
    assert r["input_mismatches"] == r["trace_mismatches"] == r["current_mismatches"] == 0
    assert iz["twin_mismatches"] == 0 and iz["flag_mismatches"] == 0
    assert r["trace_golden_violations"] == 0 and 0 < r["trace_golden_max_ratio"] <= 1
    assert iz["golden_bound_violations"] == 0 and iz["spike_disagreements"] == 0
    assert iz["flagged_updates"] == 0
    assert r["events"] > 0 and r["spikes"] > 0
    if case == "mixed":
        assert r["merged"] > 0


@pytest.mark.cocotb
# Icarus in the default lane, Verilator in the long lane (its scoreboard runs in the default)
@pytest.mark.parametrize("simulator", [pytest.param(s, marks=pytest.mark.long)
                                       if s == "verilator" else s for s in SIMULATORS])
def test_engine_equals_twin(simulator, build_root):
    cfg = CoincidenceConfig(n_sources=2, n_targets=2, delays_ticks=[[0, 16], [16, 0]],
                            max_delay_ticks=32)
    rng = np.random.default_rng(4)
    n = 400
    ins = [np.sort(rng.choice(n, 25, replace=False)) for _ in range(2)]
    ins[1] = np.unique(np.concatenate([ins[1], ins[0][:10] + 16]))   # some coincidences
    ins[1] = ins[1][ins[1] < n]
    events = {}
    for s, ts in enumerate(ins):
        for t in ts:
            events.setdefault(str(int(t)), []).append(s)
    bd = build_root / f"cuneate_engine_{simulator}"
    rep = run_cocotb(simulator, [_src(cfg, simulator, bd)], "coincidence_detector",
                     "cuneate.sim.coincidence.bench", bd,
                     config={"detector": cfg.to_kwargs(), "ticks": n, "events": events},
                     testcase="engine").report
    twin = CoincidenceTwin(cfg).run(ins, n)
    got = [[(k + 1) * cfg.dt_ms for k, t in sorted(rep["spikes"]) if t == tgt]
           for tgt in range(2)]
    assert sum(map(len, got)) > 0 and rep["ticks"] == n
    for a, b in zip(got, twin):
        assert np.allclose(a, b) and len(a) == len(b)
