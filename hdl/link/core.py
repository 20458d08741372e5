"""The UART face: the host link gateware (:class:`HostLink`) and a block behind it
(:class:`LinkedTop`, the board top of every block).

The host link serves any payload (:mod:`cuneate.hdl.lib.payload`): framed writes in, spike
batches and counters out, over a UART, in the wire format of :mod:`cuneate.hdl.link.codec`
(its functions are the model: the CRC step is the same function in RTL and host, the COBS
encoder scans as the model does). It is a chain of stream components, one module each:

receive
    UART -> buffer (``rx_fifo_depth`` bytes; a byte arriving when it is full is dropped and
    counted ``rx_overflows``) -> :class:`~cuneate.hdl.link.decoder.FrameDecoder` (COBS, CRC-32,
    the checks in order) -> :class:`~cuneate.hdl.link.executor.FrameExecutor` (a ``WRITE`` in
    effect exactly from its sweep, the tick held while it writes; ``CONTROL`` commands) -> the
    payload's ``write`` stream; the buffer holds further bytes meanwhile (back-pressure).
ticks
    :class:`~cuneate.hdl.lib.tick.TickGenerator`: free running (``OP_START``), ``arg`` sweeps
    (``OP_STEP``) or stopped (``OP_STOP``, after reset); held while the payload is ``busy``
    or the executor writes; a tick lost is counted (``tick_overruns``).
transmit
    the payload's ``spikes`` -> :class:`~cuneate.hdl.link.batcher.SpikeBatcher` (ping-pong
    batches of ``batch_sweeps`` sweeps) -> :class:`~cuneate.hdl.link.encoder.FrameEncoder`
    (``SPIKES`` and ``COUNTERS`` frames, CRC-32, COBS) -> a small buffer -> UART.

Counters (:class:`~cuneate.hdl.lib.counters.CounterBank`, ``counter_width`` bits, saturating,
never wrapping): :data:`~cuneate.hdl.link.codec.COUNTER_NAMES`.
"""

from __future__ import annotations

from amaranth import Cat, Const, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from ..flow.verilog import verilog_text
from ..lib.counters import CounterBank
from ..lib.payload import payload_signature
from ..lib.tick import TickGenerator
from ..lib.uart import UartRx, UartTx
from .batcher import SpikeBatcher
from .codec import COUNTER_NAMES
from .config import LinkConfig
from .decoder import VERDICTS, FrameDecoder
from .encoder import FrameEncoder
from .executor import FrameExecutor

__all__ = ["HostLink", "LinkedTop", "link_verilog"]


