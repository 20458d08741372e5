"""The ``board`` engine of the LIF block: a LIF core behind the UART link
(:class:`~cuneate.hdl.link.LinkedTop`) compiled by Verilator behind a simulated serial line,
driven by the host stack. Its spikes equal the fixed engine's (the twin's), every counter of the
transport's contract holds, every spike frame carries exactly the spikes of its own sweeps, and
the shipped 3x3 skin scene runs on it with the same spike trains as on ``fixed``."""

import json

import numpy as np
import pytest

from cuneate.hdl.lif import ConfigError, LifConfig
from cuneate.hdl.link import LinkConfig
from cuneate.hdl.link.codec import MAX_FRAME, parse_spikes
from cuneate.sim.host.transport import COUNTERS
from cuneate.sim.lif.engines import LifProgram, current_runs, engine_config, run_lif
from cuneate.sim.link.engines import board_link
from host_stream import board_spike_frames

# nine neurons at 1 kHz as the skin runs them, in two parameter sets (the brief's excitatory
# and inhibitory cells: refractory periods of 2 and 1 ticks)
CORE = engine_config({"update_hz": 1000.0,
                      "param_sets": [{"tau_m_ms": 20.0, "t_ref_ms": 2.0},
                                     {"tau_m_ms": 10.0, "t_ref_ms": 1.0}],
                      "neuron_sets": [0, 1, 0, 1, 0, 1, 0, 1, 0]}, 9)
SEGMENT = 20                      # ticks between current changes
#: the neurons whose currents change at each segment after the first, and the consecutive
#: runs (one link write each) they make
GROUPS = [((4,), 1), ((2, 3, 4), 1), ((0, 8), 2), ((1, 3, 5, 7), 4)]


def program(n_segments: int = 15, seed: int = 3) -> tuple[np.ndarray, int]:
    """Currents (ticks, 9) in mV: all nine set at tick 0, then every SEGMENT ticks one group of
    GROUPS changes (to a value whose raw differs); and the link writes that takes."""
    rng = np.random.default_rng(seed)
    cur = np.zeros((n_segments * SEGMENT, 9))
    row = rng.uniform(0.0, 60.0, 9)
    writes = 1
    for j in range(n_segments):
        if j:
            group, runs = GROUPS[(j - 1) % len(GROUPS)]
            for i in group:
                new = row[i]
                while CORE.I.to_raw(new) == CORE.I.to_raw(row[i]):
                    new = rng.uniform(0.0, 60.0)
                row[i] = new
            writes += runs
        cur[j * SEGMENT:(j + 1) * SEGMENT] = row
    return cur, writes


def test_current_runs_writes_what_changes_as_consecutive_runs():
    raw = np.array([[1, 2, 3, 4], [1, 2, 3, 4], [5, 2, 7, 8], [5, 2, 7, 8], [0, 0, 7, 8]])
    got = {k: [(f, v.tolist()) for f, v in runs] for k, runs in current_runs(raw).items()}
    assert got == {0: [(0, [1, 2, 3, 4])], 2: [(0, [5]), (2, [7, 8])], 4: [(0, [0, 0])]}


def test_the_board_lif_link_keeps_a_boards_idle_cycles_and_one_batch_a_millisecond():
    lc = board_link(CORE)
    assert isinstance(lc.core, LifConfig) and lc.core.tick_source == "external"
    assert lc.batch_sweeps == 1 and lc.clocks_per_bit == 4
    assert lc.n_neurons == lc.n_spike_ids == 9 and lc.current_width == CORE.I.width == 16
    assert lc.core.cycles_per_tick >= 9 + 16
    # the largest frame (and its delimiters) leaves within a batch's sweeps on the line
    assert lc.batch_sweeps * lc.core.cycles_per_tick >= (MAX_FRAME + 2) * 10 * lc.clocks_per_bit
    # the arithmetic is the core's: the clock alone differs
    same = {"clock_hz": 0.0}
    assert lc.core.to_kwargs(**same) == CORE.to_kwargs(**same)


def test_a_lif_link_refuses_what_a_lif_payload_cannot_be():
    lc = board_link(CORE)
    assert lc.info.block == "lif_core" and lc.info.populations == (("neurons", 0, 9),)
    weighted = engine_config({"update_hz": 1000.0, "weights": np.full((9, 2), 0.5)}, 9)
    with pytest.raises(ConfigError, match="no input spikes.*not 2 inputs"):
        LinkConfig(weighted)
    with pytest.raises(ConfigError, match="a LifConfig behind a face takes no n_cores"):
        LinkConfig(lc.core, n_cores=2)
    internal = LifConfig.from_kwargs(CORE.to_kwargs(tick_source="internal"))
    with pytest.raises(ConfigError, match="tick_source='external'"):
        LinkConfig(internal)


