"""``cuneate run``: a scene end to end, only what it calls for, and its report."""

import json
import re

import numpy as np
import pytest

from cuneate.golden import tactile
from cuneate.sim import cli
from cuneate.sim.scenes import afferent as scene_run
from cuneate.sim.scenes import run_scene
from cuneate.sim.scenes import DEFAULT_SCENE_TOML, parse_scene
from cuneate.sim.engines.toolchain import SIMULATORS

SMALL = DEFAULT_SCENE_TOML.replace("trials = 10", "trials = 4").replace(
    "cv_folds = 50", "cv_folds = 10")


def _scene(text=SMALL, engines=("golden", "fixed")):
    text = re.sub(r"engines = \[.*\]", "engines = [" + ", ".join(f'"{e}"' for e in engines)
                  + "]", text)
    return parse_scene(text, "small.toml")


@pytest.fixture(scope="module")
def small_run():
    return run_scene(_scene())


def test_golden_and_fixed_decode_alike(small_run):
    r = small_run
    assert len(r.neurons) == 4 * 4 * 2
    g, f = r.decoded["golden"], r.decoded["fixed"]
    assert g.accuracy is not None and f.accuracy is not None
    assert g.accuracy > 0.5 and f.accuracy > 0.5            # chance is 0.25
    assert abs(g.accuracy - f.accuracy) <= r.scene["decoder"]["tolerance"]
    assert r.decode_agreement["fixed vs golden"]["within"]
    a = r.agreement["golden vs fixed"]
    assert a["spikes_a"] > 0 and a["mean_abs_count_diff"] <= 1.0
    assert r.saturations["format_high"] == 0 and r.saturations["format_low"] == 0


def test_spike_files_load_back_equal_to_the_engines_trains(small_run, tmp_path):
    from cuneate.sim.spikes import load_spikes
    files = scene_run.write_spike_files(small_run, tmp_path)
    nn = small_run.neurons
    for e, trains in small_run.spikes.items():
        sf = load_spikes(tmp_path / files[e])
        assert sf.engine == e and sf.dt_ms == small_run.dt_ms
        assert sf.t_stop_ms == small_run.n_ticks * small_run.dt_ms
        assert len(sf.trains()) == len(trains)
        for got, want in zip(sf.trains(), trains):
            assert np.array_equal(got, np.asarray(want, dtype=float))
        assert list(sf.trial) == list(nn.trial) and list(sf.grating) == list(nn.grating)
        assert list(sf.population) == list(nn.population)
        assert list(sf.classes) == [small_run.trial_class[t] for t in nn.trial]
        neo = load_spikes(tmp_path / files[e], as_neo=True)
        i = int(np.argmax([len(t) for t in trains]))
        assert np.array_equal(neo[i].rescale("ms").magnitude, np.asarray(trains[i]))
        assert neo[i].annotations["class"] == small_run.trial_class[nn.trial[i]]
        assert neo[i].annotations["trial"] == nn.trial[i]


def test_report_lists_exactly_what_ran(small_run):
    ran = small_run.ran
    assert ran["effects"] == ["strain"]
    assert ran["engines"] == ["golden", "fixed"]
    assert [b["block"] for b in ran["blocks"]] == ["izhikevich_core"]
    # the core is sized to the scene's neurons, not to the 2500 of the default hardware
    assert ran["blocks"][0]["neurons"] == 32 and ran["blocks"][0]["core_neurons"] == 32
    assert small_run.config.n_neurons == 32


def test_unrequested_engines_effects_and_blocks_are_not_instantiated(monkeypatch):
    called = []

    def spy(name):
        def f(*a, **k):
            called.append(name)
            raise AssertionError(f"{name} must not run")
        return f
    for e in ("verilator", "icarus", "amaranth", "golden"):
        monkeypatch.setitem(scene_run.ENGINES, e, spy(e))
    for e in tactile.EFFECTS:
        monkeypatch.setitem(tactile.EFFECTS, e, spy(e))
    monkeypatch.setitem(scene_run.BLOCKS, "cuneate", spy("cuneate block"))
    monkeypatch.setitem(scene_run.BLOCKS, "lif", spy("lif block"))
    r = run_scene(_scene(engines=("fixed",)))
    assert called == [] and list(r.spikes) == ["fixed"]
    # and an effect that is listed is computed (the spy is reached)
    text = SMALL.replace('effects = ["strain"]', 'effects = ["strain", "noise"]')
    with pytest.raises(AssertionError, match="noise must not run"):
        run_scene(_scene(text, engines=("fixed",)))