class HostLink(wiring.Component):
    """The UART face (see the module docstring): the pins ``rx`` and ``tx``, the payload it
    serves (``payload``, the flipped :func:`~cuneate.hdl.lib.payload.payload_signature` of
    ``lcfg.info``) and ``running`` (ticks are due). Its parts are stream components, each
    its own module: :class:`~cuneate.hdl.link.decoder.FrameDecoder`,
    :class:`~cuneate.hdl.link.executor.FrameExecutor`,
    :class:`~cuneate.hdl.link.batcher.SpikeBatcher`,
    :class:`~cuneate.hdl.link.encoder.FrameEncoder`, with the
    :class:`~cuneate.hdl.lib.tick.TickGenerator` and a
    :class:`~cuneate.hdl.lib.counters.CounterBank`; after elaboration they are the
    attributes ``decoder``, ``executor``, ``batcher``, ``encoder``, ``ticks`` and
    ``counters``."""

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        super().__init__({"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1),
                          "payload": In(payload_signature(lcfg.info))})

    def elaborate(self, platform):
        lc = self.lcfg
        m = Module()
        p = self.payload
        m.submodules.uart_rx = urx = UartRx(lc.clocks_per_bit)
        m.submodules.uart_tx = utx = UartTx(lc.clocks_per_bit)
        m.submodules.rx_fifo = rx_store = SyncFIFOBuffered(width=8, depth=lc.rx_fifo_depth)
        # a two-entry register FIFO after the receive buffer: the decoder reads registers, not
        # the block RAM's output (its clock-to-output would start the decoder's paths)
        m.submodules.rx_head = rxf = SyncFIFOBuffered(width=8, depth=2)
        m.submodules.tx_fifo = txf = SyncFIFOBuffered(width=8, depth=lc.tx_fifo_depth)
        m.submodules.decoder = self.decoder = dec = FrameDecoder(lc)
        m.submodules.executor = self.executor = exe = FrameExecutor(lc)
        m.submodules.batcher = self.batcher = bat = SpikeBatcher(lc)
        m.submodules.encoder = self.encoder = enc = FrameEncoder(lc)
        m.submodules.ticks = self.ticks = tg = TickGenerator(lc.info.cycles_per_tick)
        m.submodules.counters = self.counters = ctr = CounterBank(COUNTER_NAMES,
                                                                   lc.counter_width)

        def inc(name):
            return getattr(ctr, f"inc_{name}")

        # --- receive: UART -> buffer -> head -> decoder -> executor -> the payload's writes
        m.d.comb += [
            urx.rx.eq(self.rx),
            rx_store.w_data.eq(urx.data), rx_store.w_en.eq(urx.valid),
            inc("rx_overflows").eq(urx.valid & ~rx_store.w_rdy),
            rxf.w_data.eq(rx_store.r_data), rxf.w_en.eq(rx_store.r_rdy),
            rx_store.r_en.eq(rxf.w_rdy),
            dec.bytes.valid.eq(rxf.r_rdy), dec.bytes.payload.eq(rxf.r_data),
            rxf.r_en.eq(dec.bytes.ready),
            inc("framing_errors").eq(dec.count_framing_errors + urx.frame_error),
            inc("seq_gaps").eq(dec.seq_gap),
            dec.value_addr.eq(exe.value_addr), dec.value_en.eq(exe.value_en),
            exe.value_data.eq(dec.value_data),
            p.write.valid.eq(exe.write.valid), p.write.payload.eq(exe.write.payload),
            exe.write.ready.eq(p.write.ready),
            exe.sweeps_started.eq(tg.sweeps_started), exe.pending.eq(tg.pending),
            exe.busy.eq(p.busy),
            inc("late_writes").eq(exe.count_late_writes), ctr.clear.eq(exe.clear_counters),
        ]
        m.d.comb += [inc(v).eq(getattr(dec, f"count_{v}")) for v in VERDICTS
                     if v != "framing_errors"]
        wiring.connect(m, dec.frame, exe.frame)
        # --- ticks: held while the block is busy or the executor writes into it
        m.d.comb += [
            tg.hold.eq(p.busy | exe.writing), tg.start.eq(exe.start), tg.stop.eq(exe.stop),
            tg.step.eq(exe.step), tg.step_count.eq(exe.step_count),
            p.tick.eq(tg.tick), self.running.eq(tg.running),
            inc("tick_overruns").eq(tg.overrun),
        ]
        # --- transmit: the payload's spikes -> batcher -> encoder -> buffer -> UART
        m.d.comb += [
            bat.spikes.valid.eq(p.spikes.valid), bat.spikes.payload.eq(p.spikes.payload),
            p.spikes.ready.eq(bat.spikes.ready),
            bat.sweep_done.eq(p.sweep_done), bat.free.eq(tg.free), bat.steps.eq(tg.steps),
            bat.pending.eq(tg.pending), bat.sweeps_started.eq(tg.sweeps_started),
            bat.spike_addr.eq(enc.spike_addr), enc.spike_data.eq(bat.spike_data),
            inc("spikes_dropped").eq(bat.count_spikes_dropped),
            inc("batches_dropped").eq(bat.count_batches_dropped),
            enc.read_counters.eq(exe.read_counters),
            enc.counters.eq(Cat(*[Cat(getattr(ctr, f"count_{n}"),
                                      Const(0, 32 - lc.counter_width))
                                  for n in COUNTER_NAMES])),
            enc.sweeps_started.eq(tg.sweeps_started),
            p.clamp_clear.eq(0),
        ]
        wiring.connect(m, bat.batch, enc.batch)
        # room for a byte, registered (the encoder offers a byte every two cycles at most, so
        # a margin of two entries covers the cycle of latency)
        room = Signal()
        m.d.sync += room.eq(txf.w_level < lc.tx_fifo_depth - 2)
        m.d.comb += [
            txf.w_data.eq(enc.bytes.payload), txf.w_en.eq(enc.bytes.valid & room),
            enc.bytes.ready.eq(room),
            utx.data.eq(txf.r_data), utx.valid.eq(txf.r_rdy), txf.r_en.eq(utx.ready),
            self.tx.eq(utx.tx),
        ]
        return m


class LinkedTop(wiring.Component):
    """A block behind the UART face: the board top of every block, for every board. The pins
    are ``rx`` and ``tx``; status outputs for LEDs: ``running``, ``overflow`` (the block dropped
    a spike or a tick overran: impossible while the link paces the ticks) and ``clamped`` (a
    clamp acted, sticky). The parts are the attributes ``link`` (:class:`HostLink`) and
    ``payload`` (the block's payload component, ``lcfg.payload.build()``)."""

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        super().__init__({"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1),
                          "overflow": Out(1), "clamped": Out(1)})
        # built here so that a simulation can watch the block
        self.payload = lcfg.payload.build()
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        m = Module()
        m.submodules.payload = pay = self.payload
        m.submodules.link = link = self.link
        wiring.connect(m, link.payload, pay)
        m.d.comb += [link.rx.eq(self.rx), self.tx.eq(link.tx),
                     self.running.eq(link.running),
                     self.overflow.eq(pay.overflow | pay.overrun),
                     self.clamped.eq(pay.clamp_flags != 0)]
        return m


def link_verilog(lcfg: LinkConfig, name: str = "linked_core", lowered: bool = False) -> str:
    """Verilog of :class:`LinkedTop`; ``lowered`` gives the yosys-lowered netlist for Icarus 11
    (see :func:`cuneate.hdl.flow.verilog.lowered_verilog`: it mis-schedules some combinational
    processes of the link's transmit FSM in the direct output)."""
    return verilog_text(LinkedTop(lcfg), name, lowered)
