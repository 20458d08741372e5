"""The link's frame executor: checked frames in, the payload's writes and the tick
generator's and counters' commands out (:class:`FrameExecutor`).

A ``WRITE`` for sweep ``tick`` waits until the block is between sweeps ``tick - 1`` and
``tick`` (``sweeps_started == tick``, no tick pending, the block not busy) and streams its
values to the payload, one a cycle from a register (a value the payload cannot take yet waits
there); ``writing`` holds the tick generator meanwhile, so the values are in effect exactly
from sweep ``tick``. A write whose sweep has started is refused (``count_late_writes``). A
``CONTROL`` pulses its command in the cycle it is taken. A frame is taken (``frame.ready``)
once acted on: its last value taken by the payload, or its command given.
"""

from __future__ import annotations

from amaranth import Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..lib.payload import write_layout
from .codec import OP_CLEAR_COUNTERS, OP_READ_COUNTERS, OP_START, OP_STEP, OP_STOP
from .config import LinkConfig
from .decoder import frame_layout, max_values

__all__ = ["FrameExecutor"]


class FrameExecutor(wiring.Component):
    """See the module docstring; ``value_*`` read the decoder's value RAM."""

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        super().__init__({
            "frame": In(stream.Signature(frame_layout(lcfg))),
            "value_addr": Out(range(max_values(lcfg))), "value_en": Out(1, init=1),
            "value_data": In(lcfg.current_width),
            "write": Out(stream.Signature(write_layout(lcfg.info))),
            "sweeps_started": In(32), "pending": In(1), "busy": In(1), "writing": Out(1),
            "start": Out(1), "stop": Out(1), "step": Out(1), "step_count": Out(32),
            "read_counters": Out(1), "clear_counters": Out(1), "count_late_writes": Out(1),
        })

    def commands(self) -> tuple:
        """Each control opcode and the strobe it pulses for the tick generator."""
        return ((OP_START, self.start), (OP_STOP, self.stop), (OP_STEP, self.step),
                (OP_READ_COUNTERS, self.read_counters), (OP_CLEAR_COUNTERS, self.clear_counters))

    def elaborate(self, platform):
        m = Module()
        f, w = self.frame.payload, self.write
        widx = Signal(range(max_values(self.lcfg) + 1))
        load = Signal()
        m.d.comb += self.value_addr.eq(widx)
        with m.If(load):
            m.d.sync += [w.valid.eq(1), w.payload.addr.eq(f.first + widx - 1),
                         w.payload.value.eq(self.value_data),
                         w.payload.last.eq(widx == f.count), widx.eq(widx + 1)]
        with m.Elif(w.ready):
            m.d.sync += w.valid.eq(0)
        m.d.comb += self.step_count.eq(f.arg)
        S = self.sweeps_started
        with m.FSM(name="exec_fsm") as fsm:
            with m.State("IDLE"):
                with m.If(self.frame.valid & f.write):
                    m.d.sync += widx.eq(0)
                    m.next = "WAIT"
                with m.Elif(self.frame.valid):
                    m.d.comb += self.frame.ready.eq(1)
                    with m.Switch(f.op):
                        for op, strobe in self.commands():
                            with m.Case(op):
                                m.d.comb += strobe.eq(1)
            with m.State("WAIT"):
                with m.If(S > f.tick):
                    m.d.comb += [self.count_late_writes.eq(1), self.frame.ready.eq(1)]
                    m.next = "IDLE"
                with m.Elif((S == f.tick) & ~self.busy & ~self.pending):
                    with m.If(f.count == 0):
                        m.d.comb += self.frame.ready.eq(1)
                        m.next = "IDLE"
                    with m.Else():
                        m.d.sync += widx.eq(1)
                        m.next = "WRITE"
            with m.State("WRITE"):
                # value_data holds value widx - 1 (read in the last cycle that advanced)
                m.d.comb += [self.writing.eq(1), load.eq(~w.valid | w.ready)]
                with m.If(load & (widx == f.count)):
                    m.next = "DRAIN"
            with m.State("DRAIN"):
                # the last value on offer: the frame is done when the payload takes it (the
                # tick may go meanwhile: the write lands before the next fetch)
                with m.If(w.ready):
                    m.d.comb += self.frame.ready.eq(1)
                    m.next = "IDLE"
        m.d.comb += self.value_en.eq(Mux(fsm.ongoing("WRITE"), load, 1))
        return m
