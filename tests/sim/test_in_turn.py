"""Trials in turn (:mod:`cuneate.sim.scenes.in_turn`): a board holding some of a scene's trials
plays them group after group; the first group starts from the reset state as the side-by-side
run does, and every spike of a group's window returns to its own trial."""

import json

import numpy as np
import pytest

from cuneate.sim.scenes import afferent, parse_scene
from cuneate.sim.scenes.in_turn import InTurn
from layered_scene import layered_text


def test_fold_and_unfold_put_each_trial_in_its_window_and_back():
    turn = InTurn(k=2, n_trials=3, n_ticks=10, dt_ms=0.5, per_trial=1)
    x = np.arange(3 * 4).reshape(4, 3) + 1          # 4 samples, one column a trial
    f = turn.fold(x, 1)
    assert f.shape == (8, 2)
    assert f[:4].tolist() == x[:, :2].tolist()      # group 0: trials 0 and 1
    assert f[4:, 0].tolist() == x[:, 2].tolist() and not f[4:, 1].any()   # trial 2, idle
    # sweep T fires at (T + 1) dt: trial 2's sweep 3 is the board's sweep 13 of neuron 0
    board = [np.array([1.0, 5.0, 7.0]), np.array([2.0, 5.5])]
    got = turn.unfold(board)
    assert [g.tolist() for g in got] == [[1.0, 5.0], [2.0], [2.0]]


def test_in_turn_the_first_group_equals_the_side_by_side_run_and_state_carries_on():
    scene = parse_scene(layered_text(duration_ms=150, trials=2), "slide_layer.toml")
    side = afferent.run(scene, ["golden", "fixed"])
    turn = afferent.run(scene, ["golden", "fixed"], in_turn=2)
    assert turn.ran["in_turn"] == {"trials_at_a_time": 2, "groups": 3, "ticks_a_group": 2400,
                                   "ticks": 7200}
    per = len(side.neurons) // 6
    for e in ("golden", "fixed"):
        a, b = side.spikes[e], turn.spikes[e]
        assert len(a) == len(b) == 6 * per
        assert all(np.array_equal(x, y) for x, y in zip(a[:2 * per], b[:2 * per]))
        assert all(len(x) == 0 or 0 < x.min() and x.max() <= 150 for x in b)
        # later groups start from the state the last left: their trains differ
        assert not all(np.array_equal(x, y) for x, y in zip(a[2 * per:], b[2 * per:]))
        la, lb = side.layer["spikes"][e], turn.layer["spikes"][e]
        assert all(np.array_equal(x, y) for x, y in zip(la[:4], lb[:4]))
    assert turn.agreement["golden vs fixed"]["neurons"] == 6 * per
    assert "trials in turn: 2 at a time" in afferent.format_run(turn)


def test_cuneate_run_in_turn_plays_the_scene_as_its_board_does(tmp_path, capsys):
    from cuneate.sim import cli
    p = tmp_path / "turn.toml"
    p.write_text(layered_text(duration_ms=100, trials=1).replace(
        "[hardware]", "[hardware]\nboard_trials = 2"))
    assert cli.main(["run", str(p), "--in-turn", "--json", "-q", "--out",
                     str(tmp_path / "o")]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["ran"]["in_turn"] == {"trials_at_a_time": 2, "groups": 2,
                                         "ticks_a_group": 1600, "ticks": 3200}
    assert summary["agreement"]["golden vs fixed"]["neurons"] == 3 * 2 * 2
    # a scene that names no board_trials has no board to play in turn
    q = tmp_path / "side.toml"
    q.write_text(layered_text(duration_ms=100, trials=1))
    assert cli.main(["run", str(q), "--in-turn", "-q", "--out", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"cuneate run: --in-turn: {q} names no hardware.board_trials (the trials a "
                   f"board holds at a time)"]


def test_in_turn_with_a_front_end_latency_is_refused():
    """A latency would carry a group's last samples into the next group's trials."""
    text = layered_text(duration_ms=100, trials=1).replace("[frontend]",
                                                           "[frontend]\nlatency_ticks = 3")
    with pytest.raises(ValueError, match=r"^frontend.latency_ticks = 3: in turn, a group's last "
                                         r"samples would drive the next group's trials"):
        afferent.run(parse_scene(text, "late.toml"), ["fixed"], in_turn=1)
