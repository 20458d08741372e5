"""`cuneate simulate izhikevich` engines print identical spike trains for the same inputs."""

import json

import pytest
from cli_run import run_cli

from cuneate.golden import izhikevich as golden
from cuneate.golden.metrics import compare_trains
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.izhikevich.engines import run_engine

ARGS = ["simulate", "izhikevich", "--preset", "RS", "--neurons", "3", "--current", "4", "10",
        "30", "--duration-ms", "150", "--json"]


@pytest.fixture(scope="module")
def fixed_result():
    core = {"param_sets": (golden.PRESETS["RS"].as_tuple(),)}
    return run_engine("fixed", core, [4.0, 10.0, 30.0], 150.0).spikes_ms


@pytest.mark.parametrize("engine", ["fixed", "amaranth"])
def test_python_engines_identical(engine, capsys, fixed_result):
    rc, out, _ = run_cli(capsys, ARGS + ["--engine", engine])
    assert rc == 0
    res = json.loads(out)
    assert res["engine"] == engine and res["model"] == "izhikevich" and res["dt_ms"] == 0.0625
    assert res["spikes_ms"] == fixed_result
    assert sum(len(s) for s in res["spikes_ms"]) > 5


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_hdl_engines_identical(simulator, capsys, fixed_result, build_root):
    rc, out, err = run_cli(capsys, ARGS + ["--engine", simulator, "--build-dir",
                                           str(build_root / f"engine_{simulator}")])
    assert rc == 0, err
    res = json.loads(out)
    assert res["engine"] == simulator and res["spikes_ms"] == fixed_result


def test_fixed_engine_agreement_with_golden_rs_i10(capsys):
    """RS, I = 10, 1 s: the fixed engine against float64 Euler (reported and bounded)."""
    rc, out, _ = run_cli(capsys, ["simulate", "izhikevich", "--engine", "fixed", "--current",
                                  "10", "--duration-ms", "1000", "--json"])
    fx = json.loads(out)["spikes_ms"][0]
    rc, out, _ = run_cli(capsys, ["simulate", "izhikevich", "--engine", "golden", "--current",
                                  "10", "--duration-ms", "1000", "--json"])
    g = json.loads(out)["spikes_ms"][0]
    cmp = compare_trains(g, fx, 0.0625, q_per_ms=0.005)
    print(f"\nRS I=10 1 s: golden {cmp['n_a']} spikes, fixed {cmp['n_b']}, "
          f"max |dt| {cmp['max_abs_error_ms']} ms, within +-1 tick "
          f"{cmp['fraction_within_tick']:.3f}, VP(q=5/s) {cmp['vp_distance']:.4f}")
    assert cmp["n_a"] == cmp["n_b"] == 23
    assert cmp["fraction_within_tick"] == 1.0
