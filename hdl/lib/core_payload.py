"""A time-multiplexed core as a payload: the wiring every core with the bookkeeping's ports
(:mod:`cuneate.hdl.lib.bookkeeping`: host write port, spike FIFO, ``busy``, ``sweep_done``,
sticky flags) shares behind :func:`~cuneate.hdl.lib.payload.payload_signature`.

The core takes every write in the cycle it is offered (``write.ready`` is 1); its spike FIFO
is the ``spikes`` stream; ``busy`` is its sweep issue."""

from __future__ import annotations

from amaranth import Module
from amaranth.lib import wiring

from .payload import payload_signature

__all__ = ["CorePayload"]


class CorePayload(wiring.Component):
    """``core`` (built by the spec, kept as the attribute ``core`` so a simulation can watch
    it) behind the payload signature of ``spec.info``; the core's tick is external."""

    def __init__(self, spec, core):
        self.spec = spec
        self.core = core
        super().__init__(payload_signature(spec.info))

    def elaborate(self, platform):
        m = Module()
        m.submodules.core = core = self.core
        w, s = self.write, self.spikes
        m.d.comb += [
            w.ready.eq(1),
            core.i_wr_en.eq(w.valid), core.i_wr_addr.eq(w.payload.addr),
            core.i_wr_data.eq(w.payload.value),
            s.valid.eq(core.spike_valid), core.spike_ready.eq(s.ready),
            s.payload.index.eq(core.spike_index), s.payload.sweep.eq(core.spike_sweep),
            core.tick.eq(self.tick), self.busy.eq(core.busy),
            self.sweep_done.eq(core.sweep_done),
            self.clamp_flags.eq(core.clamp_flags), core.clamp_clear.eq(self.clamp_clear),
            self.overflow.eq(core.spike_overflow), self.overrun.eq(core.overrun),
        ]
        return m
