"""cocotb benches for the generated :class:`cuneate.hdl.izhikevich.IzhikevichCore` Verilog.

The bench is configured by the JSON file named in ``CUNEATE_BENCH_CONFIG`` and writes its
figures to ``CUNEATE_BENCH_REPORT``. Two tests:

``scoreboard``
    Watches every cycle. Each update that leaves the pipeline is collected; when a sweep is
    complete it is checked by :class:`cuneate.sim.izhikevich.scoreboard.SweepChecker`: (a) the
    bit-exact
    twin advanced from the DUT's own previous state with the current the DUT reports it used,
    clamp flags included - zero mismatches allowed - and (b) the float64 golden Euler step from
    the same state, within the error bound derived from the formats, for every update no clamp
    touched (a flagged clamp is an expected deviation, counted). The current used must be the
    last one the host wrote (or, for a write in the cycle of the fetch, the one before). The
    spike stream, the per-sweep spike and clamp counters and the sticky clamp flags must agree
    with the updates; nothing may overflow or overrun. Currents are random in
    ``current_range`` (rewritten during sweeps), or, with ``flip_every``, held at the two ends
    of the range and flipped every ``flip_every`` sweeps (the full-scale extremes).
``engine``
    Writes the currents, drives external ticks and records the spike stream: the
    ``icarus``/``verilator`` engines of ``cuneate simulate``.
``play``
    Plays a host driver's write schedule (the ``icarus``/``verilator`` transports).
``array_check``
    The same per-update check for :class:`~cuneate.hdl.izhikevich.array.IzhikevichArray`
    (generated with its per-core probe ports): every update of every core against that core's
    twin and golden, the spike stream against the spiking updates as global ids, the summed
    ``sweep_count`` per sweep.
"""

from __future__ import annotations

import random
import time

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

from cuneate.hdl.izhikevich import CLAMP_KINDS, IzhikevichConfig
from cuneate.hdl.izhikevich.array import PROBES, core_configs
from cuneate.sim.engines.bench import CoreBench, bench_config, bench_progress, bench_report
from cuneate.sim.engines.waves import BENCH_CLOCK_NS
from cuneate.sim.izhikevich.scoreboard import SweepChecker


def make_config(core: dict) -> IzhikevichConfig:
    """The core configuration from its JSON form (:meth:`IzhikevichConfig.to_kwargs`)."""
    return IzhikevichConfig.from_kwargs(core)


