"""cocotb bench for the generated :class:`cuneate.hdl.network.AfferentCuneateNetwork` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG``; the report goes to
``CUNEATE_BENCH_REPORT``. Test ``engine``: per tick, wait until the network is idle, write the
host currents that change, pulse ``tick``; every cycle the output stream is read (``out_ready``
held high). The report holds the stream (population, tick modulo the tick width, index) and
the network's counters; the ``icarus``/``verilator`` engines of ``cuneate simulate network``.

Test ``scoreboard``: ticks at random spacing, sometimes held high for stretches (every tick then
taken in the first cycle the sweep boundary allows); host current writes at random cycles
(also during sweeps); ``out_ready`` random. Every cycle the core's and the detector's update
outputs (``core.upd_*``, ``det.upd_*``) and the link are watched:

* every afferent sweep is checked against the Izhikevich twin from the DUT's own previous
  state and the float64 golden one-step bound
  (:class:`~cuneate.sim.izhikevich.scoreboard.SweepChecker`);
* every detector tick is checked (input sums, traces, current, v, u, spikes, clamps) against
  the coincidence twin with, as its input events, the source spikes of the previous afferent
  sweep as the DUT's core produced them, and against golden
  (:class:`~cuneate.sim.coincidence.scoreboard.CoincidenceChecker`);
* the link carried each source spike exactly once, never in the cycle of a tick;
* the output stream holds every afferent and cuneate spike exactly once with its population.
"""

from __future__ import annotations

import time
from collections import Counter

import cocotb
from cocotb.triggers import FallingEdge

import numpy as np

from cuneate.hdl.network import NetworkConfig
from cuneate.sim.coincidence.scoreboard import CoincidenceChecker
from cuneate.sim.engines.bench import bench_case, bench_config, bench_report, start_in_reset
from cuneate.sim.izhikevich.scoreboard import SweepChecker


async def _start(dut):
    """Clock, reset, inputs idle, the spike stream always read."""
    await start_in_reset(dut, (dut.tick, dut.i_wr_en, dut.i_wr_addr, dut.i_wr_data,
                               dut.clamp_clear), (dut.out_ready,))


@cocotb.test()
async def engine(dut):
    spec = bench_config()
    n_ticks = spec["ticks"]
    writes = {int(k): v for k, v in spec["writes"].items()}
    await _start(dut)
    stream = []
    cycles = 0
    t0 = time.perf_counter()

    async def step():
        nonlocal cycles
        if int(dut.out_valid.value):
            stream.append((int(dut.out_population.value), int(dut.out_tick.value),
                           int(dut.out_index.value)))
        await FallingEdge(dut.clk)
        cycles += 1

    for k in range(n_ticks):
        while int(dut.busy.value):
            await step()
        for i, raw in writes.get(k, []):
            dut.i_wr_en.value = 1
            dut.i_wr_addr.value = i
            dut.i_wr_data.value = raw
            await step()
        dut.i_wr_en.value = 0
        dut.tick.value = 1
        await step()
        dut.tick.value = 0
    while int(dut.busy.value) or int(dut.out_valid.value):
        await step()
    for _ in range(8):
        await step()
    counters = {k: int(getattr(dut, k).value) for k in
                ("tick_count", "link_count", "merged_count", "cuneate_overflow_count",
                 "afferent_overflow", "overrun_count")}
    bench_report({"stream": stream, "counters": counters, "cycles": cycles,
                  "cycles_per_s": cycles / (time.perf_counter() - t0)})
    assert counters["tick_count"] == n_ticks


def _signed(sig) -> int:
    return sig.value.to_signed()


