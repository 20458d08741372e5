"""Texture scenes (``sensor.kind = "mems"``): parsing and refusals, a small run decoded by the
seeds' decoders on golden and fixed, the hard cases (near-identical textures, silent
afferents), recorded traces through the same scene, a grid with the spatial VP."""

import json
import re

import numpy as np
import pytest

from cuneate.sim import cli
from cuneate.sim.scenes import run_scene
from cuneate.sim.scenes.scene import SceneError, example_path, load_scene, parse_scene
from scene_text import scene_with

SMALL = """
[scene]
name = "three textures"
trials = 3
seed = 1

[sensor]
kind = "mems"
effects = ["noise"]
noise = {sigma_mV = 0.01}

[stimulus]
kind = "textures"
textures = ["corduroy", "glass", "latex"]
slide_mm = 3

[[population]]
name = "sa"
model = "izhikevich"
preset = "RS"
pairs = [0, 1]

[run]
engines = ["golden", "fixed"]
"""


def _scene(text=SMALL, **subs):
    return scene_with(text, **subs)


@pytest.fixture(scope="module")
def small_run():
    return run_scene(_scene())


def test_the_example_is_the_seeds_condition_with_the_fingertips_defaults():
    s = load_scene(example_path("textures"))
    assert s.kind == "texture" and s.classes()[:2] == ["plain_weave", "twill"]
    assert len(s.classes()) == 10 and s["scene"]["trials"] == 10
    assert s["stimulus"]["force_mN"] == 400 and s["stimulus"]["velocity_mm_per_s"] == 15
    assert s["hardware"]["update_hz"] == 20000 and s["sensor"]["channels"] == 16
    assert s.engines == ["golden", "fixed", "verilator"]
    small = _scene()
    assert small["sensor"]["sample_rate_hz"] == 2000 and small["sensor"]["effects"] == ["noise"]
    assert small["hardware"]["update_hz"] == 20000 and small["decoder"]["kind"] == "vp"
    assert small["scene"]["duration_ms"] == pytest.approx(50 + 200 + 100 + 200 + 100 + 150)
    assert small.populations[0]["gratings"] == [0, 1] and small.populations[0]["encoding"] == "SA"


@pytest.mark.parametrize("subs,message", [
    ({"seed = 1": "seed = 1\nduration_ms = 900"},
     "scene.duration_ms: a texture trial lasts its protocol's phases"),
    ({'kind = "mems"': 'kind = "mems"\nchannels = 8'},
     "sensor.channels: a MEMS fingertip has 16 tethers (4 sensors x 4), got 8"),
    ({'effects = ["noise"]': 'effects = ["strain"]'},
     "sensor.effects[0]: 'strain' is not an effect of a MEMS fingertip"),
    ({"noise = {sigma_mV = 0.01}": "noise = {sigma_pm = 1}"},
     "sensor.noise.sigma_pm: unknown key"),
    ({"pairs = [0, 1]": "gratings = [0]"}, "population[0].gratings: a MEMS fingertip's "
                                            "afferents take opponent pairs"),
    ({"pairs = [0, 1]": "pairs = [0, 8]"}, "population[0].pairs[1]: out of range: pair 8"),
    ({"pairs = [0, 1]": 'encoding = "FA"'}, "population[0].encoding: texture scenes decode SA"),
    ({"[run]": '[decoder]\nkind = "tree"\n[run]'}, "decoder.kind: a texture scene decodes"),
    ({'"latex"]': '"velvet"]'}, "stimulus.textures[2]: unknown texture 'velvet'"),
    ({'"latex"]': '{name = "l2", like = "latex", colour = 1}]'},
     "stimulus.textures[2]: a texture table takes name, like and the parameters"),
    ({'"latex"]': '"glass"]'}, "stimulus.textures: names a texture twice"),
    ({"[run]": "[grid]\nforces_mN = [400]\n[run]"},
     "grid: a grid needs at least two conditions"),
    ({'kind = "textures"': 'kind = "recorded"\nrecordings = [{file = "a.npz"}]'},
     "stimulus.recordings[0].label: missing required key"),
])
def test_texture_scenes_refuse_in_one_line(subs, message):
    with pytest.raises(SceneError) as e:
        _scene(**subs)
    assert str(e.value).startswith(f"t.toml: {message}"), str(e.value)
    assert "\n" not in str(e.value)


