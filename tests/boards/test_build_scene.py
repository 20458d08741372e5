"""``cuneate build BOARD SCENE``: a board sized to a scene's blocks, with the link's budget for
it in the report; scenes whose blocks no board top carries, or whose traffic the link cannot
carry in real time, are refused in one line naming the limit."""

import json

from cuneate.sim.cli import main
from cuneate.sim.scenes.scene import DEFAULT_SCENE_TOML


def test_a_board_sized_to_a_scene_reports_its_blocks_and_link_budget(tmp_path, capsys):
    assert main(["build", "ulx3s", "pulse_amplitudes", "--no-bitstream", "--json",
                 "--out", str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    sc = r["scene"]
    assert r["neurons"] == sc["neurons"] == 48 and r["cores"] == 1
    assert [b["block"] for b in sc["blocks"]] == ["izhikevich_core"]
    assert r["core"]["param_sets"][0]["name"] == "RS"
    rows = {row["baud"]: row for row in sc["link_budget"]["rows"]}
    # the scene streams in real time at the board's 3 Mbaud, not at 115200 baud
    assert rows[3_000_000]["real_time"] and not rows[115_200]["real_time"]
    assert 0 < rows[3_000_000]["in_load"] < 1 and sc["link_budget"]["sample_hz"] == 1000
    txt = (tmp_path / "cuneate_ulx3s.report.txt").read_text()
    assert "scene blocks: izhikevich_core (48 neurons" in txt and "3 Mbaud: to the device" in txt


def test_a_scene_whose_blocks_no_board_carries_is_refused(tmp_path, capsys):
    assert main(["build", "ulx3s", "ridge_angle", "--no-bitstream", "--out",
                 str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs the network block on the board" in err[0]


def test_a_scene_the_link_cannot_carry_in_real_time_is_refused_with_the_figure(tmp_path,
                                                                              capsys):
    fast = tmp_path / "fast.toml"
    fast.write_text(DEFAULT_SCENE_TOML.replace("sample_rate_hz = 1000",
                                               "sample_rate_hz = 16000"))
    assert main(["build", "--board", "ulx3s", str(fast), "--no-bitstream", "--out",
                 str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "take 4,400,000 B/s to the board" in err[0]
    assert "more than the 3 Mbaud link's 300,000 B/s (link limit)" in err[0]
    assert "80 currents every sample at 16000 Hz" in err[0]


def test_a_scene_whose_spikes_overflow_a_batch_frame_is_refused(tmp_path, capsys):
    """400 afferents sampled at 100 Hz: their currents fit the line, but at 200 Hz a neuron a
    millisecond's batch would hold 80 spikes, more than a frame carries."""
    many = tmp_path / "many.toml"
    many.write_text(DEFAULT_SCENE_TOML.replace("trials = 10", "trials = 50")
                    .replace("sample_rate_hz = 1000", "sample_rate_hz = 100"))
    assert main(["build", "ulx3s", str(many), "--no-bitstream", "--out",
                 str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "80 spikes a batch of 16 sweeps" in err[0] and "exceed the 79 a spike frame holds" \
        in err[0]
