"""cocotb benches for the generated :class:`cuneate.hdl.lif.LifCore` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG``; figures go to
``CUNEATE_BENCH_REPORT``. Two tests:

``scoreboard``
    Watches every cycle with external ticks every ``period`` cycles while the host rewrites
    currents at random (also during sweeps) and input spikes arrive at random between ticks.
    Every whole sweep of updates is checked by :class:`LifSweepChecker`: (a) the bit-exact
    twin from the DUT's own previous state, with the current the DUT reports it used and the
    input spikes driven before the sweep's tick - zero mismatches in ``v``, the refractory
    counter, the spike, the accumulated input and the clamp flags; (b) the float64 golden
    update from the same state within the derived one-step bound for every unflagged update.
    The current used must be one the host wrote; the spike stream, per-sweep spike and clamp
    counters and sticky flags must agree with the updates; ``in_merged`` must be set exactly
    when a source spiked twice within one tick. With ``weights_writable`` the host also
    rewrites weight rows between sweeps; the twin follows the same writes.
``engine``
    Runs the core like a host: per sweep, waits for the previous sweep to finish issuing,
    writes the currents that change, sends that sweep's input spikes, ticks; records the spike
    stream. The ``icarus``/``verilator`` engines of ``cuneate simulate lif``.
"""

from __future__ import annotations

import random
import time

import cocotb
import numpy as np
from cocotb.triggers import FallingEdge

from cuneate.hdl.lif import CLAMP_KINDS, PIPELINE_DEPTH, LifConfig, LifTwin
from cuneate.sim.engines.bench import (CoreBench, bench_config, bench_progress, bench_report,
                                        spikes_then_tick)
from cuneate.sim.lif.scoreboard import LifSweepChecker


@cocotb.test()
async def scoreboard(dut):
    cfgj = bench_config()
    cfg = LifConfig.from_kwargs(cfgj["core"])
    N, F = cfg.n_neurons, cfg.n_inputs
    checker = LifSweepChecker(cfg)
    tr_sigs = [getattr(dut, f"upd_{t.name}") for t in cfg.traces]
    tb = CoreBench(dut, cfg, CLAMP_KINDS, {
        "v": lambda d: d.upd_v.value.to_signed(),
        "ref": lambda d: int(d.upd_ref.value) if cfg.ref_bits else 0,
        "acc": lambda d: d.upd_acc.value.to_signed() if F else 0})
    rng = random.Random(cfgj.get("seed", 1))
    n_sweeps = cfgj["sweeps"]
    period = cfgj.get("period", N + 8)
    if cfg.weights_writable:
        assert period >= N + PIPELINE_DEPTH + 2, "period too short for weight writes"
    lo, hi = cfgj.get("current_range", [cfg.I.min_value, cfg.I.max_value])
    writes_per_sweep = cfgj.get("writes_per_sweep", 2)
    spike_p = cfgj.get("input_spike_p", 0.3)
    await tb.start([dut.tick] + ([dut.in_valid, dut.in_source] if F else []))
    d = dut
    for n in range(N):
        await tb.write_current(n, cfg.I.to_raw(rng.uniform(lo, hi)), count=True)
    # x of sweep k: the sources whose spikes were driven between tick k-1 and tick k
    x_of = [np.zeros(F, dtype=bool) for _ in range(n_sweeps + 2)]
    buf = tb.buf
    tr = np.zeros((len(cfg.traces), N), dtype=np.int64)
    extra = {"current_violations": 0}
    tick_no = 0
    t0 = time.perf_counter()
    phase = 0
    merged_expected = False
    # host weight-row writes land between sweeps (after the last write-back, before the tick)
    w_writes = [[] for _ in range(n_sweeps + 2)]
    wr_p = cfgj.get("weight_writes_per_sweep", 0.5) if cfg.weights_writable else 0.0
    while checker.stats["sweeps_checked"] < n_sweeps:
        # drive this cycle's inputs (after the falling edge)
        tick = phase == 0 and tick_no < n_sweeps + 1
        d.tick.value = int(tick)
        if tick:
            tick_no += 1
        d.i_wr_en.value = 0
        if F:
            d.in_valid.value = 0
        if cfg.weights_writable:
            d.w_wr_en.value = 0
        if wr_p and phase >= N + PIPELINE_DEPTH + 1 and rng.random() < wr_p:
            n = rng.randrange(N)
            row = [rng.randint(cfg.W.min_raw, cfg.W.max_raw) for _ in range(F)]
            d.w_wr_en.value = 1
            d.w_wr_addr.value = n
            d.w_wr_data.value = LifTwin.pack_weights(cfg, row)
            w_writes[tick_no].append((n, row))
        elif not tick and F and rng.random() < spike_p:
            s = rng.randrange(F)
            d.in_valid.value = 1
            d.in_source.value = s
            merged_expected |= bool(x_of[tick_no][s])
            x_of[tick_no][s] = True            # lands in the sweep of the next tick
        elif not tick and rng.random() < writes_per_sweep / period:
            tb.drive_write(rng.randrange(N), cfg.I.to_raw(rng.uniform(lo, hi)))
        await FallingEdge(d.clk)
        tb.cycle += 1
        phase = (phase + 1) % period
        full = tb.sample()
        if int(d.upd_valid.value):
            for j, sg in enumerate(tr_sigs):
                tr[j, int(d.upd_index.value)] = sg.value.to_signed()
        if not full:
            continue
        k = checker.stats["sweeps_checked"]
        for n, row in w_writes[k]:
            checker.twin.set_weights(n, row)
        checker.check(buf["v"], buf["ref"], buf["i"], buf["acc"], buf["spike"], buf["clamp"],
                      x_of[k] if F else None, tr)
        extra["current_violations"] += tb.current_violations(PIPELINE_DEPTH)
        tb.expect_sweep(k, checker.stats["clamp_sticky"])
    d.tick.value = 0
    d.i_wr_en.value = 0
    if F:
        d.in_valid.value = 0
    await tb.drain()
    elapsed = time.perf_counter() - t0
    extra.update(tb.mismatches())
    extra["stream_matches"] = tb.stream[:len(tb.expected_stream)] == tb.expected_stream
    extra["input_spikes"] = int(sum(x.sum() for x in x_of))
    extra["merged_expected"] = merged_expected
    extra["weight_writes"] = sum(len(w) for w in w_writes[:n_sweeps])
    extra["merged_flag"] = bool(int(d.in_merged.value)) if F else False
    stats = checker.stats | extra
    stats.update(overrun=int(d.overrun.value), spike_overflow=int(d.spike_overflow.value),
                 cycles=tb.cycle, wall_s=elapsed,
                 cycles_per_s=tb.cycle / elapsed if elapsed else None)
    bench_report(stats)
    assert not checker.failures(), "; ".join(checker.failures())
    assert stats["current_violations"] == 0
    assert stats["merged_flag"] == stats["merged_expected"], "in_merged flag disagrees"
    assert stats["count_mismatches"] == 0 and stats["clamp_counter_mismatches"] == 0
    assert stats["sticky_mismatches"] == 0 and stats["stream_matches"]
    assert stats["overrun"] == 0 and stats["spike_overflow"] == 0


