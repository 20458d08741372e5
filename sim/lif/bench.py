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
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge

from cuneate.hdl.lif import CLAMP_KINDS, PIPELINE_DEPTH, LifConfig, LifTwin
from cuneate.sim.engines.cocotb import bench_config, bench_progress, bench_report
from cuneate.sim.lif.scoreboard import LifSweepChecker


class TB:
    """Clock, reset and host drivers (current writes, input spikes, ticks)."""

    def __init__(self, dut, cfg: LifConfig):
        self.dut, self.cfg = dut, cfg
        self.cycle = 0
        self.writes: dict[int, list[tuple[int, int]]] = {}

    async def start(self):
        cocotb.start_soon(Clock(self.dut.clk, 10, unit="ns").start())
        d = self.dut
        d.rst.value = 1
        for s in (d.i_wr_en, d.sel_wr_en, d.i_wr_addr, d.i_wr_data, d.sel_wr_addr,
                  d.sel_wr_data, d.clamp_clear, d.tick):
            s.value = 0
        if self.cfg.n_inputs:
            d.in_valid.value = 0
            d.in_source.value = 0
        d.spike_ready.value = 1
        await RisingEdge(d.clk)
        await RisingEdge(d.clk)
        await FallingEdge(d.clk)
        d.rst.value = 0

    async def write_current(self, neuron: int, raw: int):
        d = self.dut
        d.i_wr_addr.value = neuron
        d.i_wr_data.value = int(raw)
        d.i_wr_en.value = 1
        self.writes.setdefault(neuron, []).append((self.cycle, int(raw)))
        await FallingEdge(d.clk)
        self.cycle += 1
        d.i_wr_en.value = 0

    def allowed_currents(self, neuron: int, fetch_cycle: int) -> set[int]:
        hist = self.writes.get(neuron, [])
        before = [raw for c, raw in hist if c < fetch_cycle - 2]
        near = [raw for c, raw in hist if fetch_cycle - 2 <= c <= fetch_cycle + 2]
        return {before[-1] if before else 0, *near}


