"""The bus faces' two streams: AXI4-Stream beats in, the payload's writes out
(:class:`StreamWrites`), and the payload's spikes in, AXI4-Stream beats out
(:class:`StreamSpikes`).

**Write beats** (``s_axis``): TDATA holds two fields of ``write_field_bytes`` bytes
(:func:`~cuneate.hdl.lib.regmap.stream_format`): the raw value in the low field, two's
complement sign-extended, and the address in the high one; TLAST ends a burst. No TKEEP,
TSTRB, TUSER, TID or TDEST: every byte of a beat counts.

**The write rule.** A burst is taken between sweeps: its first beat waits while the block is
busy or a tick waits; from then on the ticks are held (``hold``) until its last beat has been
handed to the block, so a burst's values are in effect together, from the next sweep
(register ``SWEEP`` names it) - as the UART face's executor holds its ticks while it writes.
A beat whose address is ``N_WRITTEN`` or more, or whose value does not fit the value's
format, is refused and counted (``count_refused``), never written elsewhere or wrapped; a
refused last beat still ends the burst (a fan-out in front then runs at the next burst's end).

**Spike beats** (``m_axis``): TDATA holds the spike's id in the low field and its sweep number
(wrapping, ``sweep_width`` bits) in the high one; TLAST marks each sweep's last beat; TUSER (1
bit) marks an empty sweep's single beat (its id field all ones: no neuron's, its sweep number,
TLAST set), so every sweep ends with exactly one TLAST and a host or DMA engine counts sweeps by
packets. The face keeps a sweep open from its tick until its TLAST beat is taken (``sweep_open``
holds the next tick): beats of two sweeps never mix. The last spike of a sweep is known once the
block's ``sweep_done`` has come and no spike has been offered for
:data:`~cuneate.hdl.lib.payload.SPIKES_SETTLE` cycles; each spike waits in a register until the
next one (or the sweep's end) says whether it is the last. Once offered, a beat stays on the
bus, unchanged, until it is taken (AXI4-Stream).
"""

from __future__ import annotations

from amaranth import Cat, Const, Module, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from ..lib.payload import SPIKES_SETTLE, spike_layout, write_layout
from ..lib.regmap import stream_format

__all__ = ["StreamWrites", "StreamSpikes", "axis_in_layout", "axis_out_layout"]


def axis_in_layout(info) -> data.StructLayout:
    """An ``s_axis`` beat: TDATA and TLAST."""
    return data.StructLayout({"tdata": stream_format(info)["write_tdata_bits"], "tlast": 1})


def axis_out_layout(info) -> data.StructLayout:
    """An ``m_axis`` beat: TDATA, TLAST and TUSER."""
    return data.StructLayout({"tdata": stream_format(info)["spike_tdata_bits"], "tlast": 1,
                              "tuser": 1})


class _StreamSide(wiring.Component):
    """One side of the bus face over the payload ``info``: its ports (:meth:`ports`) and its
    beat register on offer."""

    def __init__(self, info):
        self.info = info
        super().__init__(self.ports(info))

    def loads(self, reg):
        """The register ``reg`` on offer can take a new beat this cycle (a documented hook:
        the proof's mutants override it)."""
        return ~reg.valid | reg.ready


class StreamWrites(_StreamSide):
    """``s_axis`` beats in, the payload's ``write`` stream out (see the module docstring).
    ``busy`` and ``pending``: the block works, a tick waits; ``burst_open``: a burst has begun
    and its last beat is not taken; ``hold``: the ticks must wait (a burst open or a value on
    offer to the block); ``count_*`` pulse per beat written, refused, and burst ended.
    The value on offer sits in a register (``write.valid``) until the block takes it."""

    @staticmethod
    def ports(info) -> dict:
        return {"s_axis": In(stream.Signature(axis_in_layout(info))),
                "write": Out(stream.Signature(write_layout(info))),
                "busy": In(1), "pending": In(1), "burst_open": Out(1), "hold": Out(1),
                "count_writes": Out(1), "count_refused": Out(1), "count_bursts": Out(1)}

    def elaborate(self, platform):
        m = Module()
        info, s, w = self.info, self.s_axis, self.write
        F = 8 * stream_format(info)["write_field_bytes"]
        fmt = info.value_format
        value, addr = s.payload.tdata[:F], s.payload.tdata[F:]
        if fmt.signed:                    # the sign bit and the bits above it all equal
            top = value[fmt.width - 1:]
            fits = (top == 0) | (top == (1 << len(top)) - 1)
        else:
            fits = value[fmt.width:] == 0 if fmt.width < F else Const(1)
        ok = Signal()
        m.d.comb += ok.eq((addr < info.n_written) & fits)
        allowed = self.burst_open | (~self.busy & ~self.pending)
        m.d.comb += s.ready.eq(self.loads(w) & allowed)
        take = s.valid & s.ready
        with m.If(take & ok):
            m.d.sync += [w.valid.eq(1), w.payload.addr.eq(addr),
                         w.payload.value.eq(value[:fmt.width]),
                         w.payload.last.eq(s.payload.tlast)]
        with m.Elif(w.ready):
            m.d.sync += w.valid.eq(0)
        with m.If(take):
            m.d.sync += self.burst_open.eq(~s.payload.tlast)
        m.d.comb += [self.hold.eq(self.burst_open | w.valid),
                     self.count_writes.eq(take & ok), self.count_refused.eq(take & ~ok),
                     self.count_bursts.eq(take & s.payload.tlast)]
        return m


