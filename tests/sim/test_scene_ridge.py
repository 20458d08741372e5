"""Ridge scenes: validation, what runs, decoding on golden, fixed and an HDL simulator."""

import json

import numpy as np
import pytest

from cuneate.sim.scenes import afferent as scene_run
from cuneate.sim.scenes import run_scene
from cuneate.sim.cli import main
from cuneate.sim.scenes import SceneError, example_path, load_scene, parse_scene

EXAMPLE = example_path("ridge_angle").read_text()


def _scene(**replace):
    text = EXAMPLE
    for a, b in replace.items():
        assert a in text, a
        text = text.replace(a, b)
    return parse_scene(text, "ridge.toml")


def test_example_resolves():
    s = load_scene(example_path("ridge_angle"))
    pops = {p["name"]: p for p in s.populations}
    assert pops["cn"]["size"] == 3 and pops["cn"]["encoding"] == "spikes"
    assert pops["sa"]["gratings"] == [0, 1] and s["decoder"]["kind"] == "pattern"
    assert s.classes() == ["-45 deg", "+0 deg", "+45 deg"]


@pytest.mark.parametrize("old,new,expect", [
    ("grid = [2, 1]", "grid = [3, 3]", "sensor.grid: a ridge scene has two stacked force"),
    ("ridge_angles_deg = [-45, 0, 45]", "ridge_angles_deg = [10]",
     "stimulus.ridge_angles_deg: must list at least two different angles"),
    ('inputs = ["sa", "fa"]', 'inputs = ["sa"]', "population[2].inputs: must name the two "
                                                  "afferent populations"),
    ('source = "fa"', 'source = "sa"', "projection[1]: a ridge scene has one projection from "
                                       "each afferent population"),
    ("weight = 4.5\n\n[[projection]]", "weight = 4.5\ndelays_ms = [0, 12.5]\n\n[[projection]]",
     "give the delays on both projections or on neither"),
    ("weight = 4.5\n\n[[projection]]", "weight = -1.0\n\n[[projection]]",
     "projection[0].weight: out of range"),
    ('kind = "pattern"', 'kind = "tree"', "decoder.kind: a ridge scene decodes the pattern"),
    ("trials = 6", "trials = 1", "scene.trials: a ridge scene needs at least 2 trials"),
])
def test_ridge_scene_errors(old, new, expect):
    with pytest.raises(SceneError) as e:
        _scene(**{old: new})
    assert str(e.value).startswith("ridge.toml: ") and expect in str(e.value)


FIRST, SECOND = "weight = 4.5\n\n[[projection]]", "target = \"cn\"\nweight = 4.5\n\n[decoder]"


@pytest.mark.parametrize("d1,d2,expect", [
    ("[0, 12.5]", "[12.5, 0]", "the SA and FA projections must use the same delays"),
    ("[0, 1.03]", "[0, 1.03]", "1.03 ms is not a whole number of ticks"),
    ("[0, 1, 2]", "[0, 1, 2]", "an even number of values"),
])
def test_given_delays_are_checked(d1, d2, expect):
    with pytest.raises(SceneError, match=expect):
        _scene(**{FIRST: f"weight = 4.5\ndelays_ms = {d1}\n\n[[projection]]",
                  SECOND: f"target = \"cn\"\nweight = 4.5\ndelays_ms = {d2}\n\n[decoder]"})


def test_given_delays_set_the_cuneate_neurons():
    # two cuneate neurons: one tuned to +45 degrees (upper delayed 12.5 ms), one to 0
    d = "delays_ms = [12.5, 0, 0, 0]"
    s = _scene(**{"weight = 4.5\n\n[[projection]]": f"weight = 4.5\n{d}\n\n[[projection]]",
                  "target = \"cn\"\nweight = 4.5\n\n[decoder]":
                      f"target = \"cn\"\nweight = 4.5\n{d}\n\n[decoder]",
                  "trials = 6": "trials = 2"})
    assert {p["name"]: p for p in s.populations}["cn"]["size"] == 2
    run = run_scene(s, engines=["fixed"])
    r = run.results["fixed"]
    assert run.ran["blocks"][1]["delays_ticks"] == [[200, 200, 0, 0], [0, 0, 0, 0]]
    # the report speaks the scene's unit: ms
    assert run.ran["blocks"][1]["delays_ms"] == [[12.5, 12.5, 0, 0], [0, 0, 0, 0]]
    by = {a: {p for p, x in zip(r.patterns, r.trial_angle) if x == a} for a in r.angles}
    assert by[45.0] == {(0,)} and by[0.0] == {(1,)} and by[-45.0] == {()}


def test_golden_and_fixed_decode_alike_and_only_the_two_blocks_run(monkeypatch):
    def forbidden(*a, **k):
        raise AssertionError("the FBG front end or another block was built")
    monkeypatch.setattr(scene_run, "synthesize", forbidden)
    monkeypatch.setitem(scene_run.BLOCKS, "izhikevich", forbidden)
    run = run_scene(_scene(**{"trials = 6": "trials = 4"}),
                              engines=["golden", "fixed"])
    g, f = run.results["golden"], run.results["fixed"]
    assert g.accuracy == f.accuracy == 1.0 and g.patterns == f.patterns
    assert [b["block"] for b in run.ran["blocks"]] == ["izhikevich_core",
                                                       "coincidence_detector"]


def _run_two_trials(tmp_path, engines):
    """``cuneate run`` of the example with 2 trials on ``engines``; its output folder."""
    out = tmp_path / "r"
    scene = tmp_path / "ridge.toml"
    scene.write_text(EXAMPLE.replace("trials = 6", "trials = 2"))
    assert main(["run", str(scene), "--engines", engines, "--out", str(out)]) == 0
    return out


@pytest.mark.cocotb
def test_ridge_scene_on_verilator_equals_fixed(tmp_path, capsys):
    out = _run_two_trials(tmp_path, "fixed,verilator")
    summ = json.loads((out / "run.json").read_text())
    assert summ["kind"] == "ridge" and summ["identical_patterns"]["verilator"]
    assert summ["engines"]["verilator"]["counts"] == summ["engines"]["fixed"]["counts"]
    assert (out / "ridge_verilator.png").stat().st_size > 1000
    assert "decode accuracy" in capsys.readouterr().out
    # a spike file per engine (there was none): per trial 4 afferents and 3 cuneate neurons,
    # the same trains on both engines, the cuneate spikes per trial those of run.json
    from cuneate.sim.spikes import load_spikes
    assert summ["spike_files"] == {e: f"spikes_{e}.npz" for e in ("fixed", "verilator")}
    f, v = (load_spikes(out / f"spikes_{e}.npz") for e in ("fixed", "verilator"))
    assert len(f) == 2 * 3 * 7 and list(f.population[:7]) == ["sa", "fa", "sa", "fa"] + \
        ["cn"] * 3 and f.t_stop_ms == 120.0
    assert all(np.array_equal(a, b) for a, b in zip(f.trains(), v.trains()))
    per_trial = [[len(t) for t in f.trains()[7 * j + 4: 7 * j + 7]] for j in range(6)]
    assert per_trial == summ["engines"]["fixed"]["counts"]


def test_ridge_report_renders(tmp_path, chromium):
    out = _run_two_trials(tmp_path, "golden")
    dom, console = chromium(out / "index.html")
    assert console == [] and "ridge angle" in dom and dom.count("<img ") == 1
    # one engine: no table comparing golden with itself; delays in ms
    assert "one engine ran: nothing to compare" in dom and "delays (ms" in dom