@cocotb.test()
async def engine(dut):
    """Run a host program: ``program`` is a list of sweeps, each ``[currents or null,
    input sources]`` (currents: raw values for every neuron, written before that sweep's
    tick; null keeps the previous ones)."""
    cfgj = bench_config()
    cfg = LifConfig.from_kwargs(cfgj["core"])
    N = cfg.n_neurons
    tb = CoreBench(dut, cfg, CLAMP_KINDS, {})
    await tb.start([dut.tick] + ([dut.in_valid, dut.in_source] if cfg.n_inputs else []))
    d = dut
    spikes: list[list[int]] = [[] for _ in range(N)]
    width, base, last_raw = cfg.sweep_number_width, 0, 0
    clamps = {k: 0 for k in CLAMP_KINDS}
    counters = {k: getattr(d, f"sweep_clamps_{k}") for k in CLAMP_KINDS}
    program = cfgj["program"]
    t0 = time.perf_counter()
    cycles = 0

    def sample():
        nonlocal base, last_raw
        if int(d.sweep_done.value):
            for k in CLAMP_KINDS:
                clamps[k] += int(counters[k].value)
        if int(d.spike_valid.value):
            raw = int(d.spike_sweep.value)
            if raw < last_raw:
                base += 1 << width
            last_raw = raw
            spikes[int(d.spike_index.value)].append(base + raw)

    async def step():
        nonlocal cycles
        await FallingEdge(d.clk)
        cycles += 1
        sample()

    for k, (cur, sources) in enumerate(program):
        while int(d.busy.value):
            await step()
        if cur is not None:
            for n in range(N):
                d.i_wr_addr.value = n
                d.i_wr_data.value = int(cur[n])
                d.i_wr_en.value = 1
                await step()
            d.i_wr_en.value = 0
        await spikes_then_tick(d, sources, step, bool(cfg.n_inputs))
        bench_progress(cfgj, k + 1)
    for _ in range(N + PIPELINE_DEPTH + cfg.spike_fifo_depth + 4):
        await step()
    sticky = int(d.clamp_flags.value)
    bench_report({"spike_sweeps": spikes, "cycles": cycles, "wall_s": time.perf_counter() - t0,
             "overrun": int(d.overrun.value), "spike_overflow": int(d.spike_overflow.value),
             "clamp_counts": clamps,
             "clamp_sticky": {k: bool(sticky >> i & 1) for i, k in enumerate(CLAMP_KINDS)}})
    assert int(d.overrun.value) == 0 and int(d.spike_overflow.value) == 0