def test_fbg_scenes_refuse_what_only_a_fingertip_has(tmp_path, capsys):
    from cuneate.sim.scenes.scene import DEFAULT_SCENE_TOML
    with pytest.raises(SceneError, match="grid: a grid of sensing conditions runs texture"):
        parse_scene(DEFAULT_SCENE_TOML + "[grid]\nforces_mN = [1, 2]\n", "g.toml")
    with pytest.raises(SceneError, match="sensor.kind: a textures stimulus slides under the "
                                         "MEMS fingertip"):
        _scene(**{'kind = "mems"': 'kind = "fbg"', 'effects = ["noise"]': 'effects = ["strain"]',
                  "noise = {sigma_mV = 0.01}": ""})
    with pytest.raises(SceneError, match="decoder.kind: 'vp' decodes texture scenes"):
        parse_scene(DEFAULT_SCENE_TOML.replace('kind = "tree"', 'kind = "vp"'), "g.toml")
    with pytest.raises(SceneError, match=r"population\[0\].pairs: opponent pairs are a MEMS"):
        parse_scene(DEFAULT_SCENE_TOML.replace('encoding = "FA"', 'encoding = "FA"\npairs = [0]'),
                    "g.toml")
    # the command's one error path: exit 2, one line naming the file and the key
    p = tmp_path / "bad.toml"
    p.write_text(SMALL.replace("seed = 1", "seed = 1\nduration_ms = 900"))
    assert cli.main(["run", str(p), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.toml: scene.duration_ms:" in err[0]


def test_a_small_scene_decodes_on_golden_and_fixed_with_every_row(small_run):
    r = small_run
    a = r.afferent
    assert r.kind == "texture" and r.channels == ["x s0: 2-4", "x s1: 5-7"]
    assert len(a.neurons) == 18 and a.dt_ms == 0.05 and a.config.update_hz == 20000
    assert a.traces[0].shape == (1600, 8) and a.trial_info[0]["tethers_V"].shape == (1600, 16)
    assert a.ran["effects"] == ["noise"] and a.ran["effect_counts"]["noise"] == {"sigma_mV": 0.01}
    assert "golden vs fixed" in a.agreement
    for e in ("golden", "fixed"):
        d = r.decoding[e]
        assert {(x.decoder, x.channel) for x in d.rows} == {
            (dec, ch) for dec in ("rate", "rate + CV", "VP")
            for ch in ("x s0: 2-4", "x s1: 5-7", "all channels")}
        h = d.headline.protocol
        assert h.chance_balanced == pytest.approx(1 / 3) and h.n_samples == 9
        assert d.accuracy > 0.75                      # three textures of distinct frictions
        assert d.window_ms == (0.0, 1600 * 10 * 0.05)


def test_the_report_and_summary(small_run, tmp_path):
    from cuneate.sim.scenes.texture import format_run, write_report
    page = write_report(small_run, tmp_path)
    html = page.read_text()
    for f in ("signals.png", "tethers.png", "vp_matrix_golden.png", "confusion_fixed.png",
              "raster_fixed.png", "spikes_golden.npz", "run.json"):
        assert (tmp_path / f).is_file(), f
    assert "Per-texture recall of VP" in html and "2000 neurons" in html
    summ = json.loads((tmp_path / "run.json").read_text())
    assert summ["kind"] == "texture" and summ["core"]["neurons_per_core"] == 2000
    assert summ["core"]["neurons_per_core_at_16kHz"] == 2500
    assert set(summ["texture_decoding"]) == {"golden", "fixed"}
    assert summ["provenance"]["seeds"]["stimulus.texture_seed"] == 1
    text = format_run(small_run)
    assert re.search(r"golden\s+VP\s+\d+\.\d % over the channels", text)
    assert "VP: 2 matrices of 9 trains" in text


def test_near_identical_textures_are_reported_as_confusions():
    """Two corduroys of close periods (one specimen, 2.6 and 2.65 mm): their trains are nearly
    the same, and the report says which trials went to the other."""
    from cuneate.sim.decode import confusions
    r = run_scene(_scene(**{'"glass", "latex"]': '{name = "corduroy_b", like = "corduroy", '
                                                  'period_u_mm = 2.65}, "latex"]',
                            "trials = 3": "trials = 5", "pairs = [0, 1]": "pairs = [0]",
                            '"golden", "fixed"': '"golden"'}))
    d = r.decoding["golden"]
    pairs = {(t, p) for t, p, _ in confusions(d.headline.protocol)}
    assert pairs & {("corduroy", "corduroy_b"), ("corduroy_b", "corduroy")}
    assert d.headline.protocol.recall["latex"] == 1.0 and d.accuracy < 1.0


def test_silent_afferents_are_reported_not_decoded_at_chance(tmp_path, capsys):
    p = tmp_path / "silent.toml"
    p.write_text(SMALL.replace("[[population]]", "[frontend]\nsa_gain = 10\n\n[[population]]")
                 .replace('"golden", "fixed"', '"fixed"'))
    assert cli.main(["run", str(p), "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert re.search(r"fixed\s+NOT DECODED: no afferent spiked in the window 0-800 ms on any "
                     r"of 2 channels: nothing to decode \(currents peak at 0\.0\d mV/ms", out)
    summ = json.loads((tmp_path / "o" / "run.json").read_text())
    assert summ["accuracy"] == {"fixed": None}


def test_recorded_tethers_run_through_the_same_scene(small_run, tmp_path):
    """Trials written as recordings (16 tethers x samples) and run back: the same opponent
    signals, so the same fixed-point spikes as the synthesized trials; in NPZ (volts) and MAT
    (millivolts, ``stimulus.signal_unit``)."""
    import scipy.io
    a = small_run.afferent
    tm = np.arange(a.traces[0].shape[0]) / 2000.0
    trials = (0, 1, 6, 7)                           # two corduroy and two latex trials
    recs = []
    for i, t in enumerate(trials):
        np.savez(tmp_path / f"r{i}.npz", Time=tm, DeltaBraggW=a.trial_info[t]["tethers_V"].T)
        recs.append(f'{{file = "r{i}.npz", label = "{a.trial_class[t]}"}}')
    scipy.io.savemat(tmp_path / "one.mat", {"Time": tm,
                                            "DeltaBraggW": 1e3 * a.trial_info[6]["tethers_V"]})
    base = SMALL.replace('effects = ["noise"]\n', "").replace("noise = {sigma_mV = 0.01}\n", "") \
        .replace('"golden", "fixed"', '"fixed"')
    (tmp_path / "v.toml").write_text(base.replace(
        'kind = "textures"', 'kind = "recorded"\nrecordings = [' + ", ".join(recs) + "]"))
    (tmp_path / "mv.toml").write_text(base.replace(
        'kind = "textures"', 'kind = "recorded"\nfile = "one.mat"\nlabel = "latex"\n'
                             'signal_unit = "mV"'))
    r = run_scene(load_scene(tmp_path / "v.toml"))
    assert r.afferent.classes == ["corduroy", "latex"] and r.afferent.ran["effects"] == []
    got = r.afferent.spikes["fixed"]
    for i, t in enumerate(trials):
        for k in range(2):
            np.testing.assert_array_equal(got[2 * i + k], a.spikes["fixed"][2 * t + k])
    assert r.decoding["fixed"].accuracy is not None
    one = run_scene(load_scene(tmp_path / "mv.toml"))
    for k in range(2):
        np.testing.assert_array_equal(one.afferent.spikes["fixed"][k], a.spikes["fixed"][12 + k])
    assert one.decoding["fixed"].reason.startswith("too few trials to decode (1 trials")


def test_a_grid_decodes_each_condition_and_the_spatial_vp_across_them(tmp_path):
    from cuneate.sim.scenes.texture import format_run, write_report
    s = _scene(**{"[run]": "[grid]\nforces_mN = [300, 400]\nvelocities_mm_per_s = [10, 15]\n"
                           "scheduler = \"sync\"\n[run]", '"glass", "latex"]': '"latex"]',
                  "trials = 3": "trials = 2", '"golden", "fixed"': '"golden"',
                  "pairs = [0, 1]": "pairs = [0]"})
    r = run_scene(s)
    assert r.kind == "texture" and len(r.cells) == 4
    assert {(c["force_mN"], c["velocity_mm_per_s"]) for c in r.cells} == \
        {(300, 10), (300, 15), (400, 10), (400, 15)}
    slow = next(c for c in r.cells if c["velocity_mm_per_s"] == 10)
    assert slow["slide_ms"][0][1] - slow["slide_ms"][0][0] == pytest.approx(300.0)
    sp = {(x["across"], x["metric"], x["protocol"]) for x in r.spatial}
    assert ("velocities", "space", "leave one condition out") in sp
    assert ("forces", "time", "pooled, leave one trial out") in sp
    assert {x["q_unit"] for x in r.spatial} == {"per ms", "per mm"}
    q = {x["metric"]: x["q"] for x in r.spatial}
    assert q == {"time": 0.005, "space": pytest.approx(5 / 15)}
    page = write_report(r, tmp_path)
    assert (tmp_path / "grid_golden.png").is_file() and "Spatial VP" in page.read_text()
    assert "grid of 4 conditions" in format_run(r)


# --------------------------------------------------------------------------- HDL engines
@pytest.mark.long
@pytest.mark.cocotb
def test_a_texture_scene_on_verilator_and_the_board_equals_fixed(build_root):
    """The core at 20 kHz on Verilator (cocotb) and the board top behind its UART link (the
    board engine): every train equal to the twin's."""
    s = _scene(**{"trials = 3": "trials = 2", "pairs = [0, 1]": "pairs = [0]",
                  '"golden", "fixed"': '"fixed", "verilator", "board"'})
    r = run_scene(s, build_dir=build_root / "texture_scene")
    a = r.afferent
    for e in ("verilator", "board"):
        ag = a.agreement[f"{e} vs fixed"]
        assert ag["spikes_a"] > 100 and ag["identical_trains"] == ag["neurons"] == 6
        assert r.decoding[e].to_dict()["rows"] == r.decoding["fixed"].to_dict()["rows"]
    b = a.counters["board"]
    assert b["frames_lost"] == 0 and b["link_budget"]["measured"]["rows"]


# --------------------------------------------------------------------------- the experiment
def _record(name: str, data: dict) -> None:
    """The release lane's figures, kept under benchmarks/results/ (docs/textures.md quotes
    them)."""
    from pathlib import Path
    out = Path(__file__).resolve().parents[2] / "benchmarks" / "results"
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.json").write_text(json.dumps(data, indent=1, default=float) + "\n")


def _channel_means(d) -> dict:
    return {dec: d.channel_range(dec)[0] for dec in ("rate", "rate + CV", "VP")}


@pytest.mark.release
@pytest.mark.cocotb
def test_the_seeds_condition_on_golden_fixed_and_verilator(tmp_path, build_root):
    """``cuneate run examples/textures.toml``: ten textures x 10 at 400 mN, 15 mm/s; VP + kNN
    (leave-one-out) >= 90 % on every engine, rate and rate + CV below it, fixed = Verilator;
    and the second synthesis seed orders the decoders alike."""
    import time
    t0 = time.perf_counter()
    assert cli.main(["-q", "run", "examples/textures.toml", "--out", str(tmp_path / "a")]) == 0
    wall = time.perf_counter() - t0
    summ = json.loads((tmp_path / "a" / "run.json").read_text())
    assert summ["agreement"]["verilator vs fixed"]["identical_trains"] == 400
    rows = {}
    for e in ("golden", "fixed", "verilator"):
        pc = summ["texture_decoding"][e]["per_channel"]
        m = {dec: pc[dec]["mean"] for dec in ("rate", "rate + CV", "VP")}
        assert m["VP"] >= 0.9 and m["rate"] < m["rate + CV"] < m["VP"], (e, m)
        rows[e] = summ["texture_decoding"][e]
    s2 = load_scene(example_path("textures"))
    s2["stimulus"]["texture_seed"] = 2
    r2 = run_scene(s2, ["golden", "fixed"])
    for e in ("golden", "fixed"):
        m = _channel_means(r2.decoding[e])
        assert m["rate"] < m["rate + CV"] < m["VP"] and m["VP"] >= 0.9, (e, m)
    _record("textures_example", {"wall_s": wall, "timing": summ["timing"],
                                 "agreement": summ["agreement"], "seed_1": rows,
                                 "seed_2": {e: d.to_dict() for e, d in r2.decoding.items()}})


@pytest.mark.release
def test_the_grid_of_25_conditions_and_the_spatial_vp(tmp_path):
    """Force 200-600 mN x velocity 5-25 mm/s, each condition its own run on a local Dask
    cluster, decoded alone (the heat map), then the spatial VP across velocities and forces."""
    import time
    s = load_scene(example_path("textures_grid"))
    t0 = time.perf_counter()
    r = run_scene(s)
    wall = time.perf_counter() - t0
    from cuneate.sim.scenes.texture import format_run, summary, write_report
    from cuneate.sim.scenes.texture_grid import grid_notes
    write_report(r, tmp_path)
    assert len(r.cells) == 25 and (tmp_path / "grid_golden.png").is_file()
    assert {x["across"] for x in r.spatial} == {"velocities", "forces"}
    print(format_run(r))
    _record("textures_grid", {"wall_s": wall, "notes": grid_notes(r, "golden")}
            | {k: v for k, v in summary(r).items() if k in ("cells", "spatial", "timing")})