def test_dropped_samples_are_held_and_counted():
    text = SMALL.replace('effects = ["strain"]',
                         'effects = ["strain", "dropped_samples"]\n'
                         'dropped_samples = {probability = 0.01}')
    r = run_scene(_scene(text, engines=("fixed",)))
    n = r.ran["effect_counts"]["dropped_samples"]["samples_dropped"]
    assert n > 0 and r.saturations["gaps_held"] == n * 2      # both gratings of each sample


def test_cli_run_writes_report_with_every_figure(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(SMALL.replace('engines = ["golden", "fixed", "verilator"]',
                               'engines = ["golden", "fixed"]'))
    out = tmp_path / "rep"
    assert cli.main(["run", str(p), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert re.search(r"golden\s+balanced accuracy\s+\d+\.\d %.*published", text)
    assert re.search(r"fixed\s+balanced accuracy\s+\d+\.\d %.*published", text)
    page = (out / "index.html").read_text()
    links = re.findall(r'src="([^"]+)"', page)
    assert {"traces.png", "currents.png", "raster_golden.png", "raster_fixed.png",
            "isi_golden.png", "confusion_fixed.png"} <= set(links)
    for link in links:
        f = out / link
        assert f.is_file() and f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summ = json.loads((out / "run.json").read_text())
    assert summ["ran"]["engines"] == ["golden", "fixed"]
    assert set(summ["accuracy"]) == {"golden", "fixed"}
    # the headline is the grouped per-grasp balanced accuracy; the published row is kept
    for e in ("golden", "fixed"):
        rows = summ["decoded"][e]["protocols"]
        assert rows[0]["name"] == "grasp-grouped, per grasp"
        assert summ["accuracy"][e] == rows[0]["balanced_accuracy"]
        assert rows[0]["chance_balanced"] == 0.25 and set(rows[0]["recall"]) == set(
            summ["classes"])
        assert rows[-1]["name"].startswith("published")
    assert "published protocol" in page and "balanced accuracy" in page
    # spike files, linked from run.json, load back equal to what the engines produced
    from cuneate.sim.spikes import load_spikes
    assert summ["spike_files"] == {"golden": "spikes_golden.npz", "fixed": "spikes_fixed.npz"}
    sf = load_spikes(out / "spikes_fixed.npz")
    assert sf.engine == "fixed" and len(sf) == summ["neurons"]
    assert sum(t.size for t in sf.trains()) == summ["spike_counts"]["fixed"]
    assert summ["provenance"]["cuneate"] == summ["version"]
    assert summ["provenance"]["tools"]["numpy"] == np.__version__


@pytest.mark.parametrize("name,front_end", [("slide_texture", ["FA", "SA"]),
                                            ("pulse_amplitudes", ["SA"])])
def test_example_scenes_run(name, front_end, tmp_path, capsys):
    assert cli.main(["run", f"examples/{name}.toml", "--out", str(tmp_path)]) == 0
    summ = json.loads((tmp_path / "run.json").read_text())
    assert summ["ran"]["front_end"] == front_end
    assert summ["ran"]["effects"] == ["strain", "noise", "resolution"]
    assert summ["accuracy"]["fixed"] > 1 / 3 + 0.2          # three classes
    assert summ["saturations"]["format_high"] == 0


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_scene_on_hdl_simulator_equals_twin(simulator, build_root):
    text = SMALL.replace("trials = 4", "trials = 1").replace("duration_ms = 700",
                                                             "duration_ms = 250")
    r = run_scene(_scene(text, engines=("fixed", simulator)),
                             build_dir=build_root / f"scene_{simulator}")
    a = r.agreement[f"{simulator} vs fixed"]
    assert a["spikes_a"] > 0 and a["identical_trains"] == a["neurons"] == 8
    for x, y in zip(r.spikes[simulator], r.spikes["fixed"]):
        assert np.array_equal(x, y)


def test_report_renders_in_headless_chromium_without_console_messages(tmp_path, chromium):
    out = tmp_path / "rep"
    assert cli.main(["run", "--engines", "golden,fixed", "--out", str(out)]) == 0
    page = out / "index.html"
    dom, console = chromium(page)
    assert "<h1>four-material grasp</h1>" in dom
    assert dom.count("<img ") == len(re.findall(r"<img ", page.read_text())) >= 8
    assert console == [], console
    for link in re.findall(r'src="([^"]+)"', dom):
        assert (out / link).is_file(), link
    # negative control: the same page with one figure gone is caught by the browser
    (out / "isi_fixed.png").unlink()
    _, console = chromium(page)
    assert len(console) == 1 and "missing figure: isi_fixed.png" in console[0]


@pytest.mark.long
@pytest.mark.cocotb
def test_default_scene_on_golden_fixed_and_verilator(tmp_path, capsys):
    """The README's main job, as shipped: 40 grasps on golden, fixed and Verilator."""
    assert cli.main(["run", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    for e in ("golden", "fixed", "verilator"):
        assert re.search(rf"{e}\s+balanced accuracy\s+\d+\.\d %", text)
    summ = json.loads((tmp_path / "run.json").read_text())
    assert summ["ran"]["engines"] == ["golden", "fixed", "verilator"]
    assert summ["agreement"]["verilator vs fixed"]["identical_trains"] == 80
    assert summ["decode_agreement"]["fixed vs golden"]["within"]
    assert summ["accuracy"]["verilator"] == summ["accuracy"]["fixed"] > 0.6


def test_scene_on_amaranth_simulator_equals_twin(tmp_path):
    from cuneate.sim.engines.waves import Waves
    text = SMALL.replace("trials = 4", "trials = 1").replace("duration_ms = 700",
                                                             "duration_ms = 150")
    r = run_scene(_scene(text, engines=("fixed", "amaranth")),
                  waves=Waves(tmp_path / "w", start=100, ticks=20))
    a = r.agreement["amaranth vs fixed"]
    assert a["spikes_a"] > 0 and a["identical_trains"] == a["neurons"] == 8
    assert r.counters["amaranth"]["writes"] == r.counters["fixed"]["writes"] > 0
    # the waveform window: only the RTL engine dumps, 20 of the run's 2400 ticks (each tick a
    # sweep of 8 cycles plus the host's writes and the spike drain, ~36 clock edges)
    w = r.files["waves"]
    assert list(w["files"]) == ["amaranth"] and w["start_tick"] == 100
    vcd = (tmp_path / "w" / "amaranth.vcd").read_text()
    assert "$enddefinitions" in vcd and " i_wr_en $end" in vcd and " spike_valid $end" in vcd
    stamps = [ln for ln in vcd.splitlines() if ln.startswith("#")]
    assert r.n_ticks == 2400 and 20 * 8 <= len(stamps) <= 22 * 50
    assert int(stamps[0][1:]) > 0                      # opens after tick 99, not at time 0
    assert (tmp_path / "w" / "amaranth.gtkw").is_file()


def test_a_silent_scene_reports_why_without_warnings(tmp_path, capsys, recwarn):
    p = tmp_path / "s.toml"
    p.write_text(SMALL.replace("gain_S = 180", "gain_S = 1"))
    assert cli.main(["run", str(p), "--engines", "fixed", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr()
    assert "too few samples to cross-validate (0 samples" in out.out
    assert re.search(r"warning: fixed: no neuron spiked \(currents peak at 0\.\d\d mV/ms",
                     out.out)
    # stderr (not a terminal here) holds only the timestamped progress lines
    assert out.err and all(re.match(r"\[\d\d:\d\d:\d\d\] ", x)
                           for x in out.err.splitlines())
    assert "warning" not in out.err.lower() and len(recwarn) == 0
    assert (tmp_path / "o" / "isi_fixed.png").is_file()
    assert cli.main(["-q", "run", str(p), "--engines", "fixed", "--out",
                     str(tmp_path / "q")]) == 0
    assert capsys.readouterr().err == ""


def test_list_examples_marks_the_default_and_describes_each(capsys):
    from cuneate.sim.scenes.scene import example_names
    assert cli.main(["run", "--list-examples"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "(default: run without SCENE) four-material grasp"
    heads = [i for i, x in enumerate(lines) if x.startswith("examples/")]
    assert len(heads) == len(example_names())
    for i in heads:                      # every example has a description under it
        assert lines[i + 1].startswith("    ") and len(lines[i + 1].strip()) > 10


def test_help_states_defaults(capsys):
    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: out/run)" in text and "(default: 100)" in text
