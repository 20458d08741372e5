"""A time-multiplexed core as a payload: the wiring every core with the bookkeeping's ports
(:mod:`cuneate.hdl.lib.bookkeeping`: host write port, spike FIFO, ``busy``, ``sweep_done``,
sticky flags) shares behind :func:`~cuneate.hdl.lib.payload.payload_signature`, and the spec
such a core's payload shares (:class:`CoreSpec`).

The core takes every write in the cycle it is offered (``write.ready`` is 1); its spike FIFO
is the ``spikes`` stream; ``busy`` is its sweep issue."""

from __future__ import annotations

from amaranth import Module

from .payload import BlockPayload, BlockSpec, write_port

__all__ = ["CorePayload", "CoreSpec"]


class CoreSpec(BlockSpec):
    """The :class:`~cuneate.hdl.lib.payload.BlockSpec` of a core whose configuration rebuilds
    from its keywords by ``from_kwargs``; its component is a :class:`CorePayload` of
    :meth:`core` (a subclass makes the core)."""

    def config_from(self, kw: dict):
        return type(self.config).from_kwargs(kw)

    def core(self):
        raise NotImplementedError

    def component(self) -> "CorePayload":
        return CorePayload(self, self.core())


class CorePayload(BlockPayload):
    """``core`` (built by the spec, kept as the attribute ``core`` so a simulation can watch
    it) behind the payload signature of ``spec.info``; the core's tick is external."""

    def __init__(self, spec, core):
        super().__init__(spec, core=core)

    def elaborate(self, platform):
        m = Module()
        m.submodules.core = core = self.core
        s = self.spikes
        m.d.comb += write_port(self.write, core)
        m.d.comb += [
            s.valid.eq(core.spike_valid), core.spike_ready.eq(s.ready),
            s.payload.index.eq(core.spike_index), s.payload.sweep.eq(core.spike_sweep),
            core.tick.eq(self.tick), self.busy.eq(core.busy),
            self.sweep_done.eq(core.sweep_done),
            self.clamp_flags.eq(core.clamp_flags), core.clamp_clear.eq(self.clamp_clear),
            self.overflow.eq(core.spike_overflow), self.overrun.eq(core.overrun),
        ]
        return m
