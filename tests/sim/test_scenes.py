"""Scene schema: the embedded default, shipped examples, and one-line errors naming file, key
and reason."""

import pytest

from cuneate.sim import cli
from cuneate.sim.scenes import (DEFAULT_SCENE_TOML, SceneError, default_scene, example_names,
                                example_path, load_scene, parse_scene)


def test_default_scene_is_the_four_material_grasp():
    s = default_scene()
    assert s.classes() == ["dragon_skin", "vytaflex", "abs", "aluminium"]
    assert s["scene"]["trials"] == 10
    assert s["sensor"]["channels"] == 2 and s.effects == ["strain"]
    assert s.engines == ["golden", "fixed", "verilator"]
    assert [p["encoding"] for p in s.populations] == ["FA"]
    assert s.populations[0]["gratings"] == [0, 1]
    assert s["frontend"]["gain_S"] == 180.0 and s["frontend"]["delta_lambda_unit_pm"] == 10.0


def test_examples_ship_and_validate():
    names = example_names()
    assert "slide_texture.toml" in names
    for n in names:
        sc = load_scene(example_path(n))
        assert sc.populations


def _err(text_add, replace=None):
    text = DEFAULT_SCENE_TOML
    if replace:
        text = text.replace(*replace)
    with pytest.raises(SceneError) as ei:
        parse_scene(text + text_add, "s.toml")
    msg = str(ei.value)
    assert "\n" not in msg and msg.startswith("s.toml: ")
    return msg


@pytest.mark.parametrize("add,replace,expect", [
    ("", ("trials = 10", "trials = 10\ncolour = 3"), "s.toml: scene.colour: unknown key"),
    ("", ("duration_ms = 700", "duration = 700"),
     "s.toml: scene.duration: missing unit: write duration_ms"),
    ("", ("velocity_mm_per_s = 1.5", "velocity = 1.5"),
     "stimulus.velocity: missing unit: write velocity_mm_per_s"),
    ("", ("trials = 10", 'trials = "ten"'), "scene.trials: wrong type: expected integer"),
    ("", ("trials = 10", "trials = 0"), "scene.trials: out of range: 0 < 1"),
    ("", ("gain_S = 180", "gain_S = nan"), "frontend.gain_S: must be finite"),
    ("", ('"golden", "fixed", "verilator"', '"golden", "modelsim"'),
     "run.engines[1]: unknown engine 'modelsim'"),
    ("", ('effects = ["strain"]', 'effects = ["strain", "wind"]'),
     "sensor.effects[1]: unknown effect 'wind'"),
    ("", ('effects = ["strain"]', 'effects = ["strain"]\nnoise = {sigma_pm = 1}'),
     "sensor.noise: parameters given for effect 'noise', which sensor.effects does not list"),
    ("", ('effects = ["strain"]', 'effects = ["strain", "noise"]\nnoise = {sigma_pm = -1}'),
     "sensor.noise.sigma_pm: out of range"),
    ("", ('"abs", "aluminium"]', '"abs", "wood"]'), "stimulus.materials[3]: unknown material"),
    ("", ("update_hz = 16000", "update_hz = 15500"), "hardware.update_hz: must be a whole "
                                                     "multiple"),
    ("[[population]]\nname = \"cn\"\nmodel = \"cuneate\"\nencoding = \"spikes\"\nsize = 3\n"
     "inputs = [\"fa\"]\n", None,
     "population[1].size: out of range: at most one cuneate neuron a grating of its fields "
     "(2), got 3"),
    ("[[population]]\nname = \"l\"\nmodel = \"lif\"\n", None,
     "population[1].model: LIF populations run on a taxel skin in this build"),
    ("[[population]]\nname = \"l\"\nmodel = \"hodgkin\"\n", None,
     "population[1].model: must be one of izhikevich, lif, cuneate"),
    ("[[projection]]\nsource = \"fa\"\ntarget = \"nobody\"\n", None,
     "projection[0].target: unknown population 'nobody'"),
    ("[[projection]]\nsource = \"fa\"\ntarget = \"fa\"\ndelays_ms = [-1.0]\n", None,
     "projection[0].delays_ms: out of range"),
    ("[[projection]]\nsource = \"fa\"\ntarget = \"fa\"\ndelays_ms = [0.0, 2.0]\n", None,
     "projection[0]: projections drive a cuneate population (model = \"cuneate\"); the scene "
     "has none"),
    ("", ('preset = "RS"', 'preset = "XX"'), "population[0].preset:"),
    ("[weather]\nsun = 1\n", None, "s.toml: weather: unknown section"),
    ("", ("[[population]]", "[population]"), "population: wrong type: write [[population]]"),
    ("", ("trials = 10", "trials = 400"), "hardware.clock_hz: the scene needs 3200 Izhikevich "
                                          "neurons (1600 trials) but one core at 4e+07 Hz / "
                                          "16000 Hz holds 2500"),
    ("", ("filter_low_hz = 1", "filter_low_hz = 1\nfilter_b = [0.045, 0, -0.045]\n"
                               "filter_a = [1, -1.919, 0.91]"),
     "frontend.filter_a: unstable filter: pole z = 1.06"),
    ("", ("filter_low_hz = 1", "filter_low_hz = 1\nfilter_b = [1.0]"),
     "frontend.filter_a: filter coefficients need both"),
    ("", ('encoding = "FA"', 'encoding = "FA"\nthreshold_pm = 1'),
     "population[0].threshold_pm: a threshold gates the SA afferents of an afferent scene"),
    ("", ("update_hz = 16000", "update_hz = 16000\nboard_trials = 41"),
     "hardware.board_trials: a board holds some of an afferent scene's trials (1 .. 40)"),
])
def test_scene_errors(add, replace, expect):
    assert expect in _err(add, replace)


def test_lif_and_coincidence_populations_validate_before_refusal():
    # a later build's scene: a spike-driven cuneate population with a projection is checked for
    # its own mistakes first (missing size), then refused as unavailable
    msg = _err("[[population]]\nname = \"cn\"\nmodel = \"cuneate\"\nencoding = \"spikes\"\n"
               "inputs = [\"fa\"]\n")
    assert "population[1].size: missing required key" in msg


def test_toml_syntax_error_names_file(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[scene\n")
    with pytest.raises(SceneError, match=r"bad.toml: not valid TOML"):
        load_scene(p)


def test_cli_bad_scene_exits_2_with_one_line(tmp_path, capsys):
    p = tmp_path / "bad.toml"
    p.write_text(DEFAULT_SCENE_TOML.replace("trials = 10", "trials = -3"))
    assert cli.main(["run", str(p), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert "bad.toml: scene.trials: out of range" in err
    assert cli.main(["run", "no_such_scene", "--out", str(tmp_path / "o")]) == 2
    assert "no such file or shipped example" in capsys.readouterr().err
    assert cli.main(["run", "--engines", "golden,spice", "--out", str(tmp_path / "o")]) == 2
    assert "unknown engine 'spice'" in capsys.readouterr().err
