"""cocotb bench for the generated :class:`cuneate.hdl.network.AfferentCuneateNetwork` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG``; the report goes to
``CUNEATE_BENCH_REPORT``. Test ``engine``: per tick, wait until the network is idle, write the
host currents that change, pulse ``tick``; every cycle the output stream is read (``out_ready``
held high). The report holds the stream (population, tick modulo the tick width, index) and
the network's counters; the ``icarus``/``verilator`` engines of ``cuneate simulate network``.
"""

from __future__ import annotations

import json
import os
import time

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge


@cocotb.test()
async def engine(dut):
    with open(os.environ["CUNEATE_BENCH_CONFIG"]) as f:
        spec = json.load(f)
    n_ticks = spec["ticks"]
    writes = {int(k): v for k, v in spec["writes"].items()}
    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.rst.value = 1
    for s in (dut.tick, dut.i_wr_en, dut.i_wr_addr, dut.i_wr_data):
        s.value = 0
    dut.out_ready.value = 1
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
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
    with open(os.environ["CUNEATE_BENCH_REPORT"], "w") as f:
        json.dump({"stream": stream, "counters": counters, "cycles": cycles,
                   "cycles_per_s": cycles / (time.perf_counter() - t0)}, f)
    assert counters["tick_count"] == n_ticks
