"""What the bus faces share (:class:`StreamFace`): the two AXI4-Stream streams, the ticks, the
counters and the register file over any payload (:mod:`cuneate.hdl.lib.payload`); a bus
bridge in front of its ``regs`` port (AXI4-Lite, :mod:`cuneate.hdl.axi.lite`; Wishbone,
:mod:`cuneate.hdl.wishbone.bus`) makes a face of it.

ticks
    :class:`~cuneate.hdl.lib.tick.TickGenerator` with a divider set by ``TICK_DIVIDER``
    (reset: the configuration's cycles per tick); stopped after reset, ``CONTROL.start`` runs
    it freely, ``STEP`` (write N) for N sweeps. A due tick waits while the block is busy, a
    write burst is open or the last sweep's spikes are not all sent; a tick due while the
    previous one still waits is lost and counted (``TICK_OVERRUNS``). A sweep behind the face
    takes at most the block's ``busy_cycles`` + :data:`FACE_IDLE_CYCLES` with a sink that
    keeps up: a divider that long never overruns.
streams
    :class:`~cuneate.hdl.axi.stream.StreamWrites` (``s_axis``, the write rule) and
    :class:`~cuneate.hdl.axi.stream.StreamSpikes` (``m_axis``, TLAST per sweep, an empty
    sweep's marker).
registers
    :class:`~cuneate.hdl.lib.regmap.RegisterFile` over the map of
    :mod:`cuneate.hdl.lib.regmap`: identity, configuration, ``CONTROL`` (start, stop, clear
    counters, clear clamp flags, soft reset), ``STEP``, ``TICK_DIVIDER``, ``STATUS``,
    ``SWEEP``, ``CLAMP_FLAGS`` and the counters (:class:`~cuneate.hdl.lib.counters
    .CounterBank`, 32 bits, saturating; :data:`~cuneate.hdl.lib.regmap.COUNTERS`).
soft reset
    ``CONTROL.soft_reset`` stops the ticks, waits until no sweep, burst or beat is in flight
    and the block is idle, then resets for one cycle (``soft_reset``) the face's streams,
    ticks and counters and - through the top - every register of the block: its sweep
    numbering, spike FIFO, sticky flags. Memories keep their contents (neuron states and
    currents, a fan-out's table and samples), as after ``rst``: FPGA block RAM takes its
    initial contents at configuration only, and the blocks have no port that writes their
    initial states. ``TICK_DIVIDER`` keeps its value.
"""

from __future__ import annotations

from amaranth import Cat, Module, ResetInserter, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from ..lib.counters import CounterBank
from ..lib.payload import payload_signature
from ..lib.regmap import COUNTERS, RegisterFile, register_port
from ..lib.tick import TickGenerator
from .stream import StreamSpikes, StreamWrites, axis_in_layout, axis_out_layout

__all__ = ["StreamFace", "FACE_IDLE_CYCLES", "face_cycles"]

#: cycles a sweep behind a bus face takes beyond the block's ``busy_cycles`` at worst: the
#: deepest pipeline's tail (9), ``sweep_done`` (2), the spikes' settling
#: (:data:`~cuneate.hdl.lib.payload.SPIKES_SETTLE`), the TLAST beat's register and handshake
#: and the tick's hold (4), with room to spare
FACE_IDLE_CYCLES = 32


def face_cycles(info) -> int:
    """The cycles a sweep of the block of ``info`` needs behind a bus face, the sink keeping
    up (a divider this long never loses a tick)."""
    return info.busy_cycles + FACE_IDLE_CYCLES


