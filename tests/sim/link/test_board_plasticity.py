"""The ``board`` engine of the learning layer: its payload behind the UART link
(:class:`~cuneate.hdl.link.LinkedTop`) compiled by Verilator behind a simulated serial line,
driven by the host stack. The layer learns on chip from the afferent spikes streamed as
writes; its CN spikes and the weights read back in the readout sweeps (after each presentation
and after the last) equal the fixed engine's (the layer's twin), with every counter of the
transport contract clean."""

import numpy as np
import pytest

from cuneate.hdl.plasticity import PlasticityConfig
from cuneate.hdl.plasticity.payload import (LearningSpec, readout_bytes, readout_ids,
                                            readout_parts, write_addresses)
from cuneate.sim.engines.registry import engine_for
from cuneate.sim.link.engines import board_link
from cuneate.sim.plasticity.engines import face_schedule, run_learning
from learning_case import small_layer

FIELDS = ("spike_pres", "spike_tick", "spike_cn", "counts")


def test_the_board_link_of_the_layer_carries_its_writes_and_a_readout_sweep():
    cfg, pres = small_layer()
    lc = board_link(cfg)
    S, M, K = cfg.n_sources, cfg.n_targets, cfg.n_synapses
    assert lc.n_written == S + M * K + 1 + M and lc.current_width == cfg.W.width
    # a readout sweep's spikes fit a batch; a sweep holds the layer's work and the link's
    assert len(readout_ids(cfg, cfg.weights_raw[0])) <= lc.batch_capacity
    assert lc.info.cycles_per_tick >= lc.info.busy_cycles + 16
    assert lc.payload.config.to_kwargs() | {"clock_hz": 0} == cfg.to_kwargs() | {"clock_hz": 0}
    plan = face_schedule(cfg, pres, np.ones(pres.n, bool))
    assert plan.n_sweeps == pres.n * pres.n_ticks + M
    # a snapshot after each presentation: M readout sweeps after each, the ticks go on
    plan = face_schedule(cfg, pres, np.ones(pres.n, bool), snapshot_every=1)
    T = pres.n_ticks
    assert plan.readouts == [1, 2] and plan.n_sweeps == 2 * (T + M)
    assert plan.tick_of_sweep.tolist() == list(range(T)) + [-1] * M + \
        list(range(T, 2 * T)) + [-2] * M
    readout = write_addresses(cfg)["readout"][0]
    assert [first for first, _ in plan.writes[T]] == [readout - 1, readout]


def test_the_board_engine_splits_a_readout_to_fit_a_spike_batch():
    """The example's layer (16 CNs of 20 synapses, 2 kHz: two sweeps a batch): readout
    sweeps of 15 synapses, two per CN; a batch of readout sweeps, or of a tick's CN spikes
    and a readout sweep, fits the batch."""
    rng = np.random.default_rng(3)
    cfg = PlasticityConfig(n_sources=80, sources=np.array(
        [np.sort(rng.choice(80, 20, replace=False)) for _ in range(16)]))
    R = engine_for("plasticity", "board").readout_synapses(cfg)
    lc = board_link(LearningSpec(cfg, R))
    spikes = R * readout_bytes(cfg)
    assert R == 15 and readout_parts(cfg, R) == 2 and lc.batch_sweeps == 2
    assert lc.payload.readout_synapses == R          # kept through the link's retiming
    assert lc.batch_sweeps * spikes <= lc.batch_capacity
    assert spikes + cfg.n_targets <= lc.batch_capacity


@pytest.mark.long
def test_the_layer_learns_on_the_board_engine_as_the_twin():
    cfg, pres = small_layer()
    flags = [True, True]
    board, fixed = (run_learning(e, cfg, pres, flags, snapshot_every=1)
                    for e in ("board", "fixed"))
    assert fixed.spike_cn.size > 0 and not np.array_equal(fixed.weights_raw, cfg.weights_raw)
    assert np.array_equal(board.weights_raw, fixed.weights_raw)
    for k in FIELDS:
        assert np.array_equal(getattr(board, k), getattr(fixed, k)), k
    assert [n for n, _ in board.snapshots] == [n for n, _ in fixed.snapshots] == [0, 1]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(board.snapshots, fixed.snapshots))
    c = board.extra["counters"]
    assert c["device_spikes_dropped"] == 0 and c["device_seq_gaps"] == 0
    assert c["spikes"] == fixed.spike_cn.size + 2 * cfg.n_targets * len(
        readout_ids(cfg, cfg.weights_raw[0]))
