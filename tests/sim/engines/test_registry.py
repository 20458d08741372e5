"""Every registered engine against every block it claims: a tiny input each, through the
block's public entry point, equal to the block's twin (``fixed``) spike for spike (and clamp
for clamp where the engine sees clamps), golden within a spike of it. The pairs come from the
registry, so a new engine is checked for every block it registers for; engines that run in a
simulator process of their own (``background``) are in the long lane. The channel fan-out
runs alone (``fanout``: its currents) and in front of a core (``fanout_front``: the core's
spikes, the design the board's fan-out test compiles)."""

import numpy as np
import pytest

from cuneate.sim.engines.registry import ENGINES, BLOCKS, block_engines, engine_for, \
    implementation
from cuneate.sim.engines.engine import BlockEngine

# the small designs other tests compile too (the Verilator cache keys on the Verilog's bytes)
IZH_CORE, IZH_CURRENTS = {"n_neurons": 8}, [4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 28.0, 32.0]
LIF_CORE = {"update_hz": 1000.0, "param_sets": [{"tau_m_ms": 20.0, "t_ref_ms": 2.0},
                                                {"tau_m_ms": 10.0, "t_ref_ms": 1.0}],
            "neuron_sets": [0, 1, 0, 1, 0, 1, 0, 1, 0]}


def _izhikevich(engine, build_dir):
    from cuneate.sim.izhikevich.engines import run_engine
    return run_engine(engine, IZH_CORE, IZH_CURRENTS, 20.0, build_dir=build_dir)


def _lif(engine, build_dir):
    from cuneate.sim.lif.engines import LifProgram, engine_config, run_lif
    cfg = engine_config(LIF_CORE, 9)
    cur = np.random.default_rng(3).uniform(0.0, 60.0, 9)
    return run_lif(engine, cfg, LifProgram.constant(cur, 60), build_dir=build_dir)


def _coincidence(engine, build_dir):
    from cuneate.hdl.coincidence import CoincidenceConfig
    from cuneate.sim.coincidence.engines import run_coincidence
    cfg = CoincidenceConfig(n_sources=2, n_targets=2, delays_ticks=[[0, 16], [16, 0]],
                            max_delay_ticks=32)
    rng = np.random.default_rng(4)
    ins = [np.sort(rng.choice(200, 15, replace=False)) for _ in range(2)]
    ins[1] = np.unique(np.concatenate([ins[1], ins[0][:8] + 16]))
    return run_coincidence(engine, cfg, [ins[0], ins[1][ins[1] < 200]], 200,
                           build_dir=build_dir)


def _network(engine, build_dir):
    from cuneate.sim.coincidence.experiments import RidgeSpec, network_config
    from cuneate.sim.network.engines import run_network
    net = network_config(RidgeSpec(trials_per_angle=1))
    cur = np.zeros((120, net.n_afferents))
    cur[:, :4] = [12.0, 18.0, 24.0, 30.0]
    return run_network(engine, net, cur, build_dir=build_dir)


def _fanout_table():
    from cuneate.hdl.fanout import FanoutConfig
    cfg = FanoutConfig(n_channels=2, channel=[0, 1, 0, 1], gain=[1.5, -2.0, 40.0, 3.0],
                       rectify=["none", "positive", "abs", "none"],
                       threshold=[None, None, None, 2.0], sample_width=12, sample_max=16.0)
    x = np.random.default_rng(1).uniform(-20, 20, (6, 2))           # some saturate
    return cfg, x


def _fanout(engine, build_dir):
    from cuneate.sim.fanout.engines import run_fanout
    cfg, x = _fanout_table()
    if engine == "golden":                      # the samples as the host saturates them
        x = np.clip(x, cfg.S.min_value, cfg.S.max_value)
    return run_fanout(engine, cfg, x, build_dir=build_dir)


def _fanout_front(engine, build_dir):
    from host_stream import FANOUT, FANOUT_CORE, FANOUT_EVERY, fanout_samples
    from cuneate.sim.fanout.engines import run_front
    raw = fanout_samples(40)
    writes = {k * FANOUT_EVERY: [(0, row)] for k, row in enumerate(raw)}
    return run_front(engine, FANOUT, FANOUT_CORE, writes, len(raw) * FANOUT_EVERY,
                     build_dir=build_dir)


def _nir(engine, build_dir):
    from cuneate.sim.nir.crosscheck import crosscheck_graph
    from cuneate.sim.nir.engines import run_network
    from cuneate.sim.nir.graph import layers_of
    from cuneate.sim.nir.mapping import map_graph
    mapped = map_graph(layers_of(crosscheck_graph(n_in=6, n_hidden=10, n_out=4)),
                       scheme="euler")
    x = (np.random.default_rng(2).random((40, 6)) < 0.3).astype(float)
    return run_network(engine, mapped, x, build_dir=build_dir)


#: Block -> its tiny run through its public entry point.
RUNS = {"izhikevich": _izhikevich, "lif": _lif, "coincidence": _coincidence,
        "network": _network, "fanout": _fanout, "fanout_front": _fanout_front, "nir": _nir}
_REFERENCE: dict = {}


def _pairs():
    out = []
    for block in RUNS:
        for e in block_engines(block):
            marks = [pytest.mark.long] if ENGINES[e].background else []
            out.append(pytest.param(block, e, marks=marks, id=f"{block}-{e}"))
    return out


def test_every_block_with_engines_has_a_tiny_run():
    block_engines("izhikevich")                  # every implementation loaded
    # the plasticity block's engines run presentation protocols into their own record
    # (LearningRun): tests/hdl/test_plasticity.py holds each against the twin
    assert set(BLOCKS) == set(RUNS) | {"plasticity"}
    for block, decl in BLOCKS.items():
        assert decl.engines == tuple(e for e in ENGINES if e in decl.engines)
        for e in decl.engines:
            impl = engine_for(block, e)
            assert isinstance(impl, BlockEngine) and impl.block == block and impl.name == e
            assert implementation(block, e) is type(impl)


@pytest.mark.parametrize("block,engine", _pairs())
def test_engine_runs_its_block_as_the_twin_does(block, engine, build_root):
    if block not in _REFERENCE:
        _REFERENCE[block] = RUNS[block]("fixed", None)
    ref = _REFERENCE[block]
    got = RUNS[block](engine, build_root / f"registry_{block}_{engine}"
                      if ENGINES[engine].hdl else None)
    assert got.engine == engine and got.n_ticks == ref.n_ticks and got.dt_ms == ref.dt_ms
    if block == "fanout":
        assert got.values.shape == ref.values.shape
        if engine == "golden":          # within the bound where the twin's current is not clamped
            cfg, x = _fanout_table()
            x = np.clip(x, cfg.S.min_value, cfg.S.max_value)
            free = np.abs(got.values) < cfg.I.max_value
            err = np.abs(got.values - ref.values)
            assert free.sum() > 0 and np.all(err[free] <= cfg.sample_bound(x)[free])
            return
        assert np.array_equal(got.values, ref.values)
        assert got.clamp_counts == ref.clamp_counts and sum(ref.clamp_counts.values()) > 0
        return
    assert len(got.spikes_ms) == len(ref.spikes_ms)
    n_ref = ref.counts()
    assert n_ref.sum() > 0, "the tiny input makes no spike"
    if engine == "golden":
        assert np.abs(got.counts() - n_ref).max() <= 1
        return
    for a, b in zip(got.spikes_ms, ref.spikes_ms):
        assert np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    if got.clamp_counts:                        # the board's link carries no clamps
        assert got.clamp_counts == ref.clamp_counts
