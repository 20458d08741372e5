"""Taxel-skin scenes: validation, what runs, the skin's behaviour on every engine, the CLI."""

import json

import numpy as np
import pytest

from cuneate.sim.scenes import afferent as scene_run
from cuneate.sim.scenes import run_scene
from cuneate.sim.cli import main
from cuneate.sim.scenes import SceneError, example_path, load_scene, parse_scene

SIMULATORS = ("icarus", "verilator")

SKIN = """
[scene]
name = "skin"
[sensor]
kind = "taxels"
grid = [3, 3]
sample_rate_hz = 1000
[stimulus]
kind = "press"
press_taxel = 4
press_widths_ms = [10, 30]
press_amplitudes_N = [1.0, 2.0]
press_base_width_ms = 30
press_gap_ms = 40
[frontend]
force_offset_mV = 5
force_gain_mV_per_N = 20
[[population]]
name = "skin"
model = "lif"
[hardware]
update_hz = 1000
[run]
engines = ["golden", "fixed"]
"""


def _scene(text=SKIN, **replace):
    for a, b in replace.items():
        assert a in text, a
        text = text.replace(a, b)
    return parse_scene(text, "skin.toml")


def _err(old, new):
    with pytest.raises(SceneError) as e:
        _scene(**{old: new})
    return str(e.value)


def test_example_resolves_its_defaults():
    s = load_scene(example_path("skin_3x3"))
    assert s["sensor"]["channels"] == 9 and s["sensor"]["effects"] == []
    assert s["scene"]["trials"] == 1
    # 30 ms of rest (half a gap), 3 width pulses (20 + 40 + 80 ms) and 3 force pulses (40 ms),
    # each followed by 60 ms of rest
    assert s["scene"]["duration_ms"] == pytest.approx(30 + 140 + 120 + 6 * 60)
    p = s.populations[0]
    assert (p["model"], p["encoding"], p["preset"], p["size"]) == ("lif", "force",
                                                                   "excitatory", 9)
    assert s["hardware"]["current_int_bits"] == 8 and s["decoder"]["kind"] == "winner"


@pytest.mark.parametrize("old,new,expect", [
    ("grid = [3, 3]", "grid = [3, 3]\nchannels = 8", "sensor.channels: a 3x3 grid has 9"),
    ("grid = [3, 3]", "grid = [3, 0]", "sensor.grid: must be [rows, columns]"),
    ("press_taxel = 4", "press_taxel = 9", "stimulus.press_taxel: out of range: 9"),
    ("press_widths_ms = [10, 30]", "press_widths_ms = [30, 10]",
     "stimulus.press_widths_ms: must list at least two growing widths"),
    ("name = \"skin\"\n[sensor]", "name = \"skin\"\ntrials = 3\n[sensor]",
     "scene.trials: a press stimulus is deterministic"),
    ("name = \"skin\"\n[sensor]", "name = \"skin\"\nduration_ms = 100\n[sensor]",
     "scene.duration_ms: shorter than the press protocol (280 ms)"),
    ("sample_rate_hz = 1000", "sample_rate_hz = 1000\neffects = [\"strain\"]",
     "sensor.effects: FBG effects do not apply to a taxel sensor"),
    ("force_gain_mV_per_N = 20", "force_gain_mV_per_N = 100",
     "frontend.force_gain_mV_per_N: currents 5..205 mV leave the LIF core's input format"),
    ("model = \"lif\"", "model = \"lif\"\npreset = \"RS\"",
     "population[0].preset: unknown LIF preset 'RS'"),
    ("model = \"lif\"", "model = \"izhikevich\"",
     "population[0].model: a taxel skin drives LIF neurons"),
    ("[run]", "[decoder]\nkind = \"tree\"\n[run]", "decoder.kind: a taxel skin decodes"),
    ("kind = \"press\"", "kind = \"grasp\"", "stimulus.kind: a taxel sensor takes a press"),
    ("update_hz = 1000", "update_hz = 1500", "hardware.update_hz: must be a whole multiple"),
    ("force_offset_mV", "force_offset", "frontend.force_offset: missing unit: write "
                                        "force_offset_mV"),
])
def test_skin_scene_errors(old, new, expect):
    msg = _err(old, new)
    assert msg.startswith("skin.toml: ") and "\n" not in msg
    assert expect in msg


def test_lif_population_on_an_fbg_scene_is_refused():
    from cuneate.sim.scenes import DEFAULT_SCENE_TOML
    text = DEFAULT_SCENE_TOML.replace('model = "izhikevich"', 'model = "lif"')
    with pytest.raises(SceneError, match=r"population\[0\].model: LIF populations run on a "
                                         r"taxel skin"):
        parse_scene(text, "grasp.toml")


