"""The learning layer as a payload (hdl/plasticity/payload.py): its write map and readout ids,
and the payload in Amaranth's simulator, driven as a face drives it (writes streamed, ticks
held while busy), against the layer's twin run from the same protocol (PlasticityFixed): every
CN spike and every weight read back in the readout sweeps, a weight written over the stream
restarting its synapse."""

import numpy as np
import pytest

from cuneate.hdl.lib.payload import SPIKES_SETTLE, payload_spec
from cuneate.hdl.plasticity import PlasticityConfig
from cuneate.hdl.plasticity.payload import (LearningSpec, readout_ids, weights_from_ids,
                                            write_addresses)
from cuneate.sim.engines.amaranth import simulate
from cuneate.sim.plasticity.engines import face_schedule, run_learning
from learning_case import small_layer


def test_the_write_map_and_the_readout_ids():
    cfg, _ = small_layer()
    S, M, K = cfg.n_sources, cfg.n_targets, cfg.n_synapses
    amap = write_addresses(cfg)
    assert amap == {"spike": (0, S), "weight": (S, M * K), "learn": (S + M * K, 1),
                    "readout": (S + M * K + 1, M)}
    spec = payload_spec(cfg)
    assert isinstance(spec, LearningSpec) and spec.info.n_written == S + M * K + 1 + M
    # 16-bit weights leave as two bytes: id M + (m * 2 + d) * 256 + byte
    assert readout_ids(cfg, [0x1234, 7, 0xFF00]).tolist() == [
        M + 0x34, M + 256 + 0x12, M + 512 + 7, M + 768, M + 1024, M + 1280 + 0xFF]
    w = np.array([0x1234, 7, 0xFF00])
    assert weights_from_ids(cfg, readout_ids(cfg, w)[::-1]).tolist() == w.tolist()
    with pytest.raises(ValueError, match="once"):
        weights_from_ids(cfg, readout_ids(cfg, w)[1:])


def drive(spec, writes: dict, n_sweeps: int) -> list[list[int]]:
    """Amaranth's simulator on the payload of ``spec`` as a face drives it: each sweep's
    writes streamed (waiting on ``ready``), the tick given once ``busy`` is low, the spike
    stream drained (random back-pressure); the ids of each sweep, in the order sent."""
    dut = spec.build()
    rng = np.random.default_rng(5)
    sweeps: list[list[int]] = [[] for _ in range(n_sweeps)]

    async def cyc(ctx):
        ready = int(rng.random() < 0.7)
        ctx.set(dut.spikes.ready, ready)
        if ready and ctx.get(dut.spikes.valid):          # taken at this edge
            p = ctx.get(dut.spikes.payload)
            sweeps[p.sweep].append(int(p.index))
        done = ctx.get(dut.sweep_done)
        await ctx.tick()
        return done

    async def tb(ctx):
        for k in range(n_sweeps):
            for first, raw in writes.get(k, []):
                for i, v in enumerate(raw):
                    ctx.set(dut.write.valid, 1)
                    ctx.set(dut.write.payload, {"addr": first + i, "value": int(v),
                                                "last": int(i == len(raw) - 1)})
                    while True:
                        taken = ctx.get(dut.write.ready)
                        await cyc(ctx)
                        if taken:
                            break
                ctx.set(dut.write.valid, 0)
            while ctx.get(dut.busy):
                await cyc(ctx)
            ctx.set(dut.tick, 1)
            await cyc(ctx)
            ctx.set(dut.tick, 0)
            while not await cyc(ctx):
                pass
            for _ in range(3 * SPIKES_SETTLE):
                await cyc(ctx)
        assert not ctx.get(dut.overflow) and not ctx.get(dut.overrun)

    simulate(dut, tb, spec.info.clock_hz)
    return sweeps


@pytest.mark.parametrize("readout_synapses", [None, 2])
def test_the_payload_learns_as_the_twin_and_sends_its_weights_in_readout_sweeps(
        readout_synapses):
    """All of a CN's synapses in one readout sweep, or two a sweep (two sweeps a CN)."""
    cfg, pres = small_layer()
    flags = np.array([False, True])
    spec = LearningSpec(cfg, readout_synapses)
    R, C = spec.readout_synapses, spec.parts
    plan = face_schedule(cfg, pres, flags, readout_synapses=readout_synapses)
    writes, n_sweeps = plan.writes, plan.n_sweeps
    got = drive(spec, writes, n_sweeps)
    fixed = run_learning("fixed", cfg, pres, flags)
    M, n_total = cfg.n_targets, pres.n * pres.n_ticks
    assert fixed.spike_cn.size > 0 and not np.array_equal(fixed.weights_raw, cfg.weights_raw)
    want = [[] for _ in range(n_total)]
    for p, k, j in zip(fixed.spike_pres, fixed.spike_tick, fixed.spike_cn):
        want[p * pres.n_ticks + k].append(int(j))
    assert got[:n_total] == want
    # a part of a CN's weights a readout sweep, in synapse order
    assert n_sweeps == n_total + M * C
    for j in range(M):
        for c in range(C):
            assert got[n_total + j * C + c] == readout_ids(
                cfg, fixed.weights_raw[j, c * R:(c + 1) * R], c * R).tolist()


def test_a_weight_written_over_the_stream_restarts_its_synapse():
    """Weights written at the first sweep: the run equals the twin's from those weights."""
    cfg, pres = small_layer()
    flags = np.ones(pres.n, bool)
    rng = np.random.default_rng(8)
    w_new = rng.uniform(0, 6, cfg.weights_real.shape)
    written = PlasticityConfig.from_kwargs(cfg.to_kwargs() | {"weights": w_new.tolist()})
    plan = face_schedule(cfg, pres, flags)
    writes, n_sweeps = plan.writes, plan.n_sweeps
    writes.setdefault(0, []).insert(0, (write_addresses(cfg)["weight"][0],
                                        written.weights_raw.reshape(-1)))
    got = drive(payload_spec(cfg), writes, n_sweeps)
    fixed = run_learning("fixed", written, pres, flags)
    n_total = pres.n * pres.n_ticks
    assert not np.array_equal(written.weights_raw, cfg.weights_raw)
    cn = [(k, j) for k in range(n_total) for j in got[k]]
    assert cn == [(p * pres.n_ticks + k, j) for p, k, j in
                  zip(fixed.spike_pres, fixed.spike_tick, fixed.spike_cn)]
    for j in range(cfg.n_targets):
        assert got[n_total + j] == readout_ids(cfg, fixed.weights_raw[j]).tolist()
