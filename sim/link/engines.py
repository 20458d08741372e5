"""The host link's gateware behind a serial port: :class:`AmaranthSerial` runs
:class:`~cuneate.hdl.link.LinkedCore` in the Amaranth simulator and drives its ``rx`` pin and
reads its ``tx`` pin bit by bit (8N1 at the link's ``clocks_per_bit``), so that the host's
:class:`~cuneate.boards.uart.UartTransport` (and the host driver over it) talks to the very
gateware a board runs, cycle by cycle.

The simulation advances only when the host waits for an answer: ``read`` runs it a block of
cycles at a time until bytes arrive. ``silent`` tells the transport that nothing more will come
(nothing left to send, and no byte from the device for longer than a frame and a batch take),
so a lost answer is reported at once instead of after a wall-clock timeout. Line faults can be
injected in both directions (``corrupt`` on the device's bytes, ``corrupt_host`` on the
host's), as with :class:`~cuneate.boards.uart.ModelSerial`.
"""

from __future__ import annotations

from collections import deque

from amaranth.sim import Simulator

from ...hdl.link import LinkedCore
from ...hdl.link.codec import MAX_FRAME
from ..host.transport import SimulatedSerial

__all__ = ["AmaranthSerial"]

CLOCK_S = 1e-6


class AmaranthSerial(SimulatedSerial):
    """A serial port whose far end is the link gateware in the Amaranth simulator.

    Parameters
    ----------
    lcfg
        The link configuration (:class:`~cuneate.hdl.link.LinkConfig`).
    corrupt, corrupt_host
        Called on each chunk of bytes the device sends / the host writes (line faults).
    block_cycles
        Cycles simulated per step while the host waits.
    """

    def __init__(self, lcfg, corrupt=None, corrupt_host=None, block_cycles: int = 256):
        self.lcfg = lcfg
        self.corrupt, self.corrupt_host = corrupt, corrupt_host
        self.block_cycles = int(block_cycles)
        cpb = lcfg.clocks_per_bit
        #: cycles without a byte from the device after which it has nothing more to say
        self.quiet_cycles = 2 * (MAX_FRAME + 2) * 10 * cpb + \
            2 * lcfg.batch_sweeps * lcfg.core.cycles_per_tick
        self.dut = dut = LinkedCore(lcfg)
        self._out: deque[int] = deque()          # bytes still to drive onto rx
        self._rx = bytearray()                   # bytes decoded from tx, not yet read
        self._chunk = bytearray()                # bytes from tx since the last read
        self._cycle = 0
        self._quiet = 0
        self.is_open = True
        self.sim = sim = Simulator(dut)
        sim.add_clock(CLOCK_S)

        # plain loops of ticks (not ``tick().repeat``): the background testbenches are
        # dropped suspended when the port is, which an async generator would complain about
        async def ticks(ctx, n):
            for _ in range(n):
                await ctx.tick()

        async def host(ctx):
            ctx.set(dut.rx, 1)
            while True:
                if not self._out:
                    await ticks(ctx, 8)
                    continue
                b = self._out.popleft()
                for bit in [0] + [(b >> i) & 1 for i in range(8)] + [1]:
                    ctx.set(dut.rx, bit)
                    await ticks(ctx, cpb)

        async def device(ctx):
            while True:
                await ctx.negedge(dut.tx)
                await ticks(ctx, cpb // 2)
                b = 0
                for i in range(8):
                    await ticks(ctx, cpb)
                    b |= ctx.get(dut.tx) << i
                await ticks(ctx, cpb)
                if ctx.get(dut.tx):                      # a stop bit; else a broken byte
                    self._chunk.append(b)

        sim.add_testbench(host, background=True)
        sim.add_testbench(device, background=True)

    def _advance(self, cycles: int):
        self._cycle += cycles
        self.sim.run_until(self._cycle * CLOCK_S)
        if self._chunk:
            data, self._chunk = bytes(self._chunk), bytearray()
            self._rx += self.corrupt(data) if self.corrupt is not None else data
            self._quiet = 0
        else:
            self._quiet += cycles

    # -- the serial port ---------------------------------------------------------------------
    def write(self, data: bytes) -> int:
        n = len(data)
        if self.corrupt_host is not None:
            data = self.corrupt_host(bytes(data))
        self._out.extend(bytes(data))
        self._quiet = 0
        return n

    def _fill(self) -> None:
        self._advance(self.block_cycles)

    @property
    def silent(self) -> bool:
        """Nothing left to send and no byte from the device for :attr:`quiet_cycles`."""
        return not self._rx and not self._out and self._quiet >= self.quiet_cycles

    @property
    def cycles(self) -> int:
        """Clock cycles simulated so far."""
        return self._cycle

    def close(self):
        self.is_open = False
