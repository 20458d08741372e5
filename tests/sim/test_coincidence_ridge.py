"""The ridge-angle experiment: afferent timing decoded by three cuneate neurons that differ only
in their conduction delays, on golden, fixed and the HDL simulators."""

import json

import numpy as np
import pytest

from cuneate.sim.cli import main
from cuneate.sim.coincidence.experiments import (RidgeSpec, afferent_currents, detector_config,
                                             ridge_comparison, ridge_experiment)
from cuneate.sim.engines.toolchain import SIMULATORS


def test_stimulus_and_tuning_follow_the_geometry():
    spec = RidgeSpec(trials_per_angle=2, jitter_ms=0.0, spread_speed=0.0, spread_force=0.0)
    cur, angles, per = afferent_currents(spec)
    assert cur.shape == (per * 6, 4) and sorted(angles) == [-45, -45, 0, 0, 45, 45]
    dt = 1000 / spec.update_hz
    for k, a in enumerate(angles):
        sa = cur[k * per:(k + 1) * per, [0, 2]]
        t_top, t_bot = np.argmax(sa, axis=0) * dt
        # the lower sensor meets a +45 deg ridge spacing * tan(45) / speed = 12.5 ms later
        assert t_bot - t_top == pytest.approx(12.5 * np.tan(np.radians(a)), abs=dt)
        fa = cur[k * per:(k + 1) * per, [1, 3]]
        assert np.all(fa >= 0) and np.argmax(fa[:, 0]) < np.argmax(sa[:, 0])   # FA leads SA
    cfg = detector_config(spec)
    # neuron j waits for the sensor that meets ridge j first by that ridge's lag (200 ticks)
    assert cfg.delays.tolist() == [[0, 0, 200, 200], [0, 0, 0, 0], [200, 200, 0, 0]]
    assert np.all(cfg.weights_real == cfg.weights_real[0, 0])   # only the delays differ


def test_golden_and_fixed_decode_every_angle_the_same():
    spec = RidgeSpec(trials_per_angle=3)
    g, f = ridge_experiment("golden", spec), ridge_experiment("fixed", spec)
    for r in (g, f):
        assert r.accuracy == 1.0
        # one unique pattern per angle: the neuron tuned to it, alone
        for j, a in enumerate(spec.angles_deg):
            assert {p for p, x in zip(r.patterns, r.trial_angle) if x == a} == {(j,)}
    assert g.decoded == f.decoded and g.patterns == f.patterns
    assert g.counts.shape == (9, 3)


def test_without_the_delays_the_angle_cannot_be_decoded():
    # identical neurons: a vertical ridge fires all three, slanted ridges none of them, so
    # -45 and +45 deg are the same pattern and at most 2/3 of the trials decode
    r = ridge_experiment("golden", RidgeSpec(trials_per_angle=4, delay_scale=0.0))
    for a in (-45.0, 45.0):
        assert {p for p, x in zip(r.patterns, r.trial_angle) if x == a} == {()}
    assert r.accuracy <= 2 / 3


def test_timing_jitter_costs_accuracy():
    r = ridge_experiment("golden", RidgeSpec(trials_per_angle=6, jitter_ms=4.0))
    assert r.accuracy < 0.9


def test_on_chip_network_decodes_like_the_blocks():
    """The afferents on the chip's Izhikevich core, their spikes over the on-chip link: the
    same active neurons on every trial as the afferent twin feeding the detector twin."""
    spec = RidgeSpec(trials_per_angle=2)
    f = ridge_experiment("fixed", spec)
    n = ridge_experiment("fixed", spec, on_chip=True)
    assert n.engine == "fixed (on-chip network)"
    assert n.patterns == f.patterns and n.decoded == f.decoded and n.accuracy == 1.0
    assert np.array_equal(n.counts, f.counts)


@pytest.mark.long
@pytest.mark.cocotb
# Verilator in CI; Icarus (the same netlist, 5x slower here) in the release lane
@pytest.mark.parametrize("simulator", [pytest.param(s, marks=pytest.mark.release)
                                       if s == "icarus" else s for s in SIMULATORS])
def test_ridge_on_chip_network_on_hdl_simulator(simulator, tmp_path):
    cmp = ridge_comparison(RidgeSpec(trials_per_angle=2), hdl_engines=(simulator,),
                           build_dir=str(tmp_path), on_chip=True)
    assert cmp["hdl_fixed_same"] == {simulator: True} and cmp["results"][2].accuracy == 1.0


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", [
    # the ridge scene runs on Verilator in the default lane (tests/sim/test_scene_ridge.py);
    # this experiment on both simulators in the long lane
    pytest.param(s, marks=pytest.mark.long) for s in SIMULATORS])
def test_ridge_on_hdl_simulator_decodes_like_fixed(simulator, tmp_path):
    cmp = ridge_comparison(RidgeSpec(trials_per_angle=2), hdl_engines=(simulator,),
                           build_dir=str(tmp_path))
    g, f, h = cmp["results"]
    assert cmp["golden_fixed_same"] and cmp["hdl_fixed_same"] == {simulator: True}
    assert sorted(h.trial_angle) == [-45.0, 0.0, 45.0] and h.accuracy == 1.0
    assert f.accuracy == 1.0


def test_ridge_command_json(capsys):
    rc = main(["coincidence", "ridge", "--trials", "2", "--hdl-engine", "--json"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    d = json.loads(out.out)
    assert d["golden_fixed_same"] is True and d["hdl_fixed_same"] == {}
    assert [r["engine"] for r in d["results"]] == ["golden", "fixed"]
    assert all(len(r["decoded"]) == 6 for r in d["results"])


def test_ridge_command_refuses_negative_jitter(capsys):
    rc = main(["coincidence", "ridge", "--jitter-ms", "-1", "--hdl-engine"])
    err = capsys.readouterr().err
    assert rc == 2 and "must be >= 0" in err and err.count("\n") == 1


@pytest.mark.long
@pytest.mark.cocotb
def test_ridge_default_experiment_all_engines(capsys, tmp_path):
    """The command's default: 10 trials per angle (jitter 0.3 ms, 5 % speed spread) on golden
    and fixed, one per angle on the Amaranth simulator, Icarus and Verilator."""
    rc = main(["coincidence", "ridge", "--hdl-engine", "amaranth", "icarus", "verilator",
               "--build-dir", str(tmp_path), "--json"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    d = json.loads(out.out)
    assert d["golden_fixed_same"]
    assert d["hdl_fixed_same"] == {"amaranth": True, "icarus": True, "verilator": True}
    assert all(r["accuracy"] == 1.0 for r in d["results"])
