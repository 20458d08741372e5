"""``cuneate build BOARD SCENE``: a board sized to a scene's blocks, with the link's budget for
it in the report; scenes whose blocks no board top carries, or whose traffic the link cannot
carry in real time, are refused in one line naming the limit."""

import json

import pytest

from cuneate.sim.cli import main
from cuneate.sim.scenes.scene import DEFAULT_SCENE_TOML, example_path


def example_text(name: str) -> str:
    return example_path(name).read_text()


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


def test_the_ridge_scene_at_16_khz_is_refused_by_the_link_budget(tmp_path, capsys):
    """The ridge scene's afferent currents change every 62.5 us sweep: a step and a write
    frame a sweep are more than 3 Mbaud carries."""
    assert main(["build", "ulx3s", "ridge_angle", "--no-bitstream", "--out",
                 str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "the scene's currents take 848,000 B/s to the board" in err[0]
    assert "6 currents every sample at 16000 Hz" in err[0] and "(link limit)" in err[0]


def test_a_ridge_scene_builds_the_network_behind_the_link(tmp_path, capsys):
    """At 4 kHz sweeps the ridge's currents fit the line: the board holds the on-chip
    afferent -> cuneate network (6 afferents: the core's smallest, 3 coincidence detectors)
    behind the link."""
    src = tmp_path / "ridge4k.toml"
    src.write_text(example_text("ridge_angle") + "\n[hardware]\nupdate_hz = 4000\n")
    assert main(["build", "ulx3s", str(src), "--no-bitstream", "--json", "--out",
                 str(tmp_path / "b")]) == 0
    r = json.loads(capsys.readouterr().out)
    sc = r["scene"]
    assert sc["kind"] == "network" and r["neurons"] == 9
    assert [b["block"] for b in sc["blocks"]] == ["izhikevich_core", "coincidence_detector"]
    assert [b["neurons"] for b in sc["blocks"]] == [6, 3]
    # the link carries the spike ids of both populations; the sweep is the board's
    assert r["link"]["n_spike_ids"] == 9 and r["link"]["n_written"] == 6
    assert r["clock_plan"]["cycles_per_tick"] == 60e6 / 4000
    rows = {row["baud"]: row for row in sc["link_budget"]["rows"]}
    # 53 bytes a sample (the 50 of five currents and one more current's 3) at 4 kHz, of the
    # line's 300 000 B/s
    assert rows[3_000_000]["real_time"]
    assert rows[3_000_000]["in_load"] == pytest.approx(53 * 4000 / 300_000)
    v = (tmp_path / "b" / "cuneate_ulx3s_core.v").read_text()
    assert "module cuneate_ulx3s_core" in v and "module \\cuneate_ulx3s_core.payload.network.det" in v


def test_the_skin_scene_builds_the_lif_core_behind_the_link(tmp_path, capsys):
    assert main(["build", "ulx3s", "skin_3x3", "--no-bitstream", "--json", "--out",
                 str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["scene"]["kind"] == "lif" and r["neurons"] == 9
    assert [b["block"] for b in r["scene"]["blocks"]] == ["lif_core"]
    assert r["core"]["n_neurons"] == 9 and r["core"]["update_hz"] == 1000
    assert r["clock_plan"]["cycles_per_tick"] == 60_000 and r["pipeline_stages"] is None
    txt = (tmp_path / "cuneate_ulx3s.report.txt").read_text()
    assert "scene blocks: lif_core (9 neurons, sets excitatory)" in txt
    assert "pipeline depth" not in txt.splitlines()[0]
    # a pipeline depth is an Izhikevich core's
    assert main(["build", "ulx3s", "skin_3x3", "--no-bitstream", "--pipeline-stages", "8",
                 "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not of a lif board" in err[0]


def test_the_whole_hand_builds_one_hand_of_channels_fanned_out_on_chip(tmp_path, capsys):
    """``board_trials = 1``: the board holds one grasp's hand, 24 gratings as 48 channels
    (shift and band) fanned out to 192 afferents and the hand's six cuneate neurons; the
    budget counts channels, not currents, and both populations' spikes."""
    assert main(["build", "ulx3s", "whole_hand", "--no-bitstream", "--json", "--out",
                 str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    sc = r["scene"]
    assert sc["kind"] == "fanout" and (sc["trials_on_board"], sc["trials"]) == (1, 12)
    fan, core, layer = sc["blocks"]
    assert fan["block"] == "channel_fanout" and core["block"] == "izhikevich_core"
    assert (fan["n_channels"], fan["n_neurons"], core["neurons"]) == (48, 192, 192)
    assert layer["block"] == "coincidence_detector" and layer["per_trial"] == 6
    assert (layer["neurons"], layer["sources"], layer["synapses"]) == (6, 192, 192)
    assert r["link"]["n_written"] == 48 and r["link"]["fanout"]["clock_hz"] == 60e6
    assert r["link"]["value_width"] == 16 and r["core"]["n_neurons"] == 192
    assert r["neurons"] == r["link"]["n_spike_ids"] == 192 + 6
    # 48 samples of 2 bytes a millisecond in frames, against 192 currents; the spikes of 198
    b = sc["link_budget"]
    assert b["words_per_sample"] == 48 and b["in_bytes_per_s"] == 131_000
    assert b["out_bytes_per_s"] == 135_800
    rows = {row["baud"]: row for row in b["rows"]}
    assert rows[3_000_000]["real_time"] and not rows[115_200]["real_time"]
    # the table is counted in the block RAMs (one core's memories, the link's, the table's,
    # the detector's), the fan-out's 18 x 16-bit product and the detector's six products
    # (three of them wider than 18 bits: two blocks each) beside the core's four multipliers
    assert r["estimate"]["BRAM"] > 8 and r["estimate"]["DSP"] == 4 + 1 + 9
    txt = (tmp_path / "cuneate_ulx3s.report.txt").read_text()
    assert "channel_fanout (48 channels to 192 afferents" in txt
    assert "coincidence_detector (6 neurons, cuneate layer)" in txt
    assert "holds 1 of the scene's 12 trials (hardware.board_trials)" in txt
    assert "every channel every sample" in txt


def test_the_whole_hand_without_board_trials_is_refused_by_the_link(tmp_path, capsys):
    src = tmp_path / "hands.toml"
    src.write_text(example_text("whole_hand").replace("board_trials = 1", ""))
    assert main(["build", "ulx3s", str(src), "--no-bitstream", "--out",
                 str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "the scene's channels take 1,251,000 B/s to the board" in err[0]
    assert "576 channels every sample at 1000 Hz" in err[0]


@pytest.mark.parametrize("edit, reason", [
    (("board_trials = 1", "board_trials = 13"), "some of an afferent scene's trials (1 .. 12)"),
    (("board_trials = 1", "board_trials = 0"), "hardware.board_trials"),
])
def test_board_trials_out_of_range_is_refused(tmp_path, capsys, edit, reason):
    src = tmp_path / "bad.toml"
    src.write_text(example_text("whole_hand").replace(*edit))
    assert main(["build", "ulx3s", str(src), "--no-bitstream", "--out",
                 str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and reason in err[0] and "bad.toml" in err[0], err


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


@pytest.mark.release
def test_the_whole_hand_bitstream_meets_timing(tmp_path, capsys):
    """One hand of the whole-hand scene (48 channels fanned out to 192 afferents, six cuneate
    neurons over them) placed and routed for the ULX3S at 60 MHz (about 3 to 5 min): timing
    met, the block RAMs and the multipliers within the sizing's estimate."""
    assert main(["build", "ulx3s", "whole_hand", "--json", "--out", str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    pr = r["place_route"]
    assert r["bitstream"] and (tmp_path / "cuneate_ulx3s.bit").stat().st_size > 100_000
    assert pr["timing_met"] and pr["min_fmax_mhz"] >= 60, pr
    assert pr["resources"]["BRAM"]["used"] <= r["estimate"]["BRAM"]
    assert 4 + 1 + 6 <= pr["resources"]["DSP"]["used"] <= r["estimate"]["DSP"]
    print("\n" + (tmp_path / "cuneate_ulx3s.report.txt").read_text())


@pytest.mark.parametrize("scene", ["skin_3x3", "ridge4k", "whole_hand"])
def test_a_scenes_board_top_elaborates_for_the_ulx3s(tmp_path, scene):
    """The board top of each kind in the ULX3S platform (amaranth's build files, no tools):
    the PLL, the UART, a LED each for running, overflow and a clamp."""
    from cuneate.boards.build import size_blocks
    from cuneate.boards.scene import scene_request
    from cuneate.boards.targets import TARGETS
    from cuneate.boards.top import BoardTop
    from cuneate.sim.scenes.scene import load_scene, parse_scene
    t = TARGETS["ulx3s"]
    sc = parse_scene(example_text("ridge_angle") + "\n[hardware]\nupdate_hz = 4000\n",
                     "ridge4k.toml") if scene == "ridge4k" else load_scene(example_path(scene))
    sized = size_blocks(t, scene_request(sc, t), None, None)
    plan = t["platform"]().prepare(BoardTop(sized["link"], sized["pll"], True), name="top")
    il, lpf = (plan.files[f"top.{x}"] for x in ("il", "lpf"))
    il, lpf = (f.decode() if isinstance(f, bytes) else f for f in (il, lpf))
    assert "EHXPLLL" in il and "uart_0__rx" in lpf and "uart_0__tx" in lpf
    assert [f"led_{i}__io" in lpf for i in range(4)] == [True, True, True, False]


def test_a_sweep_too_short_for_the_blocks_is_refused():
    """4096 taxels (a 64 x 64 skin, the largest grid) at 20 kHz (the scene's 100 MHz clock
    holds them): without the real-time budget (a lockstep host waits for the line) their LIF
    core still needs 4096
    cycles a sweep, more than a 70 MHz sweep's 3500 (the 90 MHz plan is above the measured
    fmax): refused before any synthesis, naming the figures."""
    from cuneate.boards.build import size_blocks
    from cuneate.boards.scene import scene_request
    from cuneate.boards.targets import TARGETS
    from cuneate.hdl.lib.config import ConfigError
    from cuneate.sim.scenes.scene import parse_scene
    sc = parse_scene(example_text("skin_3x3").replace("grid = [3, 3]", "grid = [64, 64]")
                     .replace("update_hz = 1000", "update_hz = 20000\nclock_hz = 100e6"),
                     "big_skin.toml")
    t = TARGETS["ulx3s"]
    with pytest.raises(ConfigError) as err:
        size_blocks(t, scene_request(sc, t, real_time=False), None, None)
    msg = str(err.value)
    assert "\n" not in msg and "no clock plan holds the scene's lif_core" in msg
    assert "a sweep of 3500 cycles cannot hold the lif_core's 4096 cycles of work and the " \
           "link's 16 idle ones" in msg and "(fmax limit)" in msg
