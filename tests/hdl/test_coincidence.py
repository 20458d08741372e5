"""The coincidence detector: refusals, RTL = twin on every update, twin against golden."""

import numpy as np
import pytest

from cuneate.golden import coincidence as gcun
from cuneate.hdl.coincidence import (CoincidenceConfig, CoincidenceDetector, CoincidenceTwin,
                                 ConfigError)
from cuneate.sim.engines.amaranth import simulate, spikes_then_tick

DELAYS = [[0, 3, 1, 0], [2, 0, 0, 5], [7, 7, 0, 0]]


def _small(**kw):
    base = dict(n_sources=4, n_targets=3, delays_ticks=DELAYS, max_delay_ticks=8)
    return CoincidenceConfig(**(base | kw))


@pytest.mark.parametrize("kw,expect", [
    (dict(delays_ticks=[[0, 3, 1, 8], [2, 0, 0, 5], [7, 7, 0, 0]]),
     "delay of target 0 from source 3 is 8 ticks: outside 0 .. 7"),
    (dict(delays_ticks=[[0, 3, 1, -1], [2, 0, 0, 5], [7, 7, 0, 0]]), "outside 0 .. 7"),
    (dict(delays_ticks=[[0, 1]]), "delays_ticks must have shape (n_targets, n_sources) = (3, 4)"),
    (dict(weights=np.full((3, 4), -1.0)), "weights must be finite and >= 0"),
    (dict(weights=np.full((3, 4), np.nan)), "weights must be finite and >= 0"),
    (dict(weights=[[8, 8, 8, 1e-4]] * 3), "weight of target 0 from source 3 (0.0001) rounds "
                                          "to 0"),
    (dict(weights=np.zeros((3, 4))), "every weight is 0"),
    (dict(tau_rise_ms=2.0, tau_decay_ms=0.5), "need 0 < tau_rise < tau_decay"),
    (dict(tau_rise_ms=1e-4), "PSP trace xr: decay k = 1 - exp(-dt/tau)"),
    (dict(tau_decay_ms=1e6, tau_rise_ms=1e5), "targets' Izhikevich arithmetic refused"),
    (dict(clock_hz=16e3 * 20), "3 targets x 4 sources need 38 cycles per tick"),
    (dict(clock_hz=16e3 * 40.5), "is not an integer number of cycles per update"),
    (dict(target_sets=[0, 1, 0]), "target_sets needs 3 indices into the 1 parameter set"),
    (dict(param_sets=("RS", "nope")), "targets' Izhikevich arithmetic refused"),
])
def test_refusals_are_one_line(kw, expect):
    with pytest.raises(ConfigError) as e:
        _small(**kw)
    assert expect in str(e.value) and "\n" not in str(e.value)


def test_from_ms_refuses_a_delay_between_ticks():
    with pytest.raises(ConfigError, match=r"delay 0.1 ms is not a whole number of ticks"):
        CoincidenceConfig.from_ms([[0.0, 0.1]])
    c = CoincidenceConfig.from_ms([[0.0, 2.0], [1.0, 0.0]])
    assert c.delays.tolist() == [[0, 32], [16, 0]]


def test_derived_formats_hold_the_worst_case_input():
    c = CoincidenceConfig()                      # brief: J = 8, 4 afferents, 32 ms history
    assert c.max_delay_ticks == 513 and c.history_addr_bits == 10
    assert (c.max_delay_ticks - 1) * c.dt_ms == 32.0
    # every source spiking every tick: xd - xr reaches J S (e_d/(1-e_d) - e_r/(1-e_r))
    ed, er = np.exp(-c.dt_ms / 2.0), np.exp(-c.dt_ms / 0.5)
    top = 8 * 4 * (ed / (1 - ed) - er / (1 - er))
    assert c.i_lo < 0 < top < c.i_hi < top + 1
    # the Izhikevich arithmetic is proven for that current range
    assert c.iz.i_lo == pytest.approx(c.i_lo) and c.iz.i_hi == pytest.approx(c.i_hi)
    d = c.to_dict()
    assert d["multipliers"] == 6 and d["formats"]["weight"]["format"] == "uQ4.8"
    assert not any(v["can_act_for_accepted_inputs"] for k, v in
                   d["izhikevich"]["clamps"].items() if k != "kinds")


def _rtl_run(cfg, schedule, overrun_at=()):
    """Drive the RTL: per tick the events of ``schedule[k]`` (one per cycle), then the tick;
    optionally a second tick pulse while busy. Returns update rows and counters."""
    dut = CoincidenceDetector(cfg)
    rows, stream = [], []
    out = {}

    async def tb(ctx):
        for k, events in enumerate(schedule):
            await spikes_then_tick(ctx, dut, events, ctx.tick, True)
            if k in overrun_at:
                await ctx.tick()
                ctx.set(dut.tick, 1)             # a tick while the last one is processed
                await ctx.tick()
                ctx.set(dut.tick, 0)
            while True:
                await ctx.tick()
                if ctx.get(dut.spike_valid):
                    stream.append((ctx.get(dut.spike_tick), ctx.get(dut.spike_target)))
                if ctx.get(dut.upd_valid):
                    rows.append({k: ctx.get(getattr(dut, f"upd_{k}")) for k in
                                 ("tick", "target", "v", "u", "xd", "xr", "a", "i", "spike",
                                  "clamp")})
                if not ctx.get(dut.busy) and not ctx.get(dut.upd_valid):
                    break
        for k in ("tick_count", "merged_count", "overrun_count", "tick_overrun",
                  "clamp_flags"):
            out[k] = ctx.get(getattr(dut, k))

    simulate(dut, tb)
    return rows, stream, out


