"""``cuneate generate plasticity``: the layer a learning scene runs, as Verilog alone and behind
each face; refusals in one line."""

import json

import pytest

from cuneate.sim.cli import main
from cuneate.sim.cli.run import resolve_scene
from cuneate.sim.plasticity import protocol as P


def test_generate_writes_the_layer_the_scene_runs(tmp_path, capsys):
    assert main(["generate", "plasticity", "cuneate_learning", "--out", str(tmp_path)]) == 0
    desc = json.loads((tmp_path / "learning_layer.json").read_text())
    scene = resolve_scene("cuneate_learning")
    ran = P.layer_config(scene, len(P.templates(scene)["afferents"]))    # as `cuneate run`
    assert (desc["n_sources"], desc["n_targets"], desc["synapses_per_target"]) == \
        (ran.n_sources, ran.n_targets, ran.n_synapses) == (80, 16, 20)
    expected = json.loads(json.dumps(ran.to_dict()))        # the JSON's own types
    assert {k: desc[k] for k in expected} == expected
    head = (tmp_path / "learning_layer.v").read_text()[:4000]
    assert "LearningLayer" in head and "module learning_layer" in \
        (tmp_path / "learning_layer.v").read_text()
    assert "16 CNs x 20 synapses of 80 afferents" in capsys.readouterr().out


@pytest.mark.parametrize("face, ports", [("uart", ["uart_rx", "uart_tx"]),
                                         ("axi", ["s_axis_tdata", "s_axil_awaddr"]),
                                         ("wishbone", ["s_axis_tdata", "wb_adr"])])
def test_generate_behind_every_face(tmp_path, capsys, face, ports):
    argv = ["generate", "plasticity", "cuneate_learning", "--out", str(tmp_path), "--face",
            face]
    if face != "uart":
        argv += ["--readout-synapses", "5"]
    assert main(argv) == 0
    text = (tmp_path / f"learning_layer_{face}.v").read_text()
    assert all(p in text for p in ports), ports
    assert f"behind the {face} face" in capsys.readouterr().out
    if face != "uart":
        regs = json.loads((tmp_path / f"learning_layer_{face}.regmap.json").read_text())
        assert regs


@pytest.mark.parametrize("argv, fragment", [
    (["textures"], "is a texture scene; the layer is made from a learning scene"),
    (["cuneate_learning", "--readout-synapses", "4"], "--readout-synapses sets a face's"),
    (["cuneate_learning", "--face", "axi", "--readout-synapses", "21"],
     "readout_synapses must be 1 .. 20"),
    (["no_such_scene"], "no such file or shipped example"),
])
def test_generate_refuses_in_one_line(tmp_path, capsys, argv, fragment):
    assert main(["generate", "plasticity", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1, err
