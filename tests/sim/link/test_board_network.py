"""The ``board`` engine of the on-chip afferent -> cuneate network: the network behind the UART
link (:class:`~cuneate.hdl.link.LinkedTop`) compiled by Verilator behind a simulated serial
line, driven by the host stack. Both populations' spikes equal the fixed engine's (the
network's twin), every spike frame carries exactly the spikes of its own sweeps, and the
ridge-angle scene runs on it."""

import numpy as np
import pytest

from cuneate.hdl.izhikevich import ConfigError
from cuneate.hdl.link import LinkConfig
from cuneate.hdl.link.codec import MAX_FRAME, parse_spikes
from cuneate.hdl.network import REPORT_SETTLE
from cuneate.sim.coincidence.experiments import RidgeSpec, afferent_currents, network_config
from cuneate.sim.host.transport import COUNTERS
from cuneate.sim.link.engines import board_link
from cuneate.sim.network.engines import current_runs, current_writes, run_network
from host_stream import board_spike_frames

SPEC = RidgeSpec(trials_per_angle=1)
NETWORK = network_config(SPEC)


def ridge_currents() -> np.ndarray:
    """The three ridge trials of SPEC (one an angle), afferent currents (ticks, 5)."""
    cur, _, _ = afferent_currents(SPEC)
    pad = np.zeros((cur.shape[0], NETWORK.n_afferents))
    pad[:, :4] = cur
    return pad


def test_the_board_network_link_carries_both_populations_and_one_batch_a_millisecond():
    lc = board_link(NETWORK)
    net = lc.payload.config
    N, M = NETWORK.n_afferents, NETWORK.n_targets
    # the host writes the afferents; spikes carry afferent and cuneate ids
    assert lc.n_neurons == N and lc.n_spike_ids == N + M
    assert lc.batch_sweeps == 16 and lc.core.to_kwargs() == net.core.to_kwargs()
    # a tick's work, the report's settling and one spike per neuron fit with a board's idle
    # cycles; the largest frame leaves within a batch
    assert net.cycles_per_tick >= net.cycles_needed + REPORT_SETTLE + N + M + 16
    assert lc.batch_sweeps * net.cycles_per_tick >= (MAX_FRAME + 2) * 10 * lc.clocks_per_bit
    # the arithmetic is the scene's network's
    same = {"clock_hz": 0, "tick_source": "external"}
    assert net.to_kwargs() | same == NETWORK.to_kwargs() | same


def test_a_network_link_carries_the_ids_of_both_populations():
    lc = board_link(NETWORK)
    N, M = NETWORK.n_afferents, NETWORK.n_targets
    assert lc.info.populations == (("afferent", 0, N), ("cuneate", N, M))
    # the afferent core alone behind a link carries the afferents' ids only
    assert LinkConfig(lc.payload.config.core, batch_sweeps=16).n_spike_ids == N


def test_board_network_equals_fixed_for_both_populations():
    cur = ridge_currents()
    ref = run_network("fixed", NETWORK, cur)
    got = run_network("board", NETWORK, cur)
    for pop in ("afferent", "cuneate"):
        a, b = ref.population(pop), got.population(pop)
        assert len(a) == len(b)
        assert all(np.array_equal(x, y) for x, y in zip(a, b)), pop
    # every cuneate neuron and every afferent of a sensor fires (the comparison is not empty)
    assert all(len(x) > 0 for x in ref.population("cuneate"))
    assert all(len(x) > 0 for x in ref.population("afferent")[:4])
    c = got.counters
    n_spikes = sum(len(x) for x in ref.spikes_ms)
    assert {k: c[k] for k in COUNTERS} == {
        "writes": sum(len(current_runs(w)) for w in current_writes(NETWORK, cur).values()),
        "spikes": n_spikes, "spikes_counted": n_spikes, "frames_lost": 0, "overflow": 0,
        "overrun": 0, "late_writes": 0}
    assert c["board_framing_errors"] == 0


def test_every_spike_frame_carries_exactly_its_own_sweeps_spikes():
    """Cuneate spikes leave the detector after the core's sweep is done: the network's tick
    report (``tick_done``) keeps the link's batch open until they are in it. (Reporting at the
    core's sweep end instead loses the cuneate spikes of a step's last sweep: this test and the
    one above fail.)"""
    cur = ridge_currents()
    n = cur.shape[0]
    N = NETWORK.n_afferents
    ref = run_network("fixed", NETWORK, cur)
    want = {(int(round(t / ref.dt_ms)) - 1, i) for i, s in enumerate(ref.spikes_ms) for t in s}
    runs = {k: current_runs(w) for k, w in current_writes(NETWORK, cur).items()}
    frames = board_spike_frames(NETWORK, runs, n)
    covered, got, at_batch_end = 0, set(), 0
    for m in frames:
        dropped, sweeps, spikes = parse_spikes(m)
        assert dropped == 0 and m.tick == covered
        # the spikes of exactly this frame's sweeps, as the twin has them
        assert {(t, i) for t, i in spikes} == {(t, i) for t, i in want
                                               if m.tick <= t < m.tick + sweeps}
        at_batch_end += sum(1 for t, i in spikes if i >= N and t == m.tick + sweeps - 1)
        got |= {(t, i) for t, i in spikes}
        covered += sweeps
    assert covered == n and got == want
    # the case at risk: cuneate spikes in their batch's last sweep
    assert at_batch_end > 0


@pytest.mark.long
def test_every_spike_train_of_the_ridge_scene_on_board_equals_fixed():
    """The ridge-angle scene's network (18 trials, 34560 ticks), every train of both
    populations: about 40 s on the board."""
    from cuneate.sim.scenes.ridge import spec_of
    from cuneate.sim.scenes.scene import example_path, load_scene
    spec = spec_of(load_scene(example_path("ridge_angle")))
    net = network_config(spec)
    cur, _, _ = afferent_currents(spec)
    pad = np.zeros((cur.shape[0], net.n_afferents))
    pad[:, :4] = cur
    ref = run_network("fixed", net, pad)
    got = run_network("board", net, pad)
    assert all(np.array_equal(x, y) for x, y in zip(ref.spikes_ms, got.spikes_ms))
    assert len(ref.spikes_ms) == len(got.spikes_ms) == net.n_afferents + net.n_targets
    assert all(len(x) > 0 for x in ref.population("cuneate"))


@pytest.mark.long
def test_ridge_scene_on_board_equals_fixed(tmp_path):
    """The whole ridge-angle scene (18 trials, 34560 ticks): about a minute on the board."""
    from cuneate.sim.scenes.ridge import same_counts
    from cuneate.sim.scenes.runner import run_scene
    from cuneate.sim.scenes.scene import example_path, load_scene
    run = run_scene(load_scene(example_path("ridge_angle")), ["fixed", "board"])
    f, b = run.results["fixed"], run.results["board"]
    assert b.patterns == f.patterns and b.decoded == f.decoded and f.accuracy == 1.0
    assert same_counts(b, f) == {"cuneate": True, "afferent": True}
    assert int(f.counts.sum()) > 0 and int(f.afferent_counts.sum()) > 0
    # the link's counters reach the run's report and its lines
    from cuneate.sim.scenes.ridge import format_run, summary
    c = b.counters
    assert c["frames_lost"] == 0 and c["board_frames_to_device"] > 0 \
        and c["board_frames_from_device"] > 0 and c["board_cycles"] > 0
    assert summary(run)["engines"]["board"]["counters"]["board_frames_to_device"] == \
        c["board_frames_to_device"]
    assert f"{c['board_frames_to_device']} frames" in format_run(run) and "0 lost" in \
        format_run(run)
