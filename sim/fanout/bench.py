"""cocotb bench for the generated :class:`cuneate.hdl.fanout.ChannelFanout` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG`` (``fanout``: the configuration's
keywords, :meth:`~cuneate.hdl.fanout.FanoutConfig.to_kwargs`); figures go to
``CUNEATE_BENCH_REPORT``. Test ``scoreboard``: ``runs`` runs; before each, random channels are
written through the valid/ready handshake (random values, a share at the format's extremes so
that clamps act, idle cycles between writes); during some runs a second ``start`` (it must be
ignored and counted) and a channel write (it must be held until the run ends and reach only the
next run) are driven. Every cycle is watched; each run must write every afferent once, in
order, ``done`` with the last write, ``n_neurons + 5`` cycles after ``start``; its currents are
checked by :class:`~cuneate.sim.fanout.scoreboard.FanoutChecker` (twin exact, golden bounded);
at the end the run, overrun and clamp counters and the sticky clamp flags must equal what was
driven and what the twin counted.

``engine``: runs given raw channel samples (one list per run) and records the currents; the
``icarus``/``verilator`` engines of the block.
"""

from __future__ import annotations

import time

import cocotb
from cocotb.triggers import FallingEdge

from cuneate.hdl.fanout import LATENCY, FanoutConfig
from cuneate.sim.engines.bench import (bench_case, bench_config, bench_report, bench_verdict,
                                       start_in_reset)
from cuneate.sim.fanout.scoreboard import FanoutChecker


async def start_bench(dut):
    await start_in_reset(dut, (dut.ch_wr_valid, dut.ch_wr_addr, dut.ch_wr_data, dut.start,
                               dut.clamp_clear))


class Watch:
    """The fan-out's outputs, sampled once per cycle (after the falling edge)."""

    def __init__(self, dut):
        self.dut, self.cycles = dut, 0
        self.writes, self.done_at, self.done_count = [], [], 0

    async def cycle(self):
        await FallingEdge(self.dut.clk)
        self.cycles += 1
        d = self.dut
        if int(d.i_wr_en.value):
            self.writes.append((int(d.i_wr_addr.value), d.i_wr_data.value.to_signed()))
        if int(d.done.value):
            self.done_at.append(self.cycles)


async def write_channel(dut, watch, mem, c, raw, pending=None):
    """One channel write through the handshake; returns the cycles it waited for ready."""
    dut.ch_wr_valid.value, dut.ch_wr_addr.value, dut.ch_wr_data.value = 1, c, raw
    waited = 0
    while True:
        ready = int(dut.ch_wr_ready.value)
        await watch.cycle()
        if ready:
            break
        waited += 1
    dut.ch_wr_valid.value = 0
    mem[c] = raw
    return waited


@cocotb.test()
async def scoreboard(dut):
    spec, cfg, rng = bench_case("fanout", FanoutConfig.from_kwargs)
    N, C, S = cfg.n_neurons, cfg.n_channels, cfg.S
    checker = FanoutChecker(cfg)
    await start_bench(dut)
    watch = Watch(dut)
    mem = [0] * C
    overruns, held = 0, 0
    t0 = time.perf_counter()

    def sample():
        u = rng.random()
        if u < spec.get("extreme_p", 0.1):
            return rng.choice((S.min_raw, S.max_raw))
        return rng.randint(S.min_raw, S.max_raw) if u < 0.5 else rng.randint(-S.max_raw // 8,
                                                                             S.max_raw // 8)
    for k in range(spec["runs"]):
        chans = range(C) if k == 0 else rng.sample(range(C), rng.randint(0, C))
        for c in chans:
            await write_channel(dut, watch, mem, c, sample())
            for _ in range(rng.choice((0, 0, 1, 3))):
                await watch.cycle()
        snapshot = list(mem)
        first = len(watch.writes)
        dut.start.value = 1
        start_cycle = watch.cycles                # done comes N + LATENCY cycles later
        await watch.cycle()
        dut.start.value = 0
        if rng.random() < spec.get("disturb_p", 0.3):
            await watch.cycle()
            dut.start.value = 1                     # a start during the run: ignored, counted
            await watch.cycle()
            dut.start.value = 0
            overruns += 1
            c = rng.randrange(C)
            held += await write_channel(dut, watch, mem, c, sample())  # held to the run's end
        while len(watch.done_at) <= k:
            await watch.cycle()
            assert watch.cycles - start_cycle < N + 4 * LATENCY, "the run never ended"
        run = watch.writes[first:]
        assert [a for a, _ in run] == list(range(N)), (
            f"run {k}: afferents written {[a for a, _ in run][:8]}..., not 0 .. {N - 1} once")
        assert watch.done_at[k] - start_cycle == N + LATENCY, (
            f"run {k}: done {watch.done_at[k] - start_cycle} cycles after start, not "
            f"{N + LATENCY}")
        checker.check(snapshot, [v for _, v in run])
    await watch.cycle()
    wall = time.perf_counter() - t0
    st = checker.stats
    extra = []
    for name, want in (("run_count", spec["runs"]), ("overrun_count", overruns),
                       ("clamp_low_count", checker.twin.clamp_counts["current_low"]),
                       ("clamp_high_count", checker.twin.clamp_counts["current_high"]),
                       ("clamp_flags", checker.twin.clamp_sticky)):
        got = int(getattr(dut, name).value)
        if got != want:
            extra.append(f"{name} {got} != {want}")
    if overruns and not held:
        extra.append("no channel write was held during a run")
    bench_verdict(st | {"cycles": watch.cycles, "cycles_per_s": watch.cycles / wall,
                        "overruns": overruns, "held_cycles": held,
                        "clamp_counts": checker.twin.clamp_counts}, checker.failures() + extra)


@cocotb.test()
async def engine(dut):
    spec = bench_config()
    cfg = FanoutConfig.from_kwargs(spec["fanout"])
    await start_bench(dut)
    watch = Watch(dut)
    mem = [0] * cfg.n_channels
    out = []
    t0 = time.perf_counter()
    for k, samples in enumerate(spec["samples"]):
        for c, raw in enumerate(samples):
            if raw != mem[c]:
                await write_channel(dut, watch, mem, c, int(raw))
        first = len(watch.writes)
        dut.start.value = 1
        await watch.cycle()
        dut.start.value = 0
        while len(watch.done_at) <= k:
            await watch.cycle()
        out.append([v for _, v in watch.writes[first:]])
    await watch.cycle()
    bench_report({"currents": out, "cycles": watch.cycles, "wall_s": time.perf_counter() - t0,
                  "clamp_low_count": int(dut.clamp_low_count.value),
                  "clamp_high_count": int(dut.clamp_high_count.value),
                  "clamp_flags": int(dut.clamp_flags.value)})
