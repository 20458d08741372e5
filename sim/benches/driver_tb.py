"""cocotb bench: play a host driver's write schedule into the generated core, record spikes.

Configured by the JSON in ``CUNEATE_BENCH_CONFIG`` (``core``: the core's keywords, ``ticks``:
sweeps to run, ``writes``: ``[tick, first, [raw, ...]]`` in tick order); reports to
``CUNEATE_BENCH_REPORT``. Protocol (shared with the Amaranth transport): for each tick ``k``,
the writes due at ``k`` go through the host-write port one word per cycle (sweep ``k - 1`` has
fully left the pipeline), then one ``tick`` pulse starts sweep ``k``; the bench waits for the
sweep to leave the pipeline, checks ``sweep_number``, adds ``sweep_count`` (the core's own
spike count) and the per-sweep clamp counters, and drains the spike FIFO (as deep as the core
has neurons), checking each spike's sweep tag. Between sweeps the clock runs but nothing is
issued, so a run equals the twin's sweep for sweep.
"""

from __future__ import annotations

import json
import os
import time

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

from cuneate.hdl.izhikevich import CLAMP_KINDS, PIPELINE_DEPTH, IzhikevichConfig


@cocotb.test()
async def play(dut):
    with open(os.environ["CUNEATE_BENCH_CONFIG"]) as f:
        cfgj = json.load(f)
    cfg = IzhikevichConfig.from_kwargs(cfgj["core"])
    N = cfg.n_neurons
    n_ticks = int(cfgj["ticks"])
    writes = cfgj["writes"]
    progress_file = cfgj.get("progress_file")
    d = dut
    cocotb.start_soon(Clock(d.clk, 10, unit="ns").start())
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
    wait = N + PIPELINE_DEPTH + 4
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
        if progress_file and (k + 1) % 1000 == 0:
            with open(progress_file, "w") as f:
                json.dump({"done": k + 1}, f)
    rep["overflow"] = int(d.spike_overflow.value)
    rep["overrun"] += int(d.overrun.value)
    rep["writes_left"] = len(writes) - w
    rep["wall_s"] = time.perf_counter() - t0
    with open(os.environ["CUNEATE_BENCH_REPORT"], "w") as f:
        json.dump(rep, f)
    assert rep["writes_left"] == 0, f"{rep['writes_left']} writes past the last tick"
    assert rep["sweep_tag_mismatches"] == 0, "spike sweep tags disagree with the sweep run"
