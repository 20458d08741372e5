"""`cuneate simulate coincidence`, `cuneate generate coincidence`: the JSON contract, engines
that agree, the generated files, and one-line refusals."""

import json

import numpy as np
import pytest
from cli_run import assert_refused, python_engine_runs, run_cli, simulate_json

from cuneate.sim.engines.toolchain import SIMULATORS

# two afferents, two cuneate neurons tuned to opposite 2 ms lags; J w = 10 mV/ms: one PSP peaks
# at 4.7 mV/ms (below the ~7.7 an RS neuron needs from rest), two coincident ones at 9.45
BASE = ["--delays-ms", "0,2;2,0", "--weights", "10", "--duration-ms", "100",
        "--input", "10,40,70", "--input", "8,42,90"]


def test_simulate_json_contract_and_coincidence_selectivity(capsys):
    runs = python_engine_runs(capsys, "coincidence", *BASE)
    for e, r in runs.items():
        assert r["model"] == "coincidence" and r["engine"] == e and r["dt_ms"] == 0.0625
        assert r["neurons"] == 2 and len(r["spikes_ms"]) == 2 and r["sources"] == 2
        assert r["input_ms"] == [[10.0, 40.0, 70.0], [8.0, 42.0, 90.0]]
        # target 0 delays source 1 by 2 ms: the pair at 10/8 ms coincides, fires once after
        # 10 ms; target 1 delays source 0: the pair at 40/42 ms; lone spikes never fire
        s0, s1 = (np.asarray(s) for s in r["spikes_ms"])
        assert len(s0) == 1 and 10 < s0[0] < 30, (e, s0)
        assert len(s1) == 1 and 42 < s1[0] < 62, (e, s1)
    assert runs["fixed"]["spikes_ms"] == runs["amaranth"]["spikes_ms"]
    assert abs(runs["golden"]["spikes_ms"][0][0] - runs["fixed"]["spikes_ms"][0][0]) <= 0.0625
    assert runs["fixed"]["saturation"]["sticky"] == 0
    assert runs["amaranth"]["saturation"]["counts"] == runs["fixed"]["saturation"]["counts"]


def test_poisson_inputs_golden_and_fixed_agree(capsys):
    args = ["--delays-ms", "0,0,1,1;0,0,0,0;1,1,0,0", "--input-rate-hz", "150",
            "--duration-ms", "400", "--seed", "2"]
    g, f = (simulate_json(capsys, "coincidence", "--engine", e, *args)
            for e in ("golden", "fixed"))
    assert g["input_ms"] == f["input_ms"] and sum(map(len, g["input_ms"])) > 100
    assert sum(map(len, f["spikes_ms"])) > 3
    for a, b in zip(g["spikes_ms"], f["spikes_ms"]):
        assert len(a) == len(b)
        assert np.max(np.abs(np.asarray(a) - np.asarray(b)), initial=0) <= 0.0625 + 1e-9


@pytest.mark.cocotb
# Icarus in the default lane, Verilator in the long lane (its scoreboard runs in the default)
@pytest.mark.parametrize("simulator", [pytest.param(s, marks=pytest.mark.long)
                                       if s == "verilator" else s for s in SIMULATORS])
def test_simulate_on_hdl_simulators_matches_twin(simulator, capsys, tmp_path):
    hw = simulate_json(capsys, "coincidence", "--engine", simulator, "--build-dir",
                       str(tmp_path), *BASE)
    tw = simulate_json(capsys, "coincidence", "--engine", "fixed", *BASE)
    assert hw["spikes_ms"] == tw["spikes_ms"] and sum(map(len, hw["spikes_ms"])) == 2


def test_generate_writes_verilog_and_description(capsys, tmp_path):
    rc, out, err = run_cli(capsys, ["generate", "coincidence", "--out", str(tmp_path),
                                    "--delays-ms", "0,0,20,20;0,0,0,0;20,20,0,0",
                                    "--name", "cn3"])
    assert rc == 0, err
    v = (tmp_path / "cn3.v").read_text()
    assert "module cn3" in v and "in_source" in v and "spike_target" in v
    d = json.loads((tmp_path / "cn3.json").read_text())
    assert d["block"] == "CoincidenceDetector" and d["module"] == "cn3"
    assert d["delays_ticks"][0] == [0, 0, 320, 320] and d["max_delay_ticks"] == 512
    assert d["max_delay_ms"] >= 31.9 and d["tick_source"] == "internal"
    kd = d["formats"]["traces"]["xd"]
    assert kd["k_exact"] == pytest.approx(1 - np.exp(-0.0625 / 2.0))
    assert abs(kd["k"]["rel_error"]) < 1e-3
    assert "T + delay" in d["latency"] and d["multipliers"] == 6
    assert d["memories"]["history"] == "512 x 4 bits"
    assert d["ports"]["in_source"]["direction"] == "in"
    assert d["ports"]["spike_target"]["direction"] == "out"
    assert "cycles per tick" in out


@pytest.mark.parametrize("argv,match", [
    (["simulate", "coincidence", "--delays-ms", "0,0.1;2,0"],
     "0.1 ms is not a whole number of ticks"),
    (["simulate", "coincidence", "--delays-ms", "0,40;2,0"],
     "delay of target 0 from source 1 is 640 ticks: outside 0 .. 511"),
    (["simulate", "coincidence", "--weights", "1,-1"], "weights must be finite and >= 0"),
    (["simulate", "coincidence", "--weight-bits", "3", "--delays-ms",
      "0,0", "--weights", "8,0.01"], "rounds to 0"),
    (["simulate", "coincidence", "--delays-ms", "0,1;1"], "same number of values"),
    (["simulate", "coincidence", "--delays-ms", "0,1", "--input", "1,2"],
     "--input is given 1 times; the detector has 2 sources"),
    (["simulate", "coincidence", "--delays-ms", "0,1", "--input", "1", "--input", "x"],
     "a comma list of times in ms"),
    (["simulate", "coincidence", "--tau-rise-ms", "0.0001"],
     "PSP trace xr: decay k = 1 - exp(-dt/tau)"),
    (["simulate", "coincidence", "--engine", "amaranth", "--duration-ms", "1e6"],
     "on the amaranth engine (about 6.08e+08 updates) would take about"),
    (["generate", "coincidence", "--out", "/tmp/x", "--clock-hz", "320000"],
     "need 38 cycles per tick"),
    (["generate", "coincidence", "--out", "/tmp/x", "--target-sets", "0,1,0"],
     "target_sets needs 3 indices"),
])
def test_bad_arguments_exit_2_with_one_line(capsys, argv, match):
    assert_refused(capsys, argv, match)
