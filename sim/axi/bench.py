"""cocotb bench of a block behind a bus face (:class:`~cuneate.hdl.axi.AxiTop` or
:class:`~cuneate.hdl.wishbone.WishboneTop`), with the bus models of cocotbext-axi
(``AxiStreamSource`` on ``s_axis`` with random gaps, ``AxiStreamSink`` on ``m_axis`` with random
back-pressure, ``AxiLiteMaster`` on ``s_axil``) or cocotbext-wishbone (``WishboneMaster`` on
``wb``).

The test ``face`` plays the configuration's schedule as a host does: ``STEP`` up to each sweep
with writes, wait until that many sweep packets (TLAST) have come, send each write as a burst
and wait until it is taken, then ``STEP`` to the end. Then it checks the bus's refusals (a
write to a constant register, a beat out of range), reads ``CLAMP_FLAGS``, clears them over the
bus and reads them again, and reads every counter. It reports the packets (beats per sweep),
the register values and the responses; the caller compares them with the twin
(:mod:`cuneate.sim.axi.scoreboard`).
"""

from __future__ import annotations

import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, RisingEdge
from cocotbext.axi import (AxiLiteBus, AxiLiteMaster, AxiStreamBus, AxiStreamFrame,
                           AxiStreamSink, AxiStreamSource)
from cocotbext.wishbone.driver import WBOp, WishboneMaster

from cuneate.sim.engines.bench import bench_config, bench_report

CLOCK_NS = 10
#: cycles a Wishbone request may wait for its answer
ACK_PATIENCE = 64


def _pauses(rng: random.Random, p: float):
    """A pause pattern: each cycle paused with probability ``p``, in runs."""
    while True:
        yield rng.random() < p


class _Lite:
    """Registers over AXI4-Lite: ``(value, response)``."""

    def __init__(self, dut):
        self.bus = AxiLiteMaster(AxiLiteBus.from_prefix(dut, "s_axil"), dut.clk, dut.rst)

    async def write(self, addr: int, value: int) -> int:
        r = await self.bus.write(addr, int(value).to_bytes(4, "little"))
        return int(r.resp)

    async def read(self, addr: int) -> tuple[int, int]:
        r = await self.bus.read(addr, 4)
        return int.from_bytes(r.data, "little"), int(r.resp)


class _Wishbone:
    """Registers over Wishbone B4 pipelined (word addresses): ``(value, 0 ACK / 2 ERR)``."""

    def __init__(self, dut):
        names = {"cyc": "cyc", "stb": "stb", "we": "we", "adr": "adr", "datwr": "dat_w",
                 "datrd": "dat_r", "ack": "ack", "err": "err", "sel": "sel", "stall": "stall"}
        self.bus = WishboneMaster(dut, "wb", dut.clk, width=32, timeout=64,
                                  signals_dict=names)

    async def _op(self, addr: int, data=None):
        # an answer missing for ACK_PATIENCE cycles fails the test (never a hang)
        res = await self.bus.send_cycle([WBOp(addr >> 2, data, acktimeout=ACK_PATIENCE)])
        r = res[0]                       # ack: 1 ACK, 2 ERR, 3 RTY
        return (0 if r.datrd is None else int(r.datrd)), (0 if r.ack == 1 else 2)

    async def write(self, addr: int, value: int) -> int:
        return (await self._op(addr, int(value)))[1]

    async def read(self, addr: int) -> tuple[int, int]:
        return await self._op(addr)


@cocotb.test()
async def face(dut):
    cfg = bench_config()
    reg = cfg["registers"]
    cocotb.start_soon(Clock(dut.clk, CLOCK_NS, unit="ns").start())
    dut.rst.value = 1
    # the bus models set their outputs with immediate writes: made at time 0, Icarus 11 never
    # propagates those nets into the design (the Wishbone bridge saw its request as Z)
    await RisingEdge(dut.clk)
    bus = _Lite(dut) if cfg["face"] == "axi" else _Wishbone(dut)
    source = AxiStreamSource(AxiStreamBus.from_prefix(dut, "s_axis"), dut.clk, dut.rst,
                             byte_lanes=1)
    sink = AxiStreamSink(AxiStreamBus.from_prefix(dut, "m_axis"), dut.clk, dut.rst,
                         byte_lanes=1)
    rng = random.Random(cfg["seed"])
    source.set_pause_generator(_pauses(random.Random(rng.random()), cfg["gaps"]))
    sink.set_pause_generator(_pauses(random.Random(rng.random()), cfg["stalls"]))
    await ClockCycles(dut.clk, 4)
    dut.rst.value = 0
    await RisingEdge(dut.clk)
    packets = []

    async def receive():
        while True:
            f = await sink.recv(compact=False)
            users = f.tuser if isinstance(f.tuser, list) else [f.tuser] * len(f.tdata)
            packets.append([[int(d), int(u or 0)] for d, u in zip(f.tdata, users)])

    cocotb.start_soon(receive())

    async def stand_at(k: int):
        for _ in range(cfg["patience"]):
            if len(packets) >= k:
                return
            await RisingEdge(dut.clk)
        raise AssertionError(f"the device did not end sweep {k - 1} ({len(packets)} ended)")

    responses = {"id": await bus.read(reg["ID"])}
    at = 0
    for k, bursts in cfg["schedule"]:
        if k > at:
            assert await bus.write(reg["STEP"], k - at) == 0
            await stand_at(k)
            at = k
        for beats in bursts:
            await source.send(AxiStreamFrame(tdata=beats))
            await source.wait()
    if cfg["sweeps"] > at:
        assert await bus.write(reg["STEP"], cfg["sweeps"] - at) == 0
        await stand_at(cfg["sweeps"])
    # refusals, the clamp flags raised and cleared over the bus, the counters
    responses["write_to_const"] = await bus.write(reg["ID"], 0)
    responses["read_outside"] = (await bus.read(cfg["outside"]))[1]
    await source.send(AxiStreamFrame(tdata=[cfg["bad_beat"]]))
    await source.wait()
    await ClockCycles(dut.clk, 4)
    clamps = (await bus.read(reg["CLAMP_FLAGS"]))[0]
    assert await bus.write(reg["CONTROL"], 1 << 3) == 0
    cleared = (await bus.read(reg["CLAMP_FLAGS"]))[0]
    values = {name: (await bus.read(addr))[0] for name, addr in reg.items()}
    bench_report({"packets": packets, "responses": responses, "clamps": clamps,
                  "cleared": cleared, "registers": values})