@cocotb.test()
async def scoreboard(dut):
    spec, cfg, rng = bench_case("network", lambda kw: NetworkConfig(**kw))
    N, M, S, F = cfg.n_afferents, cfg.n_targets, cfg.n_sources, cfg.first_source
    n_ticks = spec["ticks"]
    cur_lo, cur_hi = spec.get("current_range", [0.0, 40.0])
    core_chk = SweepChecker(cfg.core)
    det_chk = CoincidenceChecker(cfg.det)
    core, det = dut.core, dut.det
    await _start(dut)
    crow = {k: np.zeros(N, dtype=np.int64) for k in ("v", "u", "i", "spike", "clamp")}
    drow = {k: np.zeros(M, dtype=np.int64) for k in ("v", "u", "xd", "xr", "a", "i", "spike",
                                                      "clamp")}
    sweeps = 0
    events_of: dict = {0: []}
    link, expect_link = Counter(), Counter()
    expect_stream, stream = Counter(), Counter()
    held, gap, cycles = 0, 0, 0
    t0 = time.perf_counter()
    W = 1 << cfg.tick_width
    while det_chk.stats["ticks_checked"] < n_ticks or sweeps < n_ticks:
        taken = int(dut.tick_count.value)
        # tick: held high for a stretch, or a pulse after a random gap
        if taken >= n_ticks:
            dut.tick.value = 0
        elif held:
            dut.tick.value = 1
            held -= 1
        elif gap:
            dut.tick.value = 0
            gap -= 1
        else:
            dut.tick.value = 1
            if rng.random() < 0.3:
                held = rng.randrange(50, 400)
            else:
                gap = rng.randrange(cfg.cycles_needed // 2, 2 * cfg.cycles_needed)
        # host current writes at random cycles
        if rng.random() < 0.05:
            dut.i_wr_en.value = 1
            dut.i_wr_addr.value = rng.randrange(N)
            dut.i_wr_data.value = int(cfg.core.I.to_raw(rng.uniform(cur_lo, cur_hi)))
        else:
            dut.i_wr_en.value = 0
        ready = rng.random() < 0.7
        dut.out_ready.value = int(ready)
        if ready and int(dut.out_valid.value):      # taken at the coming rising edge
            stream[(int(dut.out_population.value), int(dut.out_tick.value),
                    int(dut.out_index.value))] += 1
        await FallingEdge(dut.clk)
        cycles += 1
        if int(det.in_valid.value):                 # an event of sweep tick_count - 1
            link[(int(dut.tick_count.value) - 1, int(det.in_source.value))] += 1
        if int(core.upd_valid.value):
            j = int(core.upd_index.value)
            crow["v"][j], crow["u"][j] = _signed(core.upd_v), _signed(core.upd_u)
            crow["i"][j] = _signed(core.upd_current)
            crow["spike"][j], crow["clamp"][j] = int(core.upd_spike.value), \
                int(core.upd_clamp.value)
            if j == N - 1:
                core_chk.check(crow["v"], crow["u"], crow["i"], crow["spike"], crow["clamp"])
                spk = np.flatnonzero(crow["spike"])
                for a in spk:
                    expect_stream[(0, sweeps % W, int(a))] += 1
                    if F <= a < F + S:
                        expect_link[(sweeps, int(a) - F)] += 1
                sweeps += 1
                events_of[sweeps] = [int(a) - F for a in spk if F <= a < F + S]
        if int(det.upd_valid.value):
            t = int(det.upd_target.value)
            for k, sig in (("v", det.upd_v), ("u", det.upd_u), ("xd", det.upd_xd),
                           ("xr", det.upd_xr), ("i", det.upd_i)):
                drow[k][t] = _signed(sig)
            for k, sig in (("a", det.upd_a), ("spike", det.upd_spike), ("clamp", det.upd_clamp)):
                drow[k][t] = int(sig.value)
            if t == M - 1:
                k = det_chk.stats["ticks_checked"]
                det_chk.check(events_of.pop(k), {x: y.copy() for x, y in drow.items()})
                for tt in np.flatnonzero(drow["spike"]):
                    expect_stream[(1, k % W, int(tt))] += 1
    # drain the stream
    dut.tick.value = 0
    dut.i_wr_en.value = 0
    idle = 0
    while idle < 20:
        dut.out_ready.value = 1
        if int(dut.out_valid.value):
            stream[(int(dut.out_population.value), int(dut.out_tick.value),
                    int(dut.out_index.value))] += 1
            idle = 0
        else:
            idle += 1
        await FallingEdge(dut.clk)
    wall = time.perf_counter() - t0
    report = {"cycles": cycles, "cycles_per_s": cycles / wall, "sweeps_checked": sweeps,
              "detector": det_chk.stats, "core": core_chk.stats.to_dict(),
              "link_events": sum(link.values()), "link_expected": sum(expect_link.values()),
              "stream_out": sum(stream.values()), "stream_expected": sum(expect_stream.values()),
              "afferent_spikes": sum(v for k, v in expect_stream.items() if k[0] == 0),
              "cuneate_spikes": sum(v for k, v in expect_stream.items() if k[0] == 1),
              "overrun_count": int(dut.overrun_count.value),
              "tick_count": int(dut.tick_count.value)}
    bench_report(report)
    fails = core_chk.failures() + det_chk.failures()
    if link != expect_link:
        fails.append(f"link: {sum((link - expect_link).values())} extra, "
                     f"{sum((expect_link - link).values())} missing events")
    if stream != expect_stream:
        fails.append(f"stream: {sum((stream - expect_stream).values())} extra, "
                     f"{sum((expect_stream - stream).values())} missing spikes")
    if int(dut.merged_count.value) or int(dut.cuneate_overflow_count.value) or \
            int(dut.afferent_overflow.value):
        fails.append("the detector merged events or an output FIFO overflowed")
    assert not fails, "; ".join(fails)
