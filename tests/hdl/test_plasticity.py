"""The learning layer's hardware: its configuration's refusals and step table, the twin's
compiled kernel against its stage functions, the RTL against the twin (Amaranth simulator:
every spike and every weight, host writes and reads), the stage's hazard counter, and the
fixed point against golden."""

import math

import numpy as np
import pytest

from cuneate.golden.aidp import AidpParams, sigmoid
from cuneate.golden.cuneate_layer import presentations
from cuneate.hdl.plasticity import ConfigError, OPS, PlasticityConfig
from cuneate.hdl.plasticity.twin import PlasticityTwin
from cuneate.sim.plasticity.engines import run_learning


def _layer(seed=3, S=8, M=3, K=4, eta=2e-3, latency_ms=1.0, **kw):
    rng = np.random.default_rng(seed)
    src = np.array([np.sort(rng.choice(S, K, replace=False)) for _ in range(M)])
    cfg = PlasticityConfig(n_sources=S, sources=src, weights=rng.uniform(0, 6, (M, K)),
                           rule=AidpParams(eta=eta, latency_ms=latency_ms),
                           clock_hz=2000.0 * 200, **kw)
    tpl = [[np.sort(rng.uniform(0, 120, rng.integers(5, 50))) for _ in range(S)]
           for _ in range(2)]
    return cfg, tpl


@pytest.mark.parametrize("kw,match", [
    (dict(rule=AidpParams(latency_ms=9.0)), "delayed spike words"),
    (dict(rule=AidpParams(latency_ms=0.3)), "not a whole number of ticks"),
    (dict(sources=[[0, 1], [1, 8]]), "outside 0 .. 7"),
    (dict(sources=[[0, 0], [1, 2]]), "takes an afferent twice"),
    (dict(sources=[[0, 1], [1, 2]], weights=[[0.0, 7.0], [1.0, 1.0]]), r"\[0, w_max"),
    (dict(clock_hz=2000.0 * 20), "cycles per"),
    (dict(rule=AidpParams(eta=1e-12)), "rounds to 0"),
])
def test_what_the_layer_cannot_hold_is_refused_in_one_line(kw, match):
    with pytest.raises(ConfigError, match=match) as exc:
        PlasticityConfig(n_sources=8, **kw)
    assert "\n" not in str(exc.value)


def test_the_step_table_is_eta_alpha_dt_sigma_over_k_at_each_bins_centre():
    cfg, _ = _layer(eta=2e-6)
    p, K = cfg.rule, cfg.n_synapses
    unit = p.eta * p.alpha * cfg.dt_ms / K * 2.0 ** (cfg.d_shift - cfg.L.frac_bits) \
        / cfg.W.lsb
    nb = 1 << cfg.sigmoid_bits
    centre = (np.arange(nb) + 0.5) * 2.0 ** (cfg.W.width - cfg.sigmoid_bits) * cfg.W.lsb
    got = np.asarray(cfg.step_table, dtype=np.float64) * 2.0 ** -cfg.T_frac
    want = np.concatenate([unit * sigmoid(centre, False, p), unit * sigmoid(centre, True, p)])
    assert np.all(np.abs(got - want) <= 2.0 ** -cfg.T_frac / 2 + 1e-18)