class StreamSpikes(_StreamSide):
    """The payload's ``spikes`` and ``sweep_done`` in, ``m_axis`` beats out (see the module
    docstring). ``tick``: a sweep opens; ``sweep_open``: its TLAST beat is not yet taken;
    ``count_spikes``, ``count_sweeps``, ``count_empty`` pulse per spike beat, TLAST beat and
    empty sweep's marker taken. The beat on offer and the spike waiting behind it are
    registers."""

    @staticmethod
    def ports(info) -> dict:
        return {"spikes": In(stream.Signature(spike_layout(info))),
                "sweep_done": In(1), "tick": In(1),
                "m_axis": Out(stream.Signature(axis_out_layout(info))), "sweep_open": Out(1),
                "count_spikes": Out(1), "count_sweeps": Out(1), "count_empty": Out(1)}

    def elaborate(self, platform):
        m = Module()
        info, sp, out = self.info, self.spikes, self.m_axis
        sf = stream_format(info)
        F, sw = 8 * sf["spike_field_bytes"], info.sweep_width
        held = Signal(name="held_valid")
        held_id = Signal(F, name="held_id")
        held_sweep = Signal(sw, name="held_sweep")
        done_seen = Signal(name="done_seen")
        ended = Signal(name="ended")                       # the TLAST beat is on offer
        settle = Signal(range(SPIKES_SETTLE + 1), name="settle")
        number = Signal(sw, name="sweep_number")           # the open sweep's number
        free = Signal()
        m.d.comb += [free.eq(self.loads(out)),
                     sp.ready.eq(~ended & (~held | free))]
        take = sp.valid & sp.ready
        end = self.sweep_open & done_seen & (settle == 0) & ~sp.valid & ~ended & free
        with m.If(take):
            m.d.sync += [held.eq(1), held_id.eq(sp.payload.index), held_sweep.eq(sp.payload.sweep)]
            with m.If(held):                                # the held spike was not the last
                m.d.sync += [out.valid.eq(1), out.payload.tdata.eq(Cat(held_id, held_sweep)),
                             out.payload.tlast.eq(0), out.payload.tuser.eq(0)]
            with m.Elif(out.ready):
                m.d.sync += out.valid.eq(0)
        with m.Elif(end):
            m.d.sync += [out.valid.eq(1), out.payload.tlast.eq(1), ended.eq(1), held.eq(0),
                         out.payload.tuser.eq(~held)]
            with m.If(held):
                m.d.sync += out.payload.tdata.eq(Cat(held_id, held_sweep))
            with m.Else():                                  # an empty sweep's marker
                m.d.sync += out.payload.tdata.eq(Cat(Const(sf["marker_id"], F), number))
        with m.Elif(out.ready):
            m.d.sync += out.valid.eq(0)
        # the sweep: opened by its tick, closed when its TLAST beat is taken
        shake = out.valid & out.ready
        with m.If(shake & out.payload.tlast):
            m.d.sync += [self.sweep_open.eq(0), ended.eq(0), number.eq(number + 1)]
        with m.If(self.tick):
            m.d.sync += [self.sweep_open.eq(1), done_seen.eq(0)]
        with m.If(self.sweep_done & self.sweep_open):
            m.d.sync += [done_seen.eq(1), settle.eq(SPIKES_SETTLE)]
        with m.Elif(take):
            m.d.sync += settle.eq(SPIKES_SETTLE)
        with m.Elif(settle != 0):
            m.d.sync += settle.eq(settle - 1)
        m.d.comb += [self.count_spikes.eq(shake & ~out.payload.tuser),
                     self.count_sweeps.eq(shake & out.payload.tlast),
                     self.count_empty.eq(shake & out.payload.tuser)]
        return m
