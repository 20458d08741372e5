"""cocotb bench for the generated :class:`cuneate.hdl.link.LinkedTop` Verilog.

A UART model (cocotbext-uart) plays the host: the test ``play`` sends each chunk of bytes given
in the configuration (hex strings, each followed by a gap in clock cycles) on ``rx`` at the
link's baud rate, records every byte the device sends on ``tx`` for ``total_cycles`` cycles, and
reports them (hex) with the cycle counts. With ``watch_writes`` it also reports every current
the link writes toward the core (``[neuron, raw unsigned]`` per cycle the link's ``i_wr_en`` is
set). The caller decodes the frames and checks them against the protocol model and the
bit-exact twin (tests/sim/link/test_cocotb.py).
"""

from __future__ import annotations


import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, ReadOnly, RisingEdge
from cocotbext.uart import UartSink, UartSource

from cuneate.sim.engines.bench import bench_config, bench_report

CLOCK_NS = 10


class LinkTB:
    """Clock, reset and the two UART ends of the host link."""

    def __init__(self, dut, clocks_per_bit: int):
        self.dut = dut
        baud = 1e9 / (CLOCK_NS * clocks_per_bit)
        self.source = UartSource(dut.rx, baud=baud, bits=8, stop_bits=1)
        self.sink = UartSink(dut.tx, baud=baud, bits=8, stop_bits=1)

    async def start(self):
        d = self.dut
        cocotb.start_soon(Clock(d.clk, CLOCK_NS, unit="ns").start())
        d.rst.value = 1
        await ClockCycles(d.clk, 3)
        d.rst.value = 0
        await RisingEdge(d.clk)


@cocotb.test()
async def play(dut):
    cfg = bench_config()
    tb = LinkTB(dut, cfg["clocks_per_bit"])
    await tb.start()
    received = bytearray()

    async def drain():
        while True:
            received.extend(await tb.sink.read())

    cocotb.start_soon(drain())
    writes = []

    async def watch_writes():
        # the link's write stream is registered: after each clock edge it holds the write the
        # core takes at the next one (a core takes every write offered); woken only when a
        # burst of writes starts. The payload packs the address and the value
        # (hdl.lib.payload.write_layout).
        valid, payload = dut.link.payload__write__valid, dut.link.payload__write__payload
        lay = cfg["write_layout"]
        aw, vo, vw = lay["addr_bits"], lay["value_offset"], lay["value_bits"]
        while True:
            await RisingEdge(valid)
            await ReadOnly()
            while int(valid.value):
                word = int(payload.value)
                writes.append([word & ((1 << aw) - 1), (word >> vo) & ((1 << vw) - 1)])
                await RisingEdge(dut.clk)
                await ReadOnly()

    if cfg.get("watch_writes"):
        cocotb.start_soon(watch_writes())
    cycles = 0
    for hexdata, gap in cfg["chunks"]:
        await tb.source.write(bytes.fromhex(hexdata))
        await tb.source.wait()
        await ClockCycles(dut.clk, gap)
    remaining = cfg["total_cycles"]
    await ClockCycles(dut.clk, remaining)
    received.extend(tb.sink.read_nowait())
    cycles += remaining
    bench_report({"received": bytes(received).hex(), "overflow_pin": int(dut.overflow.value),
             "running_pin": int(dut.running.value), "writes": writes})