class StreamFace(wiring.Component):
    """See the module docstring. Ports: ``payload`` (the flipped payload signature of
    ``info``), ``s_axis`` and ``m_axis`` (streams of
    :func:`~cuneate.hdl.axi.stream.axis_in_layout` and ``axis_out_layout``), ``regs`` (the
    register file's bus side, for a bridge) and ``soft_reset`` (the block's registers reset in
    this cycle). After elaboration the parts are the attributes ``writes``, ``spikes``,
    ``ticks``, ``counters`` and ``registers``."""

    def __init__(self, info):
        self.info = info
        super().__init__({
            "payload": In(payload_signature(info)),
            "s_axis": In(stream.Signature(axis_in_layout(info))),
            "m_axis": Out(stream.Signature(axis_out_layout(info))),
            "regs": In(register_port()),
            "soft_reset": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        info, p = self.info, self.payload
        soft = self.soft_reset
        reset = ResetInserter(soft)
        self.writes = wr = StreamWrites(info)
        self.spikes = sp = StreamSpikes(info)
        self.ticks = tg = TickGenerator(info.cycles_per_tick, settable=True)
        self.counters = ctr = CounterBank([n for n, _ in COUNTERS])
        self.registers = rf = RegisterFile(info, {"TICK_DIVIDER": info.cycles_per_tick})
        m.submodules.writes, m.submodules.spikes = reset(wr), reset(sp)
        m.submodules.ticks, m.submodules.counters = reset(tg), reset(ctr)
        m.submodules.registers = rf
        wiring.connect(m, wiring.flipped(self.regs), rf.bus)
        # --- streams
        wiring.connect(m, wiring.flipped(self.s_axis), wr.s_axis)
        wiring.connect(m, sp.m_axis, wiring.flipped(self.m_axis))
        m.d.comb += [
            p.write.valid.eq(wr.write.valid), p.write.payload.eq(wr.write.payload),
            wr.write.ready.eq(p.write.ready), wr.busy.eq(p.busy), wr.pending.eq(tg.pending),
            sp.spikes.valid.eq(p.spikes.valid), sp.spikes.payload.eq(p.spikes.payload),
            p.spikes.ready.eq(sp.spikes.ready), sp.sweep_done.eq(p.sweep_done),
            sp.tick.eq(tg.tick),
        ]
        # --- ticks
        ctl = rf.CONTROL_data
        command = rf.CONTROL_write
        pending_reset = Signal(name="reset_pending")
        m.d.comb += [
            tg.hold.eq(p.busy | wr.hold | sp.sweep_open), p.tick.eq(tg.tick),
            tg.divider.eq(rf.TICK_DIVIDER),
            tg.start.eq(command & ctl[0]), tg.stop.eq(command & (ctl[1] | ctl[4])),
            tg.step.eq(rf.STEP_write), tg.step_count.eq(rf.STEP_data),
            p.clamp_clear.eq(command & ctl[3]), ctr.clear.eq(command & ctl[2]),
        ]
        # --- soft reset: once nothing is in flight
        idle = ~p.busy & ~wr.hold & ~sp.sweep_open & ~self.m_axis.valid & ~tg.pending
        with m.If(command & ctl[4]):
            m.d.sync += pending_reset.eq(1)
        with m.Elif(soft):
            m.d.sync += pending_reset.eq(0)
        m.d.comb += soft.eq(pending_reset & idle)
        # --- counters and registers read
        inc = {"writes": wr.count_writes, "bursts": wr.count_bursts,
               "writes_refused": wr.count_refused, "spikes": sp.count_spikes,
               "sweeps": sp.count_sweeps, "empty_sweeps": sp.count_empty, "ticks": tg.tick,
               "tick_overruns": tg.overrun}
        m.d.comb += [getattr(ctr, f"inc_{n}").eq(inc[n]) for n, _ in COUNTERS]
        m.d.comb += [getattr(rf, f"r_{n.upper()}").eq(getattr(ctr, f"count_{n}"))
                     for n, _ in COUNTERS]
        m.d.comb += [
            rf.r_STEP.eq(tg.steps), rf.r_SWEEP.eq(tg.sweeps_started),
            rf.r_CLAMP_FLAGS.eq(p.clamp_flags),
            rf.r_STATUS.eq(Cat(tg.running, tg.free, tg.pending, p.busy, wr.burst_open,
                               sp.sweep_open, p.overflow, p.overrun, pending_reset)),
        ]
        return m