@pytest.mark.parametrize("latency_ms", [0.0, 1.0])
def test_the_compiled_kernel_equals_the_stage_functions(latency_ms):
    cfg, tpl = _layer(latency_ms=latency_ms)
    pres = presentations(tpl, [0, 1, 1, 0, 1], (0, 60), 0.5, 5.0, 10.0, 4)
    flags = [True, False, True, True, False]
    a, b = PlasticityTwin(cfg, kernel="stages"), PlasticityTwin(cfg, kernel="numba")
    ra, rb = a.run(pres, flags), b.run(pres, flags)
    assert ra["counts"].sum() > 0 and sum(a.clamp_counts.values()) > 0
    for k in ("w", "cd", "cr", "L", "v", "u", "E", "delayed"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert a.H == b.H and a.ticks == b.ticks and a.clamp_counts == b.clamp_counts
    for k in ra:
        assert np.array_equal(ra[k], rb[k]), k


def test_the_rtl_equals_the_twin_spike_for_spike_and_weight_for_weight():
    """Amaranth's simulator on the layer: the spike stream, every weight read back through the
    host port, the clamp counters (every kind) against the twin's."""
    cfg, tpl = _layer(S=6, M=2, K=3)
    pres = presentations(tpl, [0, 1, 0], (0, 25), 0.5, 3.0, 5.0, 4)
    flags = [True, False, True]
    rtl, twin = (run_learning(e, cfg, pres, flags) for e in ("amaranth", "fixed"))
    assert twin.spike_cn.size > 0 and not np.array_equal(twin.weights_raw, cfg.weights_raw)
    assert np.array_equal(rtl.weights_raw, twin.weights_raw)
    for k in ("spike_pres", "spike_tick", "spike_cn", "counts"):
        assert np.array_equal(getattr(rtl, k), getattr(twin, k)), k
    assert rtl.clamp_counts == twin.clamp_counts


def test_host_writes_and_reads_wait_for_the_layer_and_restart_the_synapse():
    from cuneate.hdl.plasticity.core import LearningLayer
    from cuneate.sim.engines.amaranth import simulate
    cfg, _ = _layer(S=6, M=2, K=3)
    dut, got = LearningLayer(cfg), {}

    async def tb(ctx):
        ctx.set(dut.tick, 1)                       # a tick: the layer is busy
        await ctx.tick()
        ctx.set(dut.tick, 0)
        ctx.set(dut.w_wr_valid, 1)
        ctx.set(dut.w_wr_addr, 4)
        ctx.set(dut.w_wr_data, 12345)
        waited = 0
        while not ctx.get(dut.w_wr_ready):
            await ctx.tick()
            waited += 1
        await ctx.tick()
        ctx.set(dut.w_wr_valid, 0)
        got["waited"] = waited
        for _ in range(4):
            await ctx.tick()
        ctx.set(dut.w_rd_valid, 1)
        ctx.set(dut.w_rd_addr, 4)
        await ctx.tick()
        ctx.set(dut.w_rd_valid, 0)
        for _ in range(3):
            await ctx.tick()
            if ctx.get(dut.w_rd_resp_valid):
                got["read"] = ctx.get(dut.w_rd_resp_data)
        got["hazards"] = ctx.get(dut.hazard_count)
    simulate(dut, tb, cfg.clock_hz)
    assert got["waited"] >= cfg.cycles_needed - 3 and got["read"] == 12345
    assert got["hazards"] == 0


def test_an_operation_on_a_synapse_in_flight_is_a_counted_hazard():
    from cuneate.hdl.plasticity.stage import SynapseStage
    from cuneate.sim.engines.amaranth import simulate
    cfg, _ = _layer(S=6, M=2, K=3)
    dut, got = SynapseStage(cfg), {}

    async def tb(ctx):
        for addr, gap in ((2, 0), (2, 3), (5, 1), (2, 4)):   # 2 again after 3 cycles: hazard
            for _ in range(gap - 1 if gap else 0):
                await ctx.tick()
            ctx.set(dut.op_valid, 1)
            ctx.set(dut.op, OPS["write"])
            ctx.set(dut.op_addr, addr)
            await ctx.tick()
            ctx.set(dut.op_valid, 0)
        for _ in range(5):
            await ctx.tick()
        got["hazards"] = ctx.get(dut.hazard_count)
    simulate(dut, tb, cfg.clock_hz)
    assert got["hazards"] == 1


def test_fixed_point_learning_follows_golden():
    """A few windows of strong learning: the twin's weights within a few of the weight
    format's LSBs of golden's float64 ones, the same synapses strong."""
    cfg, tpl = _layer(seed=5, S=8, M=3, K=5, eta=5e-4)
    pres = presentations(tpl, [0, 1, 0, 1, 0, 1], (0, 80), 0.5, 5.0, 10.0, 6)
    g, f = (run_learning(e, cfg, pres, True) for e in ("golden", "fixed"))
    moved = np.abs(g.weights - cfg.weights_real)
    assert moved.max() > 0.5                                  # they learnt
    assert np.abs(g.weights - f.weights).max() < 0.05 * cfg.rule.w_max
    assert np.array_equal(g.weights > 3.0, f.weights > 3.0)
    assert math.isfinite(g.extra["drive_max"])


def test_a_frozen_layer_is_the_learning_one_without_its_steps():
    """``plastic=False`` (the baseline of the cost of learning): the same spikes as the
    learning layer's twin with no step applied, and window ends leave every weight."""
    cfg, tpl = _layer(S=6, M=2, K=3)
    frozen = PlasticityConfig(**{**cfg.to_kwargs(), "rule": cfg.rule, "plastic": False})
    assert frozen.synapse_fields == [("w", cfg.W)]
    pres = presentations(tpl, [0, 1], (0, 25), 0.5, 3.0, 5.0, 4)
    rtl = run_learning("amaranth", frozen, pres, True)
    twin = run_learning("fixed", cfg, pres, False)
    assert twin.spike_cn.size > 0 and np.array_equal(rtl.weights_raw, cfg.weights_raw)
    for k in ("spike_pres", "spike_tick", "spike_cn"):
        assert np.array_equal(getattr(rtl, k), getattr(twin, k)), k