@cocotb.test()
async def scoreboard(dut):
    cfgj = bench_config()
    cfg = LifConfig.from_kwargs(cfgj["core"])
    N, F = cfg.n_neurons, cfg.n_inputs
    checker = LifSweepChecker(cfg)
    tb = TB(dut, cfg)
    rng = random.Random(cfgj.get("seed", 1))
    n_sweeps = cfgj["sweeps"]
    period = cfgj.get("period", N + 8)
    if cfg.weights_writable:
        assert period >= N + PIPELINE_DEPTH + 2, "period too short for weight writes"
    lo, hi = cfgj.get("current_range", [cfg.I.min_value, cfg.I.max_value])
    writes_per_sweep = cfgj.get("writes_per_sweep", 2)
    spike_p = cfgj.get("input_spike_p", 0.3)
    await tb.start()
    d = dut
    for n in range(N):
        await tb.write_current(n, cfg.I.to_raw(rng.uniform(lo, hi)))
    # x of sweep k: the sources whose spikes were driven between tick k-1 and tick k
    x_of = [np.zeros(F, dtype=bool) for _ in range(n_sweeps + 2)]
    buf = {k: np.zeros(N, dtype=np.int64) for k in ("v", "ref", "i", "acc", "spike", "clamp",
                                                     "cycle")}
    buf["tr"] = np.zeros((len(cfg.traces), N), dtype=np.int64)
    tr_sigs = [getattr(dut, f"upd_{t.name}") for t in cfg.traces]
    extra = {"current_violations": 0, "count_mismatches": 0, "clamp_counter_mismatches": 0,
             "sticky_mismatches": 0}
    stream, expected_stream, done, expected_done = [], [], [], []
    counters = [getattr(d, f"sweep_clamps_{k}") for k in CLAMP_KINDS]
    sticky_seen, sticky_due = 0, False
    tick_no = 0
    fill = 0
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
            n = rng.randrange(N)
            raw = cfg.I.to_raw(rng.uniform(lo, hi))
            d.i_wr_addr.value = n
            d.i_wr_data.value = int(raw)
            d.i_wr_en.value = 1
            tb.writes.setdefault(n, []).append((tb.cycle, int(raw)))
        await FallingEdge(d.clk)
        tb.cycle += 1
        phase = (phase + 1) % period
        if sticky_due:
            sticky_due = False
            if int(d.clamp_flags.value) != sticky_seen:
                extra["sticky_mismatches"] += 1
        if int(d.spike_valid.value):
            stream.append((int(d.spike_index.value), int(d.spike_sweep.value)))
        if int(d.sweep_done.value):
            done.append((int(d.sweep_number.value), int(d.sweep_count.value),
                         *(int(c.value) for c in counters)))
        if not int(d.upd_valid.value):
            continue
        idx = int(d.upd_index.value)
        if idx == 0:
            fill = 0
        assert idx == fill, f"update order broken: expected {fill}, got {idx}"
        buf["v"][idx] = d.upd_v.value.to_signed()
        buf["ref"][idx] = int(d.upd_ref.value) if cfg.ref_bits else 0
        buf["i"][idx] = d.upd_current.value.to_signed()
        buf["acc"][idx] = d.upd_acc.value.to_signed() if F else 0
        buf["spike"][idx] = int(d.upd_spike.value)
        buf["clamp"][idx] = int(d.upd_clamp.value)
        buf["cycle"][idx] = tb.cycle
        for j, sg in enumerate(tr_sigs):
            buf["tr"][j, idx] = sg.value.to_signed()
        fill += 1
        if idx != N - 1:
            continue
        k = checker.stats["sweeps_checked"]
        for n, row in w_writes[k]:
            checker.twin.set_weights(n, row)
        checker.check(buf["v"], buf["ref"], buf["i"], buf["acc"], buf["spike"], buf["clamp"],
                      x_of[k] if F else None, buf["tr"])
        for n in range(N):
            if int(buf["i"][n]) not in tb.allowed_currents(n, int(buf["cycle"][n])
                                                           - PIPELINE_DEPTH):
                extra["current_violations"] += 1
        spk = buf["spike"].astype(bool)
        sums = [int(((buf["clamp"] >> b) & 1).sum()) for b in range(len(CLAMP_KINDS))]
        expected_done.append((k % (1 << cfg.sweep_number_width), int(spk.sum()), *sums))
        expected_stream += [(int(n), k) for n in np.flatnonzero(spk)]
        sticky_seen |= checker.stats["clamp_sticky"]
        sticky_due = True
    d.tick.value = 0
    d.i_wr_en.value = 0
    if F:
        d.in_valid.value = 0
    for _ in range(cfg.spike_fifo_depth + 4):
        await FallingEdge(d.clk)
        if int(d.spike_valid.value):
            stream.append((int(d.spike_index.value), int(d.spike_sweep.value)))
        if int(d.sweep_done.value):
            done.append((int(d.sweep_number.value), int(d.sweep_count.value),
                         *(int(c.value) for c in counters)))
    elapsed = time.perf_counter() - t0
    extra["count_mismatches"] = sum(a[:2] != b[:2] for a, b in zip(done, expected_done)) + \
        max(0, len(expected_done) - len(done))
    extra["clamp_counter_mismatches"] = sum(a[2:] != b[2:] for a, b in zip(done, expected_done))
    extra["stream_matches"] = stream[:len(expected_stream)] == expected_stream
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
    tb = TB(dut, cfg)
    await tb.start()
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
        for s in sources:
            d.in_valid.value = 1
            d.in_source.value = int(s)
            await step()
        if cfg.n_inputs:
            d.in_valid.value = 0
        d.tick.value = 1
        await step()
        d.tick.value = 0
        if (k + 1) % 1000 == 0:
            bench_progress(cfgj, k + 1)
    for _ in range(N + PIPELINE_DEPTH + cfg.spike_fifo_depth + 4):
        await step()
    sticky = int(d.clamp_flags.value)
    bench_report({"spike_sweeps": spikes, "cycles": cycles, "wall_s": time.perf_counter() - t0,
             "overrun": int(d.overrun.value), "spike_overflow": int(d.spike_overflow.value),
             "clamp_counts": clamps,
             "clamp_sticky": {k: bool(sticky >> i & 1) for i, k in enumerate(CLAMP_KINDS)}})
    assert int(d.overrun.value) == 0 and int(d.spike_overflow.value) == 0
