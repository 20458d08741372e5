"""The afferent -> cuneate network: refusals, RTL = twin tick by tick, and spike conservation
across the on-chip link at sweep boundaries and with several spikes in one tick."""

import random
from collections import Counter

import numpy as np
import pytest

from cuneate.hdl.network import AfferentCuneateNetwork, ConfigError, NetworkConfig, NetworkTwin
from cuneate.sim.engines.amaranth import simulate, write_currents

DET = dict(n_sources=4, n_targets=3, delays_ticks=[[0, 0, 3, 3], [0, 0, 0, 0], [3, 3, 0, 0]],
           max_delay_ticks=8, weights=[[6.0] * 4] * 3)


def _cfg(**kw):
    base = dict(n_afferents=6, detector=DET, clock_hz=16e3 * 64, update_hz=16e3,
                tick_source="external")
    return NetworkConfig(**(base | kw))


@pytest.mark.parametrize("kw,expect", [
    (dict(n_afferents=3), "n_afferents must be an integer >= 6"),
    (dict(detector=DET | {"n_sources": 8, "delays_ticks": None, "weights": None}),
     "the detector's 8 sources from afferent 0 on do not fit the core's 6 afferents"),
    (dict(first_source=3), "the detector's 4 sources from afferent 3 on do not fit"),
    (dict(detector=DET | {"clock_hz": 1e6}), "detector.clock_hz is the network's own setting"),
    (dict(detector=DET | {"delays_ticks": [[0, 0, 9, 3], [0] * 4, [0] * 4]}),
     "network detector refused: delay of target 0 from source 2 is 9 ticks"),
    (dict(clock_hz=16e3 * 20), "refused"),
    (dict(clock_hz=16e3 * 39), "the network needs 40 cycles per tick"),
    (dict(cuneate_fifo_depth=2), "cuneate_fifo_depth must be an integer >= n_targets (3)"),
    (dict(afferent_param_sets=("RS", "XX"), afferent_sets=[0] * 6), "afferent core refused"),
])
def test_refusals_are_one_line(kw, expect):
    with pytest.raises(ConfigError) as e:
        _cfg(**kw)
    assert expect in str(e.value) and "\n" not in str(e.value)


