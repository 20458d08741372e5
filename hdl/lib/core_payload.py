"""A time-multiplexed core as a payload: the wiring every core with the bookkeeping's ports
(:mod:`cuneate.hdl.lib.bookkeeping`: host write port, spike FIFO, ``busy``, ``sweep_done``,
sticky flags) shares behind :func:`~cuneate.hdl.lib.payload.payload_signature`, and the spec
such a core's payload shares (:class:`CoreSpec`).

The core takes every write in the cycle it is offered (``write.ready`` is 1); its spike FIFO
is the ``spikes`` stream; ``busy`` is its sweep issue."""

from __future__ import annotations

from amaranth import Module

from .config import ConfigError
from .payload import BlockPayload, PayloadSpec, write_port

__all__ = ["CorePayload", "CoreSpec"]


class CoreSpec(PayloadSpec):
    """The spec of a block whose configuration (:attr:`config`) has ``to_kwargs``,
    ``from_kwargs`` and ``tick_source``: :meth:`retimed` and :meth:`external` from it,
    :meth:`build` a :class:`CorePayload` of :meth:`core` (a subclass makes the core)."""

    config: object

    @property
    def external(self) -> bool:
        return self.config.tick_source == "external"

    def options(self) -> dict:
        """The spec's own options besides the configuration (an array's cores)."""
        return {}

    def retimed(self, clock_hz: float | None = None):
        kw = self.config.to_kwargs(tick_source="external")
        if clock_hz is not None:
            kw["clock_hz"] = clock_hz
        return type(self)(type(self.config).from_kwargs(kw), **self.options())

    def core(self):
        raise NotImplementedError

    def build(self) -> "CorePayload":
        if not self.external:
            raise ConfigError(f"a payload's ticks come from its face: the {self.info.block} "
                              f"needs tick_source='external' (retimed() gives it)")
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