def test_board_lif_equals_fixed_with_every_counter_checked():
    cur, n_writes = program()
    ref = run_lif("fixed", CORE, LifProgram(cur))
    got = run_lif("board", CORE, LifProgram(cur))
    assert len(got.spikes_ms) == len(ref.spikes_ms) == 9
    assert all(np.array_equal(a, b) for a, b in zip(ref.spikes_ms, got.spikes_ms))
    n_spikes = sum(len(s) for s in ref.spikes_ms)
    # both parameter sets fire, most neurons several times (the comparison is not empty)
    assert n_spikes > 100 and sum(1 for s in ref.spikes_ms if len(s) > 3) >= 6
    c = got.counters
    assert {k: c[k] for k in COUNTERS} == {
        "writes": n_writes, "spikes": n_spikes, "spikes_counted": n_spikes, "frames_lost": 0,
        "overflow": 0, "overrun": 0, "late_writes": 0}
    assert c["board_framing_errors"] == 0 and c["board_frames_from_device"] >= cur.shape[0]
    assert c["board_cycles"] >= cur.shape[0] * board_link(CORE).core.cycles_per_tick


@pytest.mark.parametrize("ahead", [True, False], ids=["writes-ahead", "lockstep"])
def test_every_spike_frame_carries_exactly_its_own_sweeps_spikes(ahead):
    """Both host modes: writes sent ahead (held by the device until their sweep) and lockstep
    (sent once the device stands at their sweep)."""
    cur, _ = program(n_segments=6, seed=7)
    n = cur.shape[0]
    ref = run_lif("fixed", CORE, LifProgram(cur))
    want = {(int(round(t / ref.dt_ms)) - 1, i) for i, s in enumerate(ref.spikes_ms) for t in s}
    frames = board_spike_frames(CORE, current_runs(np.asarray(CORE.I.to_raw(cur), np.int64)), n,
                                ahead=ahead)
    covered, got = 0, set()
    for m in frames:
        dropped, sweeps, spikes = parse_spikes(m)
        assert dropped == 0 and m.tick == covered
        assert {(t, i) for t, i in spikes} == {(t, i) for t, i in want
                                               if m.tick <= t < m.tick + sweeps}
        got |= {(t, i) for t, i in spikes}
        covered += sweeps
    assert covered == n and got == want and len(want) > 30


@pytest.mark.long
def test_cli_runs_the_skin_example_on_board_with_the_fixed_engines_spikes(tmp_path, capsys):
    from cuneate.sim.cli import main
    out = tmp_path / "skin"
    assert main(["run", "examples/skin_3x3", "--engines", "fixed,board", "-q", "--out",
                 str(out)]) == 0
    text = capsys.readouterr().out
    assert "board vs fixed: 9/9 identical trains, mean |spike count diff| 0.00" in text
    assert "board link:" in text and ", 0 lost;" in text
    summ = json.loads((out / "run.json").read_text())
    f, b = summ["engines"]["fixed"], summ["engines"]["board"]
    assert b["spikes_ms"] == f["spikes_ms"] and sum(map(len, f["spikes_ms"])) > 20
    assert b["counts"] == f["counts"] and summ["decoded"]["board"] == {"winner": 4,
                                                                        "correct": True}
    assert b["width_monotonic"] and b["amplitude_monotonic"]
    c = b["counters"]
    assert c["frames_lost"] == 0 and c["spikes"] == sum(map(len, f["spikes_ms"]))
    assert c["board_framing_errors"] == 0 and c["board_cycles_per_s"] > 0
    assert "board link:" in (out / "index.html").read_text()


@pytest.mark.long
def test_a_discrete_shift_decay_core_on_board_equals_fixed():
    """A discrete-form core with shift decay, 24 neurons at 16 kHz (16 sweeps a batch), 4000
    ticks of currents changing every 50: about 20 s with the board top's build."""
    cfg = engine_config({"update_hz": 16e3, "form": "discrete", "decay": "shift",
                         "param_sets": [{"alpha": 0.875, "u_th": 1.0, "u_rest": 0.0,
                                         "refractory_steps": 3}]}, 24)
    rng = np.random.default_rng(11)
    cur = np.repeat(rng.uniform(-0.05, 0.35, (80, 24)), 50, axis=0)
    ref = run_lif("fixed", cfg, LifProgram(cur))
    got = run_lif("board", cfg, LifProgram(cur))
    assert all(np.array_equal(a, b) for a, b in zip(ref.spikes_ms, got.spikes_ms))
    assert sum(len(s) for s in ref.spikes_ms) > 1000
    assert got.counters["spikes"] == sum(len(s) for s in ref.spikes_ms)
    assert got.counters["frames_lost"] == 0 and board_link(cfg).batch_sweeps == 16