def _twin_rows(cfg, schedule):
    twin = CoincidenceTwin(cfg)
    rows = []
    for k, events in enumerate(schedule):
        if events:
            twin.spike_in(events)
        a_in = twin.stamp()
        out = twin.update(twin.v, twin.u, twin.xd, twin.xr, a_in)
        twin.v, twin.u, twin.xd, twin.xr = out["v"], out["u"], out["xd"], out["xr"]
        twin.ticks += 1
        for t in range(cfg.n_targets):
            rows.append({"tick": k, "target": t, "v": int(out["v"][t]), "u": int(out["u"][t]),
                         "xd": int(out["xd"][t]), "xr": int(out["xr"][t]),
                         "a": int(a_in[t]), "i": int(out["i"][t]),
                         "spike": int(out["spike"][t]), "clamp": int(out["clamp"][t])})
    return rows, twin


@pytest.mark.parametrize("param_sets,target_sets,rounding", [
    (("RS",), None, "nearest"),
    (("RS", "FS"), [0, 1, 0], "nearest"),
    (("CH", "RS"), [1, 1, 0], "truncate"),
])
def test_rtl_equals_twin_on_every_update(param_sets, target_sets, rounding):
    cfg = _small(param_sets=param_sets, target_sets=target_sets, rounding=rounding,
                 weights=np.random.default_rng(2).uniform(2, 12, (3, 4)))
    rng = np.random.default_rng(7)
    # random events, duplicates within a tick included
    schedule = [list(rng.integers(0, 4, rng.integers(0, 6))) for _ in range(80)]
    rows, stream, counters = _rtl_run(cfg, schedule)
    expect, twin = _twin_rows(cfg, schedule)
    assert rows == expect
    assert sum(r["spike"] for r in rows) > 10
    assert sorted(stream) == sorted((r["tick"], r["target"]) for r in rows if r["spike"])
    assert counters["tick_count"] == 80 and counters["merged_count"] == twin.merged > 0
    assert counters["overrun_count"] == 0 and counters["clamp_flags"] == 0


def test_a_tick_while_busy_is_counted_not_lost_silently():
    cfg = _small()
    rows, _, counters = _rtl_run(cfg, [[0], [1], [2]], overrun_at=(1,))
    assert counters["overrun_count"] == 1 and counters["tick_overrun"] == 1
    assert counters["tick_count"] == 3 and len(rows) == 9


def test_twin_refuses_a_source_outside_the_population():
    with pytest.raises(ValueError, match=r"spike source 4 is outside 0 .. 3"):
        CoincidenceTwin(_small()).spike_in([1, 4])


def test_psp_of_one_spike_follows_the_golden_kernel():
    cfg = _small()
    twin = CoincidenceTwin(cfg)
    n = 160
    currents = []
    for k in range(n):
        if k == 10:
            twin.spike_in([0])                   # stamped with tick 10; target 2 delays it 7
        i = twin.update(twin.v, twin.u, twin.xd, twin.xr, twin.stamp())
        twin.v, twin.u, twin.xd, twin.xr = i["v"], i["u"], i["xd"], i["xr"]
        twin.ticks += 1
        currents.append(cfg.iz.I.to_float(i["i"]))
    cur = np.array(currents)
    dt = cfg.dt_ms
    gold = gcun.psp_drive([[10 * dt]], cfg.delays[:, :1] * dt, np.arange(n) * dt, J=8.0)
    lsb = cfg.iz.I.lsb
    assert np.max(np.abs(cur - gold)) < 4 * lsb and gold.max() > 3
    # onset one tick after the delayed arrival (the kernel is 0 at lag 0), never earlier
    for t, d in enumerate(cfg.delays[:, 0]):
        assert np.all(cur[:11 + d, t] == 0) and cur[11 + d, t] > 0


def test_twin_spike_trains_match_golden():
    rng = np.random.default_rng(3)
    delays = np.array([[0, 16, 0, 16], [0, 0, 0, 0], [16, 0, 16, 0]])
    cfg = CoincidenceConfig(delays_ticks=delays)
    n = 16000                                     # 1 s
    ins = [np.sort(rng.choice(n, 40, replace=False)) for _ in range(4)]
    sp = CoincidenceTwin(cfg).run(ins, n)
    g = gcun.simulate_cuneate([t * cfg.dt_ms for t in ins], delays * cfg.dt_ms, n * cfg.dt_ms,
                              dt_ms=cfg.dt_ms)
    for a, b in zip(sp, g.spikes_ms):
        assert len(a) == len(b) > 3
        assert np.max(np.abs(a - np.asarray(b))) <= cfg.dt_ms + 1e-9