@cocotb.test()
async def scoreboard(dut):
    cfgj = bench_config()
    cfg = make_config(cfgj["core"])
    N = cfg.n_neurons
    checker = SweepChecker(cfg)
    tb = CoreBench(dut, cfg, CLAMP_KINDS, {"v": lambda d: d.upd_v.value.to_signed(),
                                           "u": lambda d: d.upd_u.value.to_signed()})
    rng = random.Random(cfgj.get("seed", 1))
    n_sweeps = cfgj["sweeps"]
    lo, hi = cfgj.get("current_range", [0.0, 40.0])
    writes_per_sweep = cfgj.get("writes_per_sweep", 4)
    flip_every = cfgj.get("flip_every")
    await tb.start()

    async def driver():
        # initial currents, written while the first sweep is already running, then random
        # rewrites during the sweeps
        for n in range(N):
            await tb.write_current(n, cfg.I.to_raw(rng.uniform(lo, hi)))
        while True:
            if writes_per_sweep > 0 and rng.random() < writes_per_sweep / N:
                await tb.write_current(rng.randrange(N), cfg.I.to_raw(rng.uniform(lo, hi)))
            else:
                await FallingEdge(dut.clk)

    async def flipper():
        # full-scale extremes: neuron n starts at hi (even n) or lo (odd n); all flip to the
        # other end every flip_every sweeps
        level = [hi if n % 2 == 0 else lo for n in range(N)]
        for n in range(N):
            await tb.write_current(n, cfg.I.to_raw(level[n]))
        period = flip_every * cfg.cycles_per_tick
        while True:
            for _ in range(period - N):
                await FallingEdge(dut.clk)
            level = [hi if x == lo else lo for x in level]
            for n in range(N):
                await tb.write_current(n, cfg.I.to_raw(level[n]))

    cocotb.start_soon(flipper() if flip_every else driver())
    buf = tb.buf
    extra = {"stream_spikes": 0, "current_violations": 0}
    t0 = time.perf_counter()
    d = dut
    while checker.stats.sweeps_checked < n_sweeps:
        await FallingEdge(d.clk)
        tb.cycle += 1
        if not tb.sample():
            continue
        sweep_no = checker.stats.sweeps_checked        # sweeps are numbered from 0 after reset
        # ---- whole sweep collected: vectorized checks ----
        checker.check(buf["v"], buf["u"], buf["i"], buf["spike"], buf["clamp"])
        # currents used must be the ones the host wrote
        extra["current_violations"] += tb.current_violations(cfg.pipeline_stages)
        tb.expect_sweep(sweep_no, checker.stats.clamp_sticky)
    await tb.drain()
    elapsed = time.perf_counter() - t0
    extra.update(tb.mismatches())
    first = tb.expected_stream[0][1] if tb.expected_stream else 0
    stream_checked = [s for s in tb.stream if s[1] >= first][:len(tb.expected_stream)]
    extra["stream_spikes"] = len(stream_checked)
    extra["stream_matches"] = stream_checked == tb.expected_stream
    # a clear empties the sticky flags except for the clamp registered in the same cycle,
    # which must not be lost; afterwards they accumulate again
    pending = int(d.upd_clamp.value)
    d.clamp_clear.value = 1
    await FallingEdge(d.clk)
    d.clamp_clear.value = 0
    after_clear = int(d.clamp_flags.value)
    pending2 = pending | int(d.upd_clamp.value)
    await FallingEdge(d.clk)
    extra["clear_mismatches"] = int(after_clear != pending) + \
        int(int(d.clamp_flags.value) != pending2)
    stats = checker.stats.to_dict() | extra
    stats["overrun"] = int(d.overrun.value)
    stats["spike_overflow"] = int(d.spike_overflow.value)
    stats["cycles"] = tb.cycle
    stats["wall_s"] = elapsed
    stats["cycles_per_s"] = tb.cycle / elapsed if elapsed else None
    stats["bound_v_at_rest"] = float(cfg.one_step_bound(-65.0, -13.0, 0.0)[0])
    bench_report(stats)
    assert not checker.failures(), "; ".join(checker.failures())
    assert stats["current_violations"] == 0, "an update used a current the host never wrote"
    assert stats["count_mismatches"] == 0, "sweep_count disagrees with the updates"
    assert stats["clamp_counter_mismatches"] == 0, "per-sweep clamp counters disagree"
    assert stats["sticky_mismatches"] == 0, "sticky clamp flags disagree with the updates"
    assert stats["stream_matches"], "spike stream differs from the spiking updates"
    assert stats["overrun"] == 0 and stats["spike_overflow"] == 0


