"""cocotb bench for :class:`cuneate.hdl.lib.smoke.SmokeCounter` (toolchain smoke test)."""

import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from cuneate.hdl.lib.smoke import smoke_reference
from cuneate.sim.engines.bench import bench_config, bench_report


@cocotb.test()
async def counter_matches_reference(dut):
    cfg = bench_config()
    width, n = cfg["width"], cfg["cycles"]
    rng = random.Random(cfg.get("seed", 1))
    enables = [rng.random() < 0.7 for _ in range(n)]
    steps = [rng.randrange(1 << width) for _ in range(n)]
    expected = smoke_reference(width, enables, steps)

    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.rst.value = 1
    dut.en.value = 0
    dut.step.value = 0
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    dut.rst.value = 0
    seen = []
    for i in range(n):
        dut.en.value = int(enables[i])
        dut.step.value = steps[i]
        await RisingEdge(dut.clk)
        await ReadOnly()
        count = int(dut.count.value)
        assert int(dut.is_zero.value) == int(count == 0)
        seen.append(count)
        await FallingEdge(dut.clk)
    mismatches = [i for i, (a, b) in enumerate(zip(seen, expected)) if a != b]
    bench_report({"cycles": n, "mismatches": len(mismatches)})
    assert not mismatches, f"first mismatch at cycle {mismatches[0]}"
