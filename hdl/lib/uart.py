"""8N1 UART receiver and transmitter with an integer clocks-per-bit divider.

``UartRx`` synchronises ``rx`` through two flip-flops, finds the start bit's falling edge,
samples every bit in its middle and checks the stop bit: a byte is presented for one cycle on
``valid``/``data``; a zero stop bit pulses ``frame_error`` instead (the byte is discarded).
``UartTx`` sends ``data`` when ``valid & ready`` (a stream sink), idle-high, LSB first.
"""

from __future__ import annotations

from amaranth import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["UartRx", "UartTx"]


class _Uart(wiring.Component):
    """One end of an 8N1 line at ``clocks_per_bit`` clocks per bit (at least 4)."""

    _members: dict = {}

    def __init__(self, clocks_per_bit: int):
        if clocks_per_bit < 4:
            raise ValueError(f"UART needs at least 4 clocks per bit, got {clocks_per_bit}")
        self.clocks_per_bit = int(clocks_per_bit)
        super().__init__(self._members)


class UartRx(_Uart):
    """Receiver: ``valid``/``data`` for one cycle per byte, ``frame_error`` on a zero stop
    bit."""

    _members = {"rx": In(1, init=1), "valid": Out(1), "data": Out(8), "frame_error": Out(1)}

    def elaborate(self, platform):
        m = Module()
        cpb = self.clocks_per_bit
        s1, s2 = Signal(init=1), Signal(init=1)
        m.d.sync += [s1.eq(self.rx), s2.eq(s1)]
        count = Signal(range(cpb + cpb // 2 + 1))
        bit = Signal(range(10))
        shreg = Signal(8)
        busy = Signal()
        m.d.sync += [self.valid.eq(0), self.frame_error.eq(0)]
        with m.If(~busy):
            with m.If(~s2):
                # first sample in the middle of data bit 0: 1.5 bits after the falling edge
                m.d.sync += [busy.eq(1), count.eq(cpb + cpb // 2 - 2), bit.eq(0)]
        with m.Elif(count != 0):
            m.d.sync += count.eq(count - 1)
        with m.Else():
            m.d.sync += [count.eq(cpb - 1), bit.eq(bit + 1)]
            with m.If(bit < 8):
                m.d.sync += shreg.eq((s2 << 7) | (shreg >> 1))
            with m.Else():
                m.d.sync += busy.eq(0)
                with m.If(s2):
                    m.d.sync += [self.valid.eq(1), self.data.eq(shreg)]
                with m.Else():
                    m.d.sync += self.frame_error.eq(1)
        return m


class UartTx(_Uart):
    """Transmitter: a stream sink (``valid``/``ready``/``data``), idle high, LSB first."""

    _members = {"tx": Out(1, init=1), "valid": In(1), "ready": Out(1), "data": In(8)}

    def elaborate(self, platform):
        m = Module()
        cpb = self.clocks_per_bit
        count = Signal(range(cpb))
        bits = Signal(range(11))
        shreg = Signal(10, init=0x3FF)
        m.d.comb += [self.ready.eq(bits == 0), self.tx.eq(shreg[0])]
        with m.If(bits == 0):
            with m.If(self.valid):
                m.d.sync += [shreg.eq((1 << 9) | (self.data << 1)), bits.eq(10),
                             count.eq(cpb - 1)]
        with m.Elif(count != 0):
            m.d.sync += count.eq(count - 1)
        with m.Else():
            m.d.sync += [shreg.eq((1 << 9) | (shreg >> 1)), bits.eq(bits - 1),
                         count.eq(cpb - 1)]
        return m