@cocotb.test()
async def engine(dut):
    """Run the core like a host would: set currents, tick, read the spike stream."""
    cfgj = bench_config()
    cfg = make_config(cfgj["core"])
    N = cfg.n_neurons
    tb = CoreBench(dut, cfg, CLAMP_KINDS, {})
    await tb.start()
    currents = cfgj["currents"]
    for n in range(N):
        await tb.write_current(n, cfg.I.to_raw(currents[n] if n < len(currents) else 0.0))
    n_sweeps = cfgj["sweeps"]
    period = cfgj.get("tick_period", N)
    d = dut
    spikes: list[list[int]] = [[] for _ in range(N)]
    width = cfg.sweep_number_width
    base, last_raw = 0, 0
    t0 = time.perf_counter()
    cycles = 0
    clamps = {k: 0 for k in CLAMP_KINDS}
    counters = {k: getattr(d, f"sweep_clamps_{k}") for k in CLAMP_KINDS}
    total = n_sweeps * period + cfg.pipeline_stages + cfg.spike_fifo_depth + 4
    swept = 0
    for c in range(total):
        d.tick.value = int(c % period == 0 and c // period < n_sweeps)
        await FallingEdge(d.clk)
        cycles += 1
        if int(d.sweep_done.value):
            for k in CLAMP_KINDS:
                clamps[k] += int(counters[k].value)
            swept += 1
            bench_progress(cfgj, swept)
        if int(d.spike_valid.value):
            raw = int(d.spike_sweep.value)
            if raw < last_raw:
                base += 1 << width          # sweep number wrapped
            last_raw = raw
            spikes[int(d.spike_index.value)].append(base + raw)
    elapsed = time.perf_counter() - t0
    sticky = int(d.clamp_flags.value)
    bench_report({"spike_sweeps": spikes, "cycles": cycles, "wall_s": elapsed,
             "overrun": int(d.overrun.value), "spike_overflow": int(d.spike_overflow.value),
             "clamp_counts": clamps,
             "clamp_sticky": {k: bool(sticky >> i & 1) for i, k in enumerate(CLAMP_KINDS)}})
    assert int(d.overrun.value) == 0 and int(d.spike_overflow.value) == 0


@cocotb.test()
async def play(dut):
    """Play a host driver's write schedule into the core and record its spikes (the
    ``icarus``/``verilator`` transports of the host driver). Configuration: ``core``, ``ticks``
    (sweeps to run), ``writes`` (``[tick, first, [raw, ...]]`` in tick order). For each tick
    ``k`` the writes due at ``k`` go through the host-write port one word per cycle (sweep
    ``k - 1`` has fully left the pipeline), then one ``tick`` pulse starts sweep ``k``; the
    bench waits for the sweep to leave the pipeline, checks ``sweep_number``, adds
    ``sweep_count`` (the core's own spike count) and the per-sweep clamp counters, and drains
    the spike FIFO, checking each spike's sweep tag (the protocol of the Amaranth transport)."""
    cfgj = bench_config()
    cfg = IzhikevichConfig.from_kwargs(cfgj["core"])
    N = cfg.n_neurons
    n_ticks = int(cfgj["ticks"])
    writes = cfgj["writes"]
    d = dut
    cocotb.start_soon(Clock(d.clk, BENCH_CLOCK_NS, unit="ns").start())
    d.rst.value = 1
    for s in (d.i_wr_en, d.sel_wr_en, d.i_wr_addr, d.i_wr_data, d.sel_wr_addr, d.sel_wr_data,
              d.clamp_clear, d.tick, d.spike_ready):
        s.value = 0
    await RisingEdge(d.clk)
    await RisingEdge(d.clk)
    await FallingEdge(d.clk)
    d.rst.value = 0
    await FallingEdge(d.clk)
    rep = {"writes": 0, "words": 0, "spikes_counted": 0, "overflow": 0, "overrun": 0,
           "sweeps": 0, "sweep_tag_mismatches": 0, "clamp_counts": {k: 0 for k in CLAMP_KINDS},
           "spike_tick": [], "spike_neuron": []}
    counters = {k: getattr(d, f"sweep_clamps_{k}") for k in CLAMP_KINDS}
    mask = (1 << cfg.sweep_number_width) - 1
    wait = N + cfg.pipeline_stages + 4
    w = 0
    t0 = time.perf_counter()
    for k in range(n_ticks):
        while w < len(writes) and writes[w][0] == k:
            _, first, raw = writes[w]
            for i, x in enumerate(raw):
                d.i_wr_addr.value = first + i
                d.i_wr_data.value = int(x)
                d.i_wr_en.value = 1
                await FallingEdge(d.clk)
            d.i_wr_en.value = 0
            rep["writes"] += 1
            rep["words"] += len(raw)
            w += 1
        if w < len(writes) and writes[w][0] < k:
            raise AssertionError(f"write schedule out of order at write {w}")
        d.tick.value = 1
        await FallingEdge(d.clk)
        d.tick.value = 0
        await ClockCycles(d.clk, wait, rising=False)
        rep["sweeps"] += 1
        if int(d.sweep_number.value) != k & mask:
            rep["overrun"] += 1
        rep["spikes_counted"] += int(d.sweep_count.value)
        for kk in CLAMP_KINDS:
            rep["clamp_counts"][kk] += int(counters[kk].value)
        if int(d.spike_valid.value):
            d.spike_ready.value = 1
            while int(d.spike_valid.value):
                rep["spike_neuron"].append(int(d.spike_index.value))
                rep["spike_tick"].append(k)
                if int(d.spike_sweep.value) != k & mask:
                    rep["sweep_tag_mismatches"] += 1
                await FallingEdge(d.clk)
            d.spike_ready.value = 0
        bench_progress(cfgj, k + 1)
    rep["overflow"] = int(d.spike_overflow.value)
    rep["overrun"] += int(d.overrun.value)
    rep["writes_left"] = len(writes) - w
    rep["wall_s"] = time.perf_counter() - t0
    bench_report(rep)
    assert rep["writes_left"] == 0, f"{rep['writes_left']} writes past the last tick"
    assert rep["sweep_tag_mismatches"] == 0, "spike sweep tags disagree with the sweep run"


@cocotb.test()
async def array_check(dut):
    """An array of ``cores`` cores: the host writes every global id, then rewrites random ones
    during the sweeps; each core's updates (its ``p<k>_*`` probes) are checked sweep by sweep by
    its own :class:`SweepChecker` (twin exact, golden bounded) and must have used a current the
    host wrote to that global id; the stream must carry every spike once as ``(k * N + n,
    sweep)``, each core's spikes in that core's order; ``sweep_count`` is the sum over the
    cores; nothing overruns or overflows. ``neuron_sets`` in the bench configuration: the
    array's per-neuron initial parameter sets (each core checked against its own)."""
    cfgj = bench_config()
    cfg = make_config(cfgj["core"])
    K, N = int(cfgj["cores"]), cfg.n_neurons
    d = dut
    cocotb.start_soon(Clock(d.clk, BENCH_CLOCK_NS, unit="ns").start())
    d.rst.value = 1
    for s in (d.i_wr_en, d.sel_wr_en, d.i_wr_addr, d.i_wr_data, d.sel_wr_addr, d.sel_wr_data,
              d.clamp_clear):
        s.value = 0
    d.spike_ready.value = 1
    if cfg.tick_source == "external":
        d.tick.value = 0
    await RisingEdge(d.clk)
    await RisingEdge(d.clk)
    await FallingEdge(d.clk)
    d.rst.value = 0
    rng = random.Random(cfgj.get("seed", 1))
    lo, hi = cfgj.get("current_range", [0.0, 40.0])
    rewrites = cfgj.get("writes_per_sweep", 4)
    written = {n: {0} for n in range(K * N)}          # the current RAMs start at zero

    async def driver():
        todo = list(range(K * N))
        while True:
            n = todo.pop(0) if todo else (rng.randrange(K * N)
                                          if rng.random() < rewrites / N else None)
            if n is not None:
                raw = cfg.I.to_raw(rng.uniform(lo, hi))
                written[n].add(int(raw))
                d.i_wr_addr.value, d.i_wr_data.value, d.i_wr_en.value = n, int(raw), 1
            await FallingEdge(d.clk)
            d.i_wr_en.value = 0

    cocotb.start_soon(driver())
    # each core checked against its own configuration (its neurons' own parameter sets when
    # the array was generated with per-neuron ``neuron_sets``)
    checkers = [SweepChecker(c) for c in core_configs(cfg, K, cfgj.get("neuron_sets"))]
    probes = [{n: getattr(d, f"p{k}_{n}") for n in PROBES} for k in range(K)]
    bufs = [{n: np.zeros(N, dtype=np.int64) for n in ("v", "u", "i", "spike", "clamp")}
            for _ in range(K)]
    fill = [0] * K
    spikes_per_sweep: dict[int, int] = {}
    expected, stream, done = [], [], []
    extra = {"order_errors": 0, "current_violations": 0}
    n_sweeps, cycles = cfgj["sweeps"], 0
    width = cfg.sweep_number_width
    t0 = time.perf_counter()

    def sample_stream():
        if int(d.spike_valid.value):
            stream.append((int(d.spike_index.value), int(d.spike_sweep.value)))
        if int(d.sweep_done.value):
            done.append((int(d.sweep_number.value), int(d.sweep_count.value)))

    while min(c.stats.sweeps_checked for c in checkers) < n_sweeps:
        await FallingEdge(d.clk)
        cycles += 1
        sample_stream()
        for k in range(K):
            p, b = probes[k], bufs[k]
            if not int(p["valid"].value):
                continue
            idx = int(p["index"].value)
            if idx != fill[k]:
                extra["order_errors"] += 1
                fill[k] = idx
            b["v"][idx], b["u"][idx] = p["v"].value.to_signed(), p["u"].value.to_signed()
            b["i"][idx] = p["current"].value.to_signed()
            b["spike"][idx], b["clamp"][idx] = int(p["spike"].value), int(p["clamp"].value)
            fill[k] = idx + 1
            if fill[k] < N:
                continue
            fill[k] = 0
            sweep = checkers[k].stats.sweeps_checked
            extra["current_violations"] += sum(int(b["i"][n]) not in written[k * N + n]
                                               for n in range(N))
            checkers[k].check(b["v"], b["u"], b["i"], b["spike"], b["clamp"])
            spk = np.flatnonzero(b["spike"])
            spikes_per_sweep[sweep] = spikes_per_sweep.get(sweep, 0) + len(spk)
            expected += [(k * N + int(n), sweep % (1 << width)) for n in spk]
    for _ in range(cfg.spike_fifo_depth * K + 4):
        await FallingEdge(d.clk)
        sample_stream()
    elapsed = time.perf_counter() - t0
    # the stream's spikes of the checked sweeps (a later sweep's spikes of a low-numbered core
    # may pass a high-numbered core's backlog: the arbitration favours the lower core)
    checked = {s % (1 << width) for s in range(n_sweeps)}
    got = [x for x in stream if x[1] in checked]
    extra["stream_matches"] = sorted(got, key=lambda x: (x[1], x[0])) == \
        sorted(expected, key=lambda x: (x[1], x[0]))
    extra["stream_core_order"] = all(
        [x for x in got if x[0] // N == k] == [x for x in expected if x[0] // N == k]
        for k in range(K))
    exp_done = [(s % (1 << width), spikes_per_sweep[s]) for s in range(n_sweeps)]
    extra["count_mismatches"] = sum(a != b for a, b in zip(done, exp_done)) + \
        max(0, n_sweeps - len(done))
    totals = [c.stats.to_dict() for c in checkers]
    stats = {k: sum(t[k] for t in totals) for k in
             ("sweeps_checked", "updates_checked", "twin_mismatches", "flag_mismatches",
              "golden_bound_violations", "spike_disagreements", "flagged_updates", "spikes")}
    stats["golden_v_max_ratio"] = max(t["golden_v_max_ratio"] for t in totals)
    stats |= extra | {"cores": K, "cycles": cycles, "wall_s": elapsed,
                      "overrun": int(d.overrun.value),
                      "spike_overflow": int(d.spike_overflow.value)}
    bench_report(stats)
    failures = [f"core {k}: {f}" for k, c in enumerate(checkers) for f in c.failures()]
    assert not failures, "; ".join(failures)
    assert extra["order_errors"] == 0, "a core's updates left out of index order"
    assert extra["current_violations"] == 0, "an update used a current the host never wrote"
    assert extra["stream_matches"] and extra["stream_core_order"], "spike stream differs"
    assert extra["count_mismatches"] == 0, "sweep_count differs from the cores' spikes"
    assert stats["overrun"] == 0 and stats["spike_overflow"] == 0