def test_grid_press_behaves_and_only_the_lif_core_runs(monkeypatch):
    # the Izhikevich block and the FBG front end must not be touched by a skin scene
    def forbidden(*a, **k):
        raise AssertionError("an unrequested block or front end was built")
    monkeypatch.setitem(scene_run.BLOCKS, "izhikevich", forbidden)
    monkeypatch.setattr(scene_run, "synthesize", forbidden)
    import cuneate.sim.lif.engines as le
    ran = []
    real = le.run_lif

    def spy(engine, *a, **k):
        ran.append(engine)
        return real(engine, *a, **k)
    monkeypatch.setattr(le, "run_lif", spy)
    import cuneate.sim.lif.experiments as ex
    monkeypatch.setattr(ex, "run_lif", spy)
    # a corner of a 4x5 grid
    s = _scene(**{"grid = [3, 3]": "grid = [4, 5]", "press_taxel = 4": "press_taxel = 0"})
    run = run_scene(s)
    assert ran == ["golden", "fixed"]
    assert [b["block"] for b in run.ran["blocks"]] == ["lif_core"]
    assert run.ran["effects"] == [] and run.ran["engines"] == ["golden", "fixed"]
    for e, r in run.results.items():
        assert r.counts.shape == (4, 5)
        assert r.winner == 0 and r.width_monotonic and r.amplitude_monotonic, e
        # the force reaches only the pressed taxel's neighbours
        assert r.counts[2:, :].sum() == 0 and r.counts[:, 2:].sum() == 0
        # edge neighbours feel twice the diagonal's force: at least as many spikes
        assert r.counts[0, 1] == r.counts[1, 0] >= r.counts[1, 1]
    # golden (exact exponential integration in float64) and the twin agree spike for spike
    a = run.agreement["golden vs fixed"]
    assert a["identical_trains"] == 20 and a["max_abs_count_diff"] == 0


def test_centre_press_is_symmetric():
    run = run_scene(_scene(), engines=["fixed"])
    c = run.results["fixed"].counts
    assert np.array_equal(c, c.T) and np.array_equal(c, c[::-1, ::-1])
    assert c[1, 1] > c[0, 1] > 0 and run.results["fixed"].row_sums == \
        run.results["fixed"].col_sums


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_skin_scene_on_hdl_simulator(simulator, tmp_path):
    run = run_scene(_scene(), engines=["fixed", simulator], build_dir=tmp_path)
    r = run.results[simulator]
    assert r.winner == 4 and r.width_monotonic and r.amplitude_monotonic
    a = run.agreement[f"{simulator} vs fixed"]
    assert a["identical_trains"] == 9 and a["spikes_a"] == a["spikes_b"] > 0


def test_cli_runs_the_skin_example(tmp_path, capsys):
    out = tmp_path / "skin"
    assert main(["run", "examples/skin_3x3", "--engines", "golden,fixed", "--out",
                 str(out)]) == 0
    text = capsys.readouterr().out
    assert "winner taxel 4 (pressed)" in text and "golden vs fixed: 9/9 identical" in text
    summ = json.loads((out / "run.json").read_text())
    assert summ["kind"] == "skin" and summ["decoded"]["fixed"] == {"winner": 4,
                                                                    "correct": True}
    assert summ["engines"]["golden"]["row_sums"] == summ["engines"]["fixed"]["row_sums"]
    html = (out / "index.html").read_text()
    for fig in ("press.png", "skin_golden.png", "skin_fixed.png"):
        assert (out / fig).stat().st_size > 1000 and fig in html
    # a spike file per engine (there was none): one neuron per taxel, listed on the page
    from cuneate.sim.spikes import load_spikes
    for e in ("golden", "fixed"):
        f = load_spikes(out / f"spikes_{e}.npz")
        assert [len(t) for t in f.trains()] == \
            [c for row in summ["engines"][e]["counts"] for c in row]
        assert f"spikes_{e}.npz" in html and summ["spike_files"][e] == f"spikes_{e}.npz"
    assert main(["run", "examples/skin_3x3", "--engines", "golden", "--json", "--out",
                 str(tmp_path / "j")]) == 0
    assert json.loads(capsys.readouterr().out)["engines"]["golden"]["winner"] == 4


def test_skin_report_renders_in_headless_chromium(tmp_path, chromium):
    out = tmp_path / "skin"
    assert main(["run", "examples/skin_3x3", "--engines", "golden,fixed", "--out",
                 str(out)]) == 0
    dom, console = chromium(out / "index.html")
    assert "<h1>3x3 LIF skin, centre taxel pressed</h1>" in dom and console == [], console
    assert dom.count("<img ") == 3
    (out / "skin_fixed.png").unlink()
    _, console = chromium(out / "index.html")
    assert len(console) == 1 and "missing figure: skin_fixed.png" in console[0]
