"""The channel fan-out and an Izhikevich core behind the host link: :class:`LinkedFanoutCore`,
the board top for scenes whose host streams channel samples (a grating's shift, or its
band-passed shift) instead of one current per afferent."""

from __future__ import annotations

from amaranth import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..fanout import ChannelFanout
from ..izhikevich import IzhikevichConfig, IzhikevichCore
from ..lib.config import ConfigError
from .config import LinkConfig
from .core import HostLink, link_core_wiring

__all__ = ["LinkedFanoutCore"]


class LinkedFanoutCore(wiring.Component):
    """:class:`~cuneate.hdl.fanout.ChannelFanout` between a :class:`HostLink` and an
    :class:`~cuneate.hdl.izhikevich.IzhikevichCore`: the host writes channel samples
    (``lcfg.n_written`` values in the fan-out's sample format, ``WRITE`` frames as for
    currents); when a frame's writes are done the fan-out runs its table over the channel
    memory and writes every afferent's current into the core, ``n_neurons + 5`` cycles during
    which the link holds the next tick and the next frame's writes (its ``core_busy``; the tick
    may fire in the cycle of the last current write, which lands before the core reads neuron
    0), so the currents are in effect from the frame's sweep exactly as written currents are:
    the tick's jitter grows by the run, ``n_neurons + 6`` cycles, and
    :class:`~cuneate.hdl.link.LinkConfig` refuses a sweep too short to hold it. Spikes leave
    as from :class:`~cuneate.hdl.link.LinkedCore`.

    Pins ``rx`` and ``tx``; status outputs ``running``, ``overflow`` (the core's spike FIFO or
    overrun, or a fan-out start or channel write refused while it ran: impossible while the link
    holds the ticks and the writes) and ``clamped`` (a fan-out current clamp acted, sticky; the
    counts per kind are the fan-out's ``clamp_low_count`` and ``clamp_high_count``). The parts
    are the attributes ``fanout``, ``core`` and ``link``.
    """

    def __init__(self, lcfg: LinkConfig):
        self._MustUse__silence = True           # until checked: a refused top is never used
        if lcfg.fanout is None:
            raise ConfigError("a fan-out board top needs a link with a fan-out "
                              "(LinkConfig(fanout=...))")
        if lcfg.n_cores != 1 or not isinstance(lcfg.core, IzhikevichConfig):
            raise ConfigError("the fan-out feeds one Izhikevich core")
        self._MustUse__silence = False
        self.lcfg = lcfg
        super().__init__({"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1),
                          "overflow": Out(1), "clamped": Out(1)})
        self.fanout = ChannelFanout(lcfg.fanout)
        self.core = IzhikevichCore(lcfg.core)
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        m = Module()
        m.submodules.fanout = fan = self.fanout
        m.submodules.core = core = self.core
        m.submodules.link = link = self.link
        # a frame's writes are one burst of consecutive cycles: the fan-out starts on the
        # cycle after its last write
        was_writing = Signal()
        m.d.sync += was_writing.eq(link.i_wr_en)
        start = was_writing & ~link.i_wr_en
        # a channel write the fan-out refused (impossible while core_busy holds the link's
        # writes during a run; sticky on the overflow pin should the timing ever change)
        refused = Signal()
        with m.If(fan.ch_wr_valid & ~fan.ch_wr_ready):
            m.d.sync += refused.eq(1)
        m.d.comb += link_core_wiring(self, core, link) + [
            self.overflow.eq(core.spike_overflow | core.overrun | (fan.overrun_count != 0)
                             | refused),
            self.clamped.eq(fan.clamp_flags != 0),
            fan.ch_wr_valid.eq(link.i_wr_en), fan.ch_wr_addr.eq(link.i_wr_addr),
            fan.ch_wr_data.eq(link.i_wr_data), fan.start.eq(start),
            core.i_wr_en.eq(fan.i_wr_en), core.i_wr_addr.eq(fan.i_wr_addr),
            core.i_wr_data.eq(fan.i_wr_data),
            # no tick and no next write from a frame's first write to the fan-out's last
            link.core_busy.eq(core.busy | link.i_wr_en | start | fan.busy),
        ]
        return m