def _rtl(cfg, currents, n_ticks, tick_mode="asap", ready_p=1.0, seed=0):
    """Drive the network: constant host currents written first, then ticks (``asap``: the tick
    input held high, so every tick is taken at the earliest cycle the boundary allows;
    ``spaced``: one pulse per ``cycles_per_tick``). Records the output stream, every link
    event with the tick count at that cycle, and the detector's updates."""
    dut = AfferentCuneateNetwork(cfg)
    rng = random.Random(seed)
    rec = {"stream": [], "events": [], "det_rows": [], "go_with_event": 0}

    async def tb(ctx):
        await write_currents(ctx, dut, cfg.core.I.to_raw(np.asarray(currents)))
        cyc = 0
        while True:
            if tick_mode == "asap":
                ctx.set(dut.tick, int(ctx.get(dut.tick_count) < n_ticks))
            else:
                ctx.set(dut.tick, int(cyc % cfg.cycles_per_tick == 0 and
                                      cyc // cfg.cycles_per_tick < n_ticks))
            ready = rng.random() < ready_p
            ctx.set(dut.out_ready, int(ready))
            det, core = dut.det, dut.core
            if ctx.get(det.in_valid):
                rec["events"].append((ctx.get(dut.tick_count) - 1, ctx.get(det.in_source)))
                if ctx.get(det.tick):
                    rec["go_with_event"] += 1
            if ready and ctx.get(dut.out_valid):
                rec["stream"].append((ctx.get(dut.out_population), ctx.get(dut.out_tick),
                                      ctx.get(dut.out_index)))
            if ctx.get(det.upd_valid):
                rec["det_rows"].append((ctx.get(det.upd_tick), ctx.get(det.upd_target),
                                        ctx.get(det.upd_a), ctx.get(det.upd_v),
                                        ctx.get(det.upd_spike)))
            await ctx.tick()
            cyc += 1
            if ctx.get(dut.tick_count) >= n_ticks and not ctx.get(dut.busy) and \
                    not ctx.get(det.upd_valid) and not ctx.get(dut.out_valid) and \
                    not ctx.get(core.busy) and cyc > 20:
                # let the last sweep and detector tick finish and the stream drain
                for _ in range(cfg.cycles_needed + 10):
                    ctx.set(dut.out_ready, 1)
                    if ctx.get(dut.out_valid):
                        rec["stream"].append((ctx.get(dut.out_population),
                                              ctx.get(dut.out_tick), ctx.get(dut.out_index)))
                    await ctx.tick()
                break
        for k in ("tick_count", "link_count", "afferent_spike_count", "cuneate_spike_count",
                  "overrun_count", "cuneate_overflow_count", "afferent_overflow",
                  "merged_count"):
            rec[k] = ctx.get(getattr(dut, k))

    simulate(dut, tb)
    return rec


def _twin(cfg, currents, n_ticks):
    """Afferent and cuneate spikes as (tick, index) and the detector's input sum per
    (tick, target)."""
    tw = NetworkTwin(cfg)
    tw.set_currents(np.asarray(currents))
    aff, cun, sums = [], [], {}
    for k in range(n_ticks):
        a, c = tw.tick()
        aff += [(k, int(i)) for i in np.flatnonzero(a)]
        cun += [(k, int(t)) for t in np.flatnonzero(c)]
        sums.update({(k, t): int(x) for t, x in enumerate(tw.last_inputs)})
    return aff, cun, sums


# spaced ticks under back-pressure in the default lane; ticks as soon as possible in the long
@pytest.mark.parametrize("tick_mode,ready_p", [pytest.param("asap", 1.0, marks=pytest.mark.long),
                                               ("spaced", 0.3)])
def test_rtl_equals_twin_and_every_spike_crosses_the_link_once(tick_mode, ready_p):
    cfg = _cfg()
    # different currents: afferents fire at different sweeps, sometimes together
    currents = [20.0, 30.0, 15.0, 45.0, 60.0, 18.0]
    n = 800
    rec = _rtl(cfg, currents, n, tick_mode, ready_p, seed=5)
    aff, cun, sums = _twin(cfg, currents, n)
    assert rec["tick_count"] == n
    # a tick held high is one pending tick plus overruns; spaced ticks never overrun
    assert (rec["overrun_count"] == 0) == (tick_mode == "spaced")
    assert {(k, t): a for k, t, a, v, s in rec["det_rows"]} == sums
    # the output stream: every afferent and cuneate spike exactly once, tagged and in order
    got_aff = sorted((t, i) for p, t, i in rec["stream"] if p == 0)
    got_cun = sorted((t, i) for p, t, i in rec["stream"] if p == 1)
    assert got_aff == sorted(aff) and len(aff) > 30
    assert got_cun == sorted(cun) and len(cun) >= 3
    # the link: each source spike of sweep k is one event before tick k + 1 is taken
    src = [(k, i) for k, i in aff if i < cfg.n_sources]
    assert Counter(rec["events"]) == Counter(src)
    assert rec["link_count"] == len(src) and rec["afferent_spike_count"] == len(aff)
    assert rec["go_with_event"] == 0 and rec["merged_count"] == 0
    assert rec["cuneate_overflow_count"] == 0 and rec["afferent_overflow"] == 0
    assert rec["cuneate_spike_count"] == len(cun)


@pytest.mark.parametrize("n_afferents", [6, 40])
def test_several_spikes_in_one_tick_at_the_sweep_boundary(n_afferents):
    """Equal currents: all afferents fire in the same sweeps, so five source events arrive in
    consecutive cycles, the last from the sweep's final neuron just before sweep_done, and the
    next tick is taken in the first cycle the boundary allows. With 40 afferents the core's
    sweep outlasts the detector's tick, so only the wait for sweep_done keeps the last
    neurons' spikes in their tick."""
    det = dict(n_sources=5, n_targets=2, delays_ticks=[[0] * 5, [1] * 5], max_delay_ticks=4,
               weights=[[3.0] * 5] * 2)
    cfg = _cfg(n_afferents=n_afferents, detector=det, first_source=n_afferents - 5)
    assert cfg.core.n_neurons + 8 > cfg.det.cycles_needed or n_afferents == 6
    currents = [25.0] * n_afferents
    n = 300
    rec = _rtl(cfg, currents, n, "asap")
    aff, cun, sums = _twin(cfg, currents, n)
    per_sweep = Counter(k for k, _ in aff)
    assert set(per_sweep.values()) == {n_afferents} and len(per_sweep) >= 3   # all together
    F = cfg.first_source
    src = Counter((k, i - F) for k, i in aff if i >= F)
    assert Counter(rec["events"]) == src                         # each source spike once
    assert rec["go_with_event"] == 0 and rec["merged_count"] == 0
    # the detector's input sums: five coincident spikes stamped once, in the next tick
    assert {(k, t): a for k, t, a, v, s in rec["det_rows"]} == sums
    w = int(cfg.det.weights_raw[0, 0])
    for k in per_sweep:
        assert sums[(k + 1, 0)] == 5 * w and sums[(k + 2, 1)] == 5 * w
    got_aff = sorted((t, i) for p, t, i in rec["stream"] if p == 0)
    got_cun = sorted((t, i) for p, t, i in rec["stream"] if p == 1)
    assert got_aff == sorted(aff) and got_cun == sorted(cun) and len(cun) > 0


def test_tick_done_comes_once_every_spike_of_the_tick_is_handed_over():
    """The tick report a host link closes its spike batches on: ticks taken only while neither
    ``busy`` nor ``tick_open`` (as its payload, :mod:`cuneate.hdl.network.payload`, does), a consumer
    ready one cycle in twenty; at each ``tick_done`` every spike of the ticks taken, afferent and
    cuneate, has been handed over, and none of a later tick. (Without the wait for empty FIFOs,
    or without the settling cycles, spikes are still in a FIFO at ``tick_done``: it fails.)"""
    cfg = _cfg()
    currents = [20.0, 30.0, 15.0, 45.0, 60.0, 18.0]
    n = 300
    aff, cun = _twin(cfg, currents, n)[:2]
    want = sorted([(k, 0, i) for k, i in aff] + [(k, 1, t) for k, t in cun])
    dut = AfferentCuneateNetwork(cfg)
    rng = random.Random(3)
    rec = {"handed": [], "bad": [], "done": 0, "open_at_done": 0}

    async def tb(ctx):
        await write_currents(ctx, dut, cfg.core.I.to_raw(np.asarray(currents)))
        while rec["done"] < n:
            taken = ctx.get(dut.tick_count)
            ctx.set(dut.tick, int(taken < n and not ctx.get(dut.busy)
                                  and not ctx.get(dut.tick_open)))
            ready = rng.random() < 0.05
            ctx.set(dut.out_ready, int(ready))
            if ready and ctx.get(dut.out_valid):
                rec["handed"].append((ctx.get(dut.out_tick), ctx.get(dut.out_population),
                                      ctx.get(dut.out_index)))
            if ctx.get(dut.tick_done):
                rec["done"] += 1
                rec["open_at_done"] += ctx.get(dut.tick_open)
                if sorted(rec["handed"]) != [s for s in want if s[0] < taken]:
                    rec["bad"].append(taken - 1)
            await ctx.tick()

    simulate(dut, tb)
    assert rec["bad"] == [] and rec["done"] == n and rec["open_at_done"] == n
    assert sorted(rec["handed"]) == want and len(cun) >= 3
