"""The link's 8N1 UART at a board's slow line rate: 115200 baud from the ULX3S's 60 MHz is 521
clocks a bit (the rate 0.03 % slow). The receiver takes bytes from a sender whose bit time is
off by twice the most a board plan accepts (``MAX_BAUD_ERROR`` at each end, opposite ways),
and the transmitter's bits last exactly its clocks per bit."""

import pytest
from amaranth import Module
from amaranth.sim import Simulator

from cuneate.boards.top import MAX_BAUD_ERROR, ClockPlan
from cuneate.hdl.lib.config import ConfigError
from cuneate.hdl.lib.uart import UartRx, UartTx

CPB = ClockPlan(osc_hz=25e6, clock_hz=60e6, update_hz=16e3, baud=115_200).clocks_per_bit
BYTES = [0x00, 0xFF, 0x55, 0xA6, 0x01, 0x80]


def test_115200_baud_at_60_mhz_is_521_clocks_a_bit():
    plan = ClockPlan(osc_hz=25e6, clock_hz=60e6, update_hz=16e3, baud=115_200)
    assert CPB == plan.clocks_per_bit == 521
    assert round(plan.line_baud) == 115_163 and round(plan.baud_error, 6) == 0.00032


def test_a_rate_the_uart_cannot_sample_is_refused():
    """20 Mbaud divides 60 MHz exactly, in 3 clocks a bit: too few to sample a bit's middle."""
    with pytest.raises(ConfigError, match=r"60 MHz gives 3 clocks per bit at 2e\+07 baud: the "
                                          r"UART needs at least 4 \(baud limit\)"):
        ClockPlan(osc_hz=25e6, clock_hz=60e6, update_hz=16e3, baud=20e6)


# both ends off by the most a plan accepts, in opposite directions (the FT231X's own divider
# error stands in for the far end's)
@pytest.mark.parametrize("skew", [-2 * MAX_BAUD_ERROR, 0.0, 2 * MAX_BAUD_ERROR],
                         ids=["sender-fast", "exact", "sender-slow"])
def test_the_receiver_takes_bytes_from_a_sender_off_by_both_ends_accepted_error(skew):
    rx = UartRx(CPB)
    bit = round(CPB * (1 + skew))          # the sender's bit time in our clocks
    got, errors = [], []

    async def sender(ctx):
        ctx.set(rx.rx, 1)
        await ctx.tick().repeat(3 * CPB)
        for b in BYTES:
            for level in [0] + [(b >> i) & 1 for i in range(8)] + [1]:
                ctx.set(rx.rx, level)
                await ctx.tick().repeat(bit)
        await ctx.tick().repeat(3 * CPB)

    async def monitor(ctx):
        async for clk_edge, rst, valid, data, ferr in ctx.tick().sample(rx.valid, rx.data,
                                                                         rx.frame_error):
            if valid:
                got.append(data)
            if ferr:
                errors.append(len(got))

    sim = Simulator(rx)
    sim.add_clock(1 / 60e6)
    sim.add_testbench(sender)
    sim.add_process(monitor)
    sim.run()
    assert got == BYTES and errors == []


def test_the_transmitters_bits_last_its_clocks_per_bit():
    m = Module()
    m.submodules.tx = tx = UartTx(CPB)
    edges = []

    async def bench(ctx):
        ctx.set(tx.data, 0x55)                 # 0 1 0 1 ...: every bit boundary an edge
        ctx.set(tx.valid, 1)
        await ctx.tick()
        ctx.set(tx.valid, 0)
        last = 1
        for n in range(11 * CPB):             # n: clocks since the byte was taken
            level = ctx.get(tx.tx)
            if level != last:
                edges.append(n)
                last = level
            await ctx.tick()

    sim = Simulator(m)
    sim.add_clock(1 / 60e6)
    sim.add_testbench(bench)
    sim.run()
    # start bit, then 0x55 LSB first (1 0 1 0 1 0 1 0), then the stop bit: ten edges a bit apart
    assert len(edges) == 10
    assert {b - a for a, b in zip(edges, edges[1:])} == {CPB}
