"""Learning scenes (``stimulus.kind = "learning"``): parsing and refusals, a small run through
the protocol on golden and fixed with its report (the long lane); in the release lane the thesis's protocol on
golden, fixed and Verilator, and the 10-texture version."""

import json

import numpy as np
import pytest

from cuneate.sim import cli
from cuneate.sim.scenes import run_scene
from cuneate.sim.scenes.scene import SceneError, example_path, load_scene, parse_scene
from scene_text import scene_with

SMALL = """
[scene]
name = "a small learning layer"
seed = 1

[sensor]
kind = "mems"

[stimulus]
kind = "learning"
textures = ["latex", "bars"]
slide_mm = 3

[[population]]
name = "sa"
model = "izhikevich"
preset = "RS"
gratings = [0, 1, 2, 3, 4, 5]

[learning]
presentations = 3
test_presentations = 3
window_ms = [250, 330]
gap_ms = 10
afferent_gains = [1.0, 2.0]
cns = 3
synapses_per_cn = 6
eta = 1e-4

[decoder]
kind = "vp"
q_per_s = 20
neighbours = 1

[run]
engines = ["golden", "fixed"]
"""


def _scene(text=SMALL, **subs):
    return scene_with(text, **subs)


def test_the_example_is_the_thesis_protocol():
    s = load_scene(example_path("cuneate_learning"))
    lp = s["learning"]
    assert s.kind == "learning" and len(s.classes()) == 5 and s.classes()[3:] == ["bars",
                                                                                  "dots"]
    assert lp["presentations"] == 300 and lp["jitter_ms"] == 5
    assert len(s.populations[0]["gratings"]) * len(lp["afferent_gains"]) == 80
    assert s.engines == ["golden", "fixed", "verilator-fast"] and s["scene"]["trials"] == 1


@pytest.mark.parametrize("subs,message", [
    ({'kind = "mems"': 'kind = "fbg"'}, "sensor.kind"),
    ({"seed = 1": "seed = 1\ntrials = 4"}, "scene.trials: a learning scene synthesizes one"),
    ({"synapses_per_cn = 6": "synapses_per_cn = 13"}, "learning.synapses_per_cn: 13 synapses "
                                                      "but only 12 afferents"),
    ({"neighbours = 1": "neighbours = 3"}, "decoder.neighbours: 3 neighbours"),
    ({"window_ms = [250, 330]": "window_ms = [250, 9000]"}, "learning.window_ms"),
    ({'engines = ["golden", "fixed"]': 'engines = ["loihi"]'},
     "run.engines[0]: unknown engine 'loihi' (the plasticity block runs on: golden"),
    ({"eta = 1e-4": "eta = 1e-12"}, "learning: the step eta = 1e-12 rounds to 0"),
])
def test_a_bad_learning_scene_is_refused_in_one_line(subs, message):
    with pytest.raises(SceneError, match=message.replace("(", r"\(").replace("[", r"\[")) \
            as exc:
        _scene(**subs)
    assert "\n" not in str(exc.value)


def test_the_learning_protocol_belongs_to_learning_scenes():
    text = load_scene(example_path("textures")).source
    with pytest.raises(SceneError, match="learning: the learning protocol belongs"):
        parse_scene(open(text).read() + "\n[learning]\ncns = 2\n", "t.toml")


@pytest.mark.long
def test_a_small_layer_learns_on_golden_and_fixed_and_reports_it(tmp_path):
    from cuneate.sim.scenes.learning import format_run, write_report
    r = run_scene(_scene())
    assert list(r.runs) == ["golden", "fixed"] and r.presentations.n == 2 * (3 + 2 * 3)
    assert (r.phase == "training").sum() == 6
    f = r.results["fixed"]
    assert not np.array_equal(f["weights_before"], f["weights_after"])
    assert r.runs["fixed"].spike_cn.size > 0
    a = r.agreement["golden vs fixed"]
    assert a["max_abs_weight_diff"] < 0.05 and a["strong_agree"] == 1.0
    page = write_report(r, tmp_path)
    summ = json.loads((tmp_path / "run.json").read_text())
    assert summ["presentations"] == {"before": 6, "training": 6, "after": 6}
    assert set(summ["engines"]) == {"golden", "fixed"} and summ["afferents"] == 12
    for name in ("weights.png", "curves.png", "selectivity.png", "weight_matrix.png",
                 "templates.png", "weights_fixed.npz", "learned_fixed.nir"):
        assert (tmp_path / name).is_file(), name
    assert "Decoding the stimuli from the CNs" in page.read_text()
    assert "golden vs fixed" in format_run(r)


# --------------------------------------------------------------------------- the protocol
def _record(name: str, data: dict) -> None:
    """The release lane's figures, kept under benchmarks/results/ (benchmarks/learning.md
    quotes them)."""
    from pathlib import Path
    out = Path(__file__).resolve().parents[2] / "benchmarks" / "results"
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.json").write_text(json.dumps(data, indent=1, default=float) + "\n")


def _keep(summ: dict) -> dict:
    return {k: summ[k] for k in ("stimuli", "cns", "synapses_per_cn", "presentations",
                                 "agreement", "timing", "stdp")} | {
        "engines": {e: {k: v for k, v in s.items() if k != "curve"}
                    for e, s in summ["engines"].items()}}


@pytest.mark.release
def test_the_thesis_protocol_on_golden_fixed_and_verilator(tmp_path):
    """``cuneate run examples/cuneate_learning.toml``: 1500 presentations; golden and fixed end
    with a few strong synapses per CN and decode the stimuli from the CNs better than before
    learning (Victor-Purpura on the population and on each CN alone); Verilator's layer ends
    with the twin's weights, every one, and its spikes."""
    import time
    t0 = time.perf_counter()
    assert cli.main(["-q", "run", "examples/cuneate_learning.toml", "--out",
                     str(tmp_path)]) == 0
    wall = time.perf_counter() - t0
    summ = json.loads((tmp_path / "run.json").read_text())
    a = summ["agreement"]["verilator-fast vs fixed"]
    assert a["weights_identical"] == a["weights"] == 16 * 20 and a["spikes_identical"]
    for e in ("golden", "fixed"):
        s = summ["engines"][e]
        strong = np.asarray(s["strong_per_cn_after"])
        assert np.median(strong) <= 8 and 0.1 <= s["strong_fraction_after"] <= 0.4, (e, s)
        d = s["decoding"]
        assert d["after"]["vp"] >= d["before"]["vp"], (e, d)
        assert d["after"]["vp_each_cn"]["median"] > d["before"]["vp_each_cn"]["median"], (e, d)
    _record("learning_example", {"wall_s": wall} | _keep(summ))


@pytest.mark.release
def test_the_ten_texture_version_beside_the_anchor(tmp_path):
    """``examples/cuneate_learning_textures.toml``: the same protocol on the ten textures, 25
    CNs (the anchor's: a median of 96 % across 25 learning CNs), golden and fixed and golden's
    STDP beside AIDP."""
    import time
    t0 = time.perf_counter()
    assert cli.main(["-q", "run", "examples/cuneate_learning_textures.toml", "--out",
                     str(tmp_path)]) == 0
    wall = time.perf_counter() - t0
    summ = json.loads((tmp_path / "run.json").read_text())
    for e in ("golden", "fixed"):
        d = summ["engines"][e]["decoding"]
        assert d["after"]["vp_each_cn"]["median"] > d["before"]["vp_each_cn"]["median"], d
    _record("learning_textures", {"wall_s": wall} | _keep(summ))
