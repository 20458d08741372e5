"""cocotb bench of the simulated LiteX SoC (:mod:`cuneate.boards.litex_sim`): the test
``bridge`` clocks and resets the SoC, opens a pseudo-terminal (raw) and writes its name to the
configuration's ``pty_file``, then each bit time moves the bytes the host wrote on the
terminal into a cocotbext-uart ``UartSource`` on ``serial_rx`` and the bytes a ``UartSink``
read on ``serial_tx`` onto the terminal, until the host writes ``stop_file`` (or
``wall_s`` seconds pass: a failure). The host (LiteX's ``CommUART``) runs outside the
simulator; the bench reports the bytes each way and the cycles run.
"""

from __future__ import annotations

import os
import time
import tty
from pathlib import Path

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, RisingEdge, Timer
from cocotbext.uart import UartSink, UartSource

from cuneate.sim.engines.bench import bench_config, bench_report


@cocotb.test()
async def bridge(dut):
    cfg = bench_config()
    period, cpb = cfg["clock_ns"], cfg["clocks_per_bit"]
    cocotb.start_soon(Clock(dut.clk, period, unit="ns").start())
    dut.rst.value = 1
    dut.serial_rx.value = 1
    await RisingEdge(dut.clk)
    # made after the first edge: Icarus 11 ignores immediate writes at time 0
    baud = 1e9 / (period * cpb)
    source = UartSource(dut.serial_rx, baud=baud, bits=8, stop_bits=1)
    sink = UartSink(dut.serial_tx, baud=baud, bits=8, stop_bits=1)
    await ClockCycles(dut.clk, 4)
    dut.rst.value = 0
    await ClockCycles(dut.clk, 2 * cpb)
    master, slave = os.openpty()
    tty.setraw(slave)
    os.set_blocking(master, False)
    stop = Path(cfg["stop_file"])
    Path(cfg["pty_file"]).write_text(os.ttyname(slave) + "\n")
    to_soc = to_host = bits = 0
    end = time.monotonic() + cfg["wall_s"]
    bit = Timer(period * cpb, unit="ns")
    try:
        while not stop.exists():
            if time.monotonic() > end:
                raise AssertionError(f"the host did not finish in {cfg['wall_s']} s")
            try:
                data = os.read(master, 256)
            except BlockingIOError:
                data = b""
            if data:
                source.write_nowait(data)
                to_soc += len(data)
            if not sink.empty():
                back = sink.read_nowait()
                os.write(master, bytes(back))
                to_host += len(back)
            await bit
            bits += 1
    finally:
        os.close(master)
        os.close(slave)
    bench_report({"bytes_to_soc": to_soc, "bytes_to_host": to_host, "bits": bits,
                  "cycles": bits * cpb})
