"""The coincidence detector's CLI and the ridge-angle experiment on every engine."""

import json

import numpy as np
import pytest

from cuneate.sim.cli import main
from cuneate.sim.cuneate_engines import run_coincidence
from cuneate.sim.experiments_cuneate import (RidgeSpec, afferent_currents, afferent_spikes,
                                             detector_config, ridge_experiment)
from cuneate.sim.toolchain import SIMULATORS

ARGS = ["--sources", "2", "--targets", "2", "--delays-ms", "0,2;2,0", "--spikes",
        "0:10,12,14;1:12,14,16", "--duration-ms", "50", "--json"]


def _sim(capsys, engine, extra=()):
    assert main(["simulate", "coincidence", "--engine", engine, *ARGS, *extra]) == 0
    return json.loads(capsys.readouterr().out)


def test_simulate_json_contract_and_golden_equals_fixed(capsys):
    g, f = _sim(capsys, "golden"), _sim(capsys, "fixed")
    assert g["dt_ms"] == 0.0625 and g["ticks"] == 800
    # target 0 delays source 1 by 2 ms: source 0 at 12, 14 meets source 1 at 10+2, 12+2 ...
    assert g["spike_counts"] == f["spike_counts"] and sum(g["spike_counts"]) == 2
    for a, b in zip(g["spikes_ms"], f["spikes_ms"]):
        assert np.allclose(a, b, atol=0.0625 + 1e-9)
    # spike convention: update of tick k -> (k + 1) dt, on the grid
    assert all(abs(t / 0.0625 - round(t / 0.0625)) < 1e-9 for s in f["spikes_ms"] for t in s)


def test_simulate_on_the_amaranth_simulator_equals_fixed(capsys):
    assert _sim(capsys, "amaranth")["spikes_ms"] == _sim(capsys, "fixed")["spikes_ms"]


@pytest.mark.parametrize("argv,expect", [
    (["--spikes", "0:1.03"], "--spikes: source 0: 1.03 ms is not a tick time"),
    (["--spikes", "7:1"], "--spikes: source 7 is outside 0 .. 3"),
    (["--spikes", "0:x"], "--spikes: expected 'SOURCE:t1,t2;...'"),
    (["--spikes", "0:200"], "--spikes: a spike lies at or after the end of the run"),
    (["--delays-ms", "40,0,0,0;0,0,0,0;0,0,0,0"],
     "delay of target 0 from source 0 is 640 ticks: outside 0 .. 512"),
    (["--delays-ms", "0.01,0,0,0;0,0,0,0;0,0,0,0"], "must be a multiple of dt"),
    (["--delays-ms", "1,2"], "--delays-ms: needs 3 rows (targets) of 4 values"),
    (["--weights", "-1"], "weights must be finite and >= 0"),
    (["--weights", "1e-5"], "rounds to 0"),
    (["--duration-ms", "0.01"], "shorter than one tick"),
    (["--clock-hz", "16e3"], "need 38 cycles per tick"),
    (["--target-sets", "0,1,0"], "target_sets needs 3 indices"),
])
def test_simulate_refusals_are_one_line(argv, expect, capsys):
    assert main(["simulate", "coincidence", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert expect in err and "\n" not in err and err.startswith("cuneate: ")


def test_generate_writes_verilog_and_json(tmp_path, capsys):
    out = tmp_path / "g"
    assert main(["generate", "coincidence", "--out", str(out), "--delays-ms",
                 "20,20,0,0;0,0,0,0;0,0,20,20", "--weights", "4.5"]) == 0
    v = (out / "coincidence_detector.v").read_text()
    d = json.loads((out / "coincidence_detector.json").read_text())
    assert "module coincidence_detector" in v
    assert d["max_delay_ms"] == 32.0 and d["delays_ticks"][0] == [320, 320, 0, 0]
    assert d["ports"]["in_source"]["direction"] == "in" and d["multipliers"] == 6
    assert d["weights_quantized"][0][0] == 4.5 and d["cycles_needed"] == 38
    # the same refusals as simulate, word for word
    assert main(["generate", "coincidence", "--out", str(out), "--weights", "-1"]) == 2
    e1 = capsys.readouterr().err
    assert main(["simulate", "coincidence", "--weights", "-1"]) == 2
    assert capsys.readouterr().err == e1


SMALL = RidgeSpec(trials_per_angle=2)


def test_ridge_decodes_on_golden_and_fixed_alike():
    spec = RidgeSpec(trials_per_angle=6)
    g, f = ridge_experiment("golden", spec), ridge_experiment("fixed", spec)
    # each angle has its own cuneate neuron: one pattern per angle, decoded perfectly
    assert g.accuracy == f.accuracy == 1.0
    assert g.table == f.table == {(0,): -45.0, (1,): 0.0, (2,): 45.0}
    assert g.patterns == f.patterns


def test_one_sensor_alone_does_not_fire_a_cuneate_neuron():
    spec = RidgeSpec(trials_per_angle=2)
    cfg = detector_config(spec)
    cur, angles, per = afferent_currents(spec)
    ins = afferent_spikes(spec, cur, fixed=True)
    assert all(len(x) > 0 for x in ins)
    for keep in ((0, 1), (2, 3)):                     # upper sensor only, lower sensor only
        only = [x if s in keep else np.zeros(0, dtype=np.int64) for s, x in enumerate(ins)]
        run = run_coincidence("fixed", cfg, only, cur.shape[0])
        assert sum(map(len, run.spikes_ms)) == 0


@pytest.mark.cocotb
@pytest.mark.parametrize("engine", [pytest.param("amaranth", marks=pytest.mark.long),
                                    *SIMULATORS])
def test_ridge_on_rtl_engines_equals_fixed(engine, build_root):
    f = ridge_experiment("fixed", SMALL)
    r = ridge_experiment(engine, SMALL, build_dir=build_root / f"ridge_{engine}")
    assert np.array_equal(r.counts, f.counts) and r.counts.sum() > 0
    assert r.accuracy == f.accuracy == 1.0


def test_cli_ridge_prints_the_table(capsys):
    assert main(["coincidence", "ridge", "--engine", "golden", "--trials-per-angle", "2",
                 "--json"]) == 0
    r = json.loads(capsys.readouterr().out)[0]
    assert r["engine"] == "golden" and r["accuracy"] == 1.0
    assert r["table"] == {"[0]": -45.0, "[1]": 0.0, "[2]": 45.0}
