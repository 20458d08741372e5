"""The channel fan-out as an adapter in front of any payload (:mod:`cuneate.hdl.lib.payload`):
the host writes channel samples; after a burst's last sample the fan-out runs its table and
writes every afferent's current into the block behind it."""

from __future__ import annotations

from amaranth import Cat, Module, Signal

from ..lib.config import ConfigError
from ..lib.payload import BlockPayload, PayloadInfo, PayloadSpec, PayloadTwin, implements
from .config import CLAMP_KINDS, FanoutConfig
from .core import ChannelFanout
from .twin import FanoutTwin

__all__ = ["FanoutSpec", "FanoutPayload"]


@implements(FanoutConfig)
class FanoutSpec(PayloadSpec):
    """``fanout`` in front of ``inner`` (a spec whose block takes a write every cycle), padded
    with idle afferents to the values ``inner`` takes. A tick's work grows by a burst of
    ``n_channels`` writes and a run of ``cycles_per_run``; the clamp kinds are the inner
    block's, then the fan-out's (``fanout_current_low``, ``fanout_current_high``)."""

    def __init__(self, fanout: FanoutConfig, inner: PayloadSpec):
        if not isinstance(inner, PayloadSpec):
            raise ConfigError("a fan-out stands in front of a block's payload spec")
        if isinstance(inner, FanoutSpec):
            raise ConfigError("a fan-out feeds a block, not another fan-out")
        i = inner.info
        if i.written != "current":
            raise ConfigError(f"the fan-out writes currents; the block behind it takes "
                              f"{i.written}s")
        if fanout.n_neurons > i.n_written or fanout.I != i.value_format:
            raise ConfigError(f"the fan-out feeds {fanout.n_neurons} afferents in {fanout.I}; "
                              f"the block behind it takes {i.n_written} in {i.value_format}")
        self.fanout, self.inner = fanout.padded(i.n_written), inner
        f = self.fanout
        self.info = PayloadInfo(
            block=f"channel_fanout+{i.block}", written="channel sample",
            n_written=f.n_channels, value_format=f.S, populations=i.populations,
            sweep_width=i.sweep_width, clock_hz=i.clock_hz, update_hz=i.update_hz,
            cycles_per_tick=i.cycles_per_tick,
            busy_cycles=i.busy_cycles + f.n_channels + f.cycles_per_run,
            clamp_kinds=i.clamp_kinds + tuple(f"fanout_{k}" for k in CLAMP_KINDS),
            rounding=i.rounding,
            parts=({"block": "channel_fanout", "channels": f.n_channels,
                    "afferents": f.n_neurons},) + i.parts)

    @property
    def config(self):
        return self.inner.config

    @property
    def external(self) -> bool:
        return self.inner.external

    def retimed(self, clock_hz: float | None = None) -> "FanoutSpec":
        inner = self.inner.retimed(clock_hz)
        kw = self.fanout.to_kwargs() | {"clock_hz": inner.info.clock_hz}
        return FanoutSpec(FanoutConfig.from_kwargs(kw), inner)

    def build(self) -> "FanoutPayload":
        return FanoutPayload(self)

    def twin(self) -> "_FanoutTwin":
        return _FanoutTwin(FanoutTwin(self.fanout), self.inner.twin(),
                           len(self.inner.info.clamp_kinds))


class _FanoutTwin(PayloadTwin):
    def __init__(self, fanout: FanoutTwin, inner: PayloadTwin, n_inner: int):
        self.fanout, self.inner, self.n_inner = fanout, inner, n_inner

    def write(self, addr: int, raw: int) -> None:
        self.fanout.write(addr, raw)

    def end_burst(self) -> None:
        for n, raw in enumerate(self.fanout.run()[0]):
            self.inner.write(n, int(raw))

    def sweep(self):
        return self.inner.sweep()

    def clamp_flags(self) -> int:
        """The inner block's flags, the fan-out's above them (the spec's clamp kinds)."""
        return self.inner.clamp_flags() | int(self.fanout.clamp_sticky) << self.n_inner


class FanoutPayload(BlockPayload):
    """:class:`~cuneate.hdl.fanout.ChannelFanout` (attribute ``fanout``) in front of the
    inner block's payload (attribute ``inner``). The fan-out starts in the cycle after a
    burst's last write; ``busy`` covers the writes on offer, that cycle, the run and the inner
    block's own work, so a face holds its next tick until the currents are in; a write offered
    while the fan-out runs waits (``ready`` low). ``overflow`` adds a start refused while a
    run was still going (impossible while the face honours ``busy``)."""

    def __init__(self, spec: FanoutSpec):
        super().__init__(spec, fanout=ChannelFanout(spec.fanout), inner=spec.inner.build())

    def elaborate(self, platform):
        m = Module()
        m.submodules.fanout = fan = self.fanout
        m.submodules.inner = inner = self.inner
        w, s, iw, isp = self.write, self.spikes, inner.write, inner.spikes
        start = Signal()
        m.d.sync += start.eq(w.valid & w.ready & w.payload.last)
        m.d.comb += [
            fan.ch_wr_valid.eq(w.valid), w.ready.eq(fan.ch_wr_ready),
            fan.ch_wr_addr.eq(w.payload.addr), fan.ch_wr_data.eq(w.payload.value),
            fan.start.eq(start),
            iw.valid.eq(fan.i_wr_en), iw.payload.addr.eq(fan.i_wr_addr),
            iw.payload.value.eq(fan.i_wr_data), iw.payload.last.eq(fan.done),
            s.valid.eq(isp.valid), isp.ready.eq(s.ready), s.payload.eq(isp.payload),
            inner.tick.eq(self.tick),
            self.busy.eq(inner.busy | fan.busy | w.valid | start),
            self.sweep_done.eq(inner.sweep_done),
            self.clamp_flags.eq(Cat(inner.clamp_flags, fan.clamp_flags)),
            inner.clamp_clear.eq(self.clamp_clear), fan.clamp_clear.eq(self.clamp_clear),
            self.overflow.eq(inner.overflow | (fan.overrun_count != 0)),
            self.overrun.eq(inner.overrun),
        ]
        return m
