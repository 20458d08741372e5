"""IzhikevichArray in the Amaranth simulator: every update of every core equals its twin's
(from the core's own previous state and the current it reports), host writes by global id
reach the right core, and the spike stream carries every spike once as a global id with its
sweep, each core's spikes in that core's order."""

import numpy as np
import pytest
from current_writes import RandomWrites

from cuneate.hdl.izhikevich import (ConfigError, IzhikevichArray, IzhikevichArrayTwin,
                                    IzhikevichConfig)
from cuneate.hdl.izhikevich.config import PIPELINE_STAGES
from cuneate.sim.engines.amaranth import simulate


def _run(arr, n_sweeps, rng, lo=-5.0, hi=150.0, writes_per_sweep=3):
    cfg, K = arr.cfg, arr.n_cores
    N, total = cfg.n_neurons, arr.n_total
    rec = {"ups": [[] for _ in range(K)], "stream": [], "done": [], "writes": []}

    async def bench(ctx):
        ctx.set(arr.spike_ready, 1)
        writes = RandomWrites(cfg, rng, total, lo, hi, writes_per_sweep / N)
        for _ in range((n_sweeps + 1) * cfg.cycles_per_tick):
            w = writes.next()
            ctx.set(arr.i_wr_en, int(w is not None))
            if w is not None:
                ctx.set(arr.i_wr_addr, w[0])
                ctx.set(arr.i_wr_data, w[1])
                rec["writes"].append(w)
            await ctx.tick()
            for k, core in enumerate(arr.cores):
                if ctx.get(core.upd_valid):
                    rec["ups"][k].append((ctx.get(core.upd_index), ctx.get(core.upd_v),
                                          ctx.get(core.upd_u), ctx.get(core.upd_current),
                                          ctx.get(core.upd_spike)))
            if ctx.get(arr.spike_valid):
                rec["stream"].append((ctx.get(arr.spike_index), ctx.get(arr.spike_sweep)))
            if ctx.get(arr.sweep_done):
                rec["done"].append((ctx.get(arr.sweep_number), ctx.get(arr.sweep_count)))
        rec["overrun"] = ctx.get(arr.overrun)
        rec["overflow"] = ctx.get(arr.spike_overflow)

    simulate(arr, bench)
    return rec


#: per global id: core 0 all RS, core 1 all FS, core 2 the four sets in turn
PER_CORE_SETS = [0] * 12 + [3] * 12 + [i % 4 for i in range(12)]


@pytest.mark.parametrize("depth, sets", [(5, None), (max(PIPELINE_STAGES), None),
                                         (5, PER_CORE_SETS)],
                         ids=["depth5", "deepest", "depth5-per-core-sets"])
def test_array_matches_its_twins_every_update(depth, sets):
    K, N = 3, 12
    cfg = IzhikevichConfig(n_neurons=N, clock_hz=16e3 * 16, param_sets=("RS", "IB", "CH", "FS"),
                           neuron_sets=[i % 4 for i in range(N)], spike_fifo_depth=64,
                           pipeline_stages=depth)
    arr = IzhikevichArray(cfg, K, neuron_sets=sets)
    rec = _run(arr, 80, np.random.default_rng(depth))
    twin = IzhikevichArrayTwin(cfg, K, kernel="stages", neuron_sets=sets)
    if sets is not None:
        # each core starts its neurons with their own sets (the RTL's set memories, checked
        # below update by update against twins built with the same sets)
        assert [list(c.cfg.neuron_sets) for c in arr.cores] == \
            [sets[k * N:(k + 1) * N] for k in range(K)]
        assert [list(t.cfg.neuron_sets) for t in twin.twins] == \
            [sets[k * N:(k + 1) * N] for k in range(K)]
    n_full = min(min(len(u) for u in rec["ups"]) // N, len(rec["done"]))
    assert n_full >= 79
    written = {n: {0} for n in range(K * N)}          # the current RAM starts at zero
    for n, raw in rec["writes"]:
        written[n].add(raw)
    spikes_by_sweep = []
    for s in range(n_full):
        spk_all = []
        for k in range(K):
            ups = np.array(rec["ups"][k][s * N:(s + 1) * N], dtype=np.int64)
            assert np.all(ups[:, 0] == np.arange(N))
            t = twin.twins[k]
            # each core used a current the host wrote to that global id
            assert all(int(c) in written[k * N + i] for i, c in enumerate(ups[:, 3]))
            t.I[:] = ups[:, 3]
            spk = t.sweep()
            np.testing.assert_array_equal(t.v, ups[:, 1], err_msg=f"core {k} sweep {s} v")
            np.testing.assert_array_equal(t.u, ups[:, 2], err_msg=f"core {k} sweep {s} u")
            np.testing.assert_array_equal(spk, ups[:, 4].astype(bool))
            spk_all.append(spk)
        spikes = np.concatenate(spk_all)
        assert rec["done"][s] == (s, int(spikes.sum()))
        spikes_by_sweep += [(int(n), s) for n in np.flatnonzero(spikes)]
    assert len(spikes_by_sweep) > 30
    stream = rec["stream"][:len(spikes_by_sweep)]
    # every spike once, tagged with its sweep; each core's spikes in that core's order
    assert sorted(stream, key=lambda x: (x[1], x[0])) == spikes_by_sweep
    for k in range(K):
        assert [x for x in stream if x[0] // N == k] == \
            [x for x in spikes_by_sweep if x[0] // N == k]
    assert rec["overrun"] == 0 and rec["overflow"] == 0


def test_array_refuses_a_core_count_it_cannot_build():
    cfg = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8)
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ConfigError, match="n_cores"):
            IzhikevichArray(cfg, bad)


@pytest.mark.parametrize("sets, match", [([0] * 15, "one set per neuron of the array"),
                                         ([0] * 15 + [2], "set indices 0..1"),
                                         ([0] * 15 + [True], "set indices 0..1")])
def test_array_refuses_sets_it_cannot_hold(sets, match):
    cfg = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, param_sets=("RS", "FS"))
    with pytest.raises(ConfigError, match=match):
        IzhikevichArray(cfg, 2, neuron_sets=sets)
    with pytest.raises(ConfigError, match=match):
        IzhikevichArrayTwin(cfg, 2, neuron_sets=sets)


def test_an_array_with_one_table_of_sets_everywhere_builds_one_configuration():
    """Sets equal in every core (or none given): every core is built from the configuration
    itself (one set of formats and one elaboration path)."""
    from cuneate.hdl.izhikevich.array import core_configs
    cfg = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, param_sets=("RS", "FS"),
                           neuron_sets=[0, 1] * 4)
    assert all(c is cfg for c in core_configs(cfg, 3))
    assert all(c is cfg for c in core_configs(cfg, 3, [0, 1] * 12))
    per = core_configs(cfg, 2, [1] * 8 + [0] * 8)
    assert [list(c.neuron_sets) for c in per] == [[1] * 8, [0] * 8]
    assert all((c.V, c.U) == (cfg.V, cfg.U) for c in per)
