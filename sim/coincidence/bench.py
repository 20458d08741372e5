"""cocotb bench for the generated :class:`cuneate.hdl.coincidence.CoincidenceDetector` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG``; figures go to
``CUNEATE_BENCH_REPORT``. Test ``scoreboard``: external ticks every ``period`` cycles; between
ticks input spike events arrive at random (one per cycle, sometimes twice from one source).
Every cycle is watched; every target update is checked when its tick is complete:

* the input sum the DUT used (``upd_a``) equals the twin's from the events driven before that
  tick and the delays and weights;
* traces, PSP current, ``v``, ``u``, spike and clamp flags equal the bit-exact twin advanced from
  the DUT's own previous state (zero mismatches);
* the float64 golden steps from the same state stay within their derived one-step bounds:
  the traces (:func:`~cuneate.hdl.lib.synapses.trace_golden_check`) and the Izhikevich update
  (:class:`~cuneate.sim.izhikevich.scoreboard.SweepChecker`, flagged clamps expected,
  unflagged fail);
* the spike stream equals the updates' spikes, ``merged_count`` the duplicate events and
  ``tick_count`` the ticks.

``engine``: runs a given input schedule (events per tick) and records the spike stream; the
``icarus``/``verilator`` engines of ``cuneate simulate coincidence``.
"""

from __future__ import annotations

import time

import cocotb
import numpy as np
from cocotb.triggers import FallingEdge

from cuneate.hdl.coincidence import CoincidenceConfig
from cuneate.sim.coincidence.scoreboard import CoincidenceChecker
from cuneate.sim.engines.bench import (bench_case, bench_config, bench_report, bench_verdict,
                                       spikes_then_tick, start_in_reset)


async def start_bench(dut):
    await start_in_reset(dut, (dut.tick, dut.in_valid, dut.in_source, dut.clamp_clear))


UPDATE_FIELDS = ("v", "u", "xd", "xr", "a", "i", "spike", "clamp")


def update_row(dut) -> dict:
    sig = {"v": dut.upd_v, "u": dut.upd_u, "xd": dut.upd_xd, "xr": dut.upd_xr, "a": dut.upd_a,
           "i": dut.upd_i, "spike": dut.upd_spike, "clamp": dut.upd_clamp}
    signed = {"v", "u", "xd", "xr", "i"}
    return {k: (s.value.to_signed() if k in signed else int(s.value)) for k, s in sig.items()}


@cocotb.test()
async def scoreboard(dut):
    spec, cfg, rng = bench_case("detector", lambda kw: CoincidenceConfig(**kw))
    M, S = cfg.n_targets, cfg.n_sources
    n_ticks = spec["ticks"]
    period = spec.get("period", cfg.cycles_needed + 2 * S + 4)
    p_event = spec.get("event_p", 0.3)
    checker = CoincidenceChecker(cfg)
    await start_bench(dut)
    pending, events_of = [], {}
    rows: dict = {}
    stream, upd_spikes = [], []
    tick_no, phase, cycles = 0, 1, 0
    merged = 0
    t0 = time.perf_counter()
    while checker.stats["ticks_checked"] < n_ticks:
        tick = phase == 0 and tick_no < n_ticks
        dut.tick.value = int(tick)
        dut.in_valid.value = 0
        if tick:
            events_of[tick_no] = pending
            pending = []
            tick_no += 1
        elif tick_no < n_ticks and rng.random() < p_event:
            s = rng.randrange(S)
            dut.in_valid.value = 1
            dut.in_source.value = s
            merged += s in pending
            pending.append(s)
        await FallingEdge(dut.clk)
        cycles += 1
        phase = (phase + 1) % period
        if int(dut.spike_valid.value):
            stream.append((int(dut.spike_tick.value), int(dut.spike_target.value)))
        if not int(dut.upd_valid.value):
            continue
        k, t = int(dut.upd_tick.value), int(dut.upd_target.value)
        r = update_row(dut)
        rows.setdefault(k, {f: np.zeros(M, dtype=np.int64) for f in UPDATE_FIELDS})
        for f in UPDATE_FIELDS:
            rows[k][f][t] = r[f]
        if r["spike"]:
            upd_spikes.append((k, t))
        if t == M - 1:
            checker.check(events_of[k], rows.pop(k))
    wall = time.perf_counter() - t0
    extra = []
    if sorted(stream) != sorted(upd_spikes):
        extra.append(f"spike stream {len(stream)} events differs from the updates' "
                     f"{len(upd_spikes)} spikes")
    if int(dut.merged_count.value) != merged:
        extra.append(f"merged_count {int(dut.merged_count.value)} != {merged} duplicate events")
    if int(dut.tick_count.value) != n_ticks:
        extra.append(f"tick_count {int(dut.tick_count.value)} != {n_ticks}")
    if int(dut.overrun_count.value):
        extra.append(f"{int(dut.overrun_count.value)} ticks overran (period too short)")
    report = checker.stats | {"izhikevich": checker.iz.stats.to_dict(), "cycles": cycles,
                              "cycles_per_s": cycles / wall, "spikes": len(stream),
                              "merged": merged, "events": sum(map(len, events_of.values()))}
    bench_verdict(report, checker.failures() + extra)


@cocotb.test()
async def engine(dut):
    spec = bench_config()
    CoincidenceConfig(**spec["detector"])          # refuses a configuration it cannot build
    n_ticks = spec["ticks"]
    by_tick = {int(k): v for k, v in spec["events"].items()}
    await start_bench(dut)
    stream, clamp_words = [], []
    t0 = time.perf_counter()
    for k in range(n_ticks):
        await spikes_then_tick(dut, by_tick.get(k, []), lambda: FallingEdge(dut.clk), True)
        while True:
            await FallingEdge(dut.clk)
            if int(dut.spike_valid.value):
                stream.append((int(dut.spike_tick.value), int(dut.spike_target.value)))
            if int(dut.upd_valid.value) and int(dut.upd_clamp.value):
                clamp_words.append(int(dut.upd_clamp.value))
            if not int(dut.busy.value) and not int(dut.upd_valid.value):
                break
    bench_report({"spikes": stream, "ticks": int(dut.tick_count.value),
             "merged": int(dut.merged_count.value), "wall_s": time.perf_counter() - t0,
             "clamp_flags": int(dut.clamp_flags.value), "clamp_words": clamp_words})
