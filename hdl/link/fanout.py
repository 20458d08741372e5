"""The channel fan-out behind the host link, in front of an Izhikevich core
(:class:`LinkedFanoutCore`) or of the afferent -> cuneate network (:class:`LinkedFanoutNetwork`):
the board tops for scenes whose host streams channel samples (a grating's shift, or its
band-passed shift) instead of one current per afferent. :func:`link_fanout_wiring` is what the
two share: the link's writes into the fan-out and its run after a frame's writes."""

from __future__ import annotations

from amaranth import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..fanout import ChannelFanout
from ..izhikevich import IzhikevichConfig, IzhikevichCore
from ..lib.config import ConfigError
from ..network import AfferentCuneateNetwork, NetworkConfig
from .config import LinkConfig
from .core import HostLink, link_core_wiring
from .network import check_network_link, link_network_wiring

__all__ = ["LinkedFanoutCore", "LinkedFanoutNetwork", "link_fanout_wiring"]

_PINS = {"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1), "overflow": Out(1),
         "clamped": Out(1)}


def _need_fanout(lcfg: LinkConfig) -> None:
    if lcfg.fanout is None:
        raise ConfigError("a fan-out board top needs a link with a fan-out "
                          "(LinkConfig(fanout=...))")


def link_fanout_wiring(m: Module, top, fan: ChannelFanout, link: HostLink):
    """The fan-out ``fan`` behind ``link``, added to ``m``: the link's writes are channel
    writes; the fan-out starts on the cycle after a frame's last write (a frame's writes are
    one burst of consecutive cycles); ``top.clamped`` is its sticky clamp flag. The fan-out's
    current writes (``i_wr_en``, ``i_wr_addr``, ``i_wr_data``) are the top's to connect to the
    block behind it (a core's host write port, or the network's).

    Returns ``(hold, fault)``: when the link must hold the next tick and the next frame's
    writes (from a frame's first write to the fan-out's last current write), and the
    fan-out's faults for the ``overflow`` pin (a start during a run, or a channel write
    refused while it ran: impossible while ``hold`` reaches the link's ``core_busy``; sticky
    should the timing ever change)."""
    was_writing = Signal()
    m.d.sync += was_writing.eq(link.i_wr_en)
    start = was_writing & ~link.i_wr_en
    refused = Signal()
    with m.If(fan.ch_wr_valid & ~fan.ch_wr_ready):
        m.d.sync += refused.eq(1)
    m.d.comb += [
        top.clamped.eq(fan.clamp_flags != 0),
        fan.ch_wr_valid.eq(link.i_wr_en), fan.ch_wr_addr.eq(link.i_wr_addr),
        fan.ch_wr_data.eq(link.i_wr_data), fan.start.eq(start),
    ]
    return link.i_wr_en | start | fan.busy, (fan.overrun_count != 0) | refused


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
        _need_fanout(lcfg)
        if lcfg.n_cores != 1 or not isinstance(lcfg.core, IzhikevichConfig):
            raise ConfigError("the fan-out feeds one Izhikevich core")
        self._MustUse__silence = False
        self.lcfg = lcfg
        super().__init__(dict(_PINS))
        self.fanout = ChannelFanout(lcfg.fanout)
        self.core = IzhikevichCore(lcfg.core)
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        m = Module()
        m.submodules.fanout = fan = self.fanout
        m.submodules.core = core = self.core
        m.submodules.link = link = self.link
        hold, fault = link_fanout_wiring(m, self, fan, link)
        m.d.comb += link_core_wiring(self, core, link) + [
            self.overflow.eq(core.spike_overflow | core.overrun | fault),
            core.i_wr_en.eq(fan.i_wr_en), core.i_wr_addr.eq(fan.i_wr_addr),
            core.i_wr_data.eq(fan.i_wr_data),
            # no tick and no next write from a frame's first write to the fan-out's last
            link.core_busy.eq(core.busy | hold),
        ]
        return m


class LinkedFanoutNetwork(wiring.Component):
    """:class:`~cuneate.hdl.fanout.ChannelFanout` between a :class:`HostLink` and the on-chip
    afferent -> cuneate network (:class:`~cuneate.hdl.network.AfferentCuneateNetwork`): the
    host writes channel samples (``lcfg.n_written`` values in the fan-out's sample format,
    ``WRITE`` frames as for currents) and the fan-out writes every afferent's current into the
    network's afferent core; spikes of both populations leave as from
    :class:`~cuneate.hdl.link.LinkedNetwork` (afferent ``i`` as ``i``, cuneate ``j`` as
    ``n_afferents + j``, each at the tick the network reports it at).

    Latency and ticks: a frame for sweep ``k`` waits until the network has reported tick
    ``k - 1`` (its ``tick_done``); its ``n_channels`` writes, then the fan-out's run of
    ``n_afferents + 5`` cycles, hold the link's next tick and next frame's writes, with the
    network's ``busy | tick_open`` (the link's ``core_busy``, :func:`link_network_wiring`); the
    tick may fire in the cycle of the last current write, which lands before the core reads
    neuron 0. The currents are thus in effect from sweep ``k``, exactly as currents written to
    :class:`~cuneate.hdl.link.LinkedNetwork` are, and the cuneate neurons see those afferents'
    spikes with the network's own latency (:meth:`~cuneate.hdl.network.NetworkConfig.latency`).
    The tick's jitter grows by the writes and the run, ``n_channels + n_afferents + 6`` cycles;
    a sweep must hold them beside the network's tick work and the link's idle cycles
    (:func:`~cuneate.sim.link.engines.board_fanout_network_config` sizes it).

    Pins ``rx`` and ``tx``; status outputs ``running``, ``overflow`` (a network FIFO dropped a
    spike or a tick overran, or a fan-out start or channel write refused while it ran:
    impossible while the link holds the ticks and the writes) and ``clamped`` (a fan-out
    current clamp acted, sticky; the counts per kind are the fan-out's ``clamp_low_count`` and
    ``clamp_high_count``). The parts are the attributes ``fanout``, ``network`` and ``link``.

    Parameters
    ----------
    ncfg
        The network (:class:`~cuneate.hdl.network.NetworkConfig`, ``tick_source="external"``).
    lcfg
        The link, with a ``fanout`` of ``ncfg.n_afferents`` afferents; its core is the
        network's afferent core (``ncfg.core``) and its ``spike_ids`` cover both populations
        (``n_afferents + n_targets``).
    """

    def __init__(self, ncfg: NetworkConfig, lcfg: LinkConfig):
        self._MustUse__silence = True           # until checked: a refused top is never used
        _need_fanout(lcfg)
        if lcfg.fanout.n_neurons != ncfg.n_afferents:
            raise ConfigError(f"the fan-out feeds {lcfg.fanout.n_neurons} afferents; the "
                              f"network has {ncfg.n_afferents}")
        check_network_link(ncfg, lcfg)
        self._MustUse__silence = False
        self.ncfg, self.lcfg = ncfg, lcfg
        super().__init__(dict(_PINS))
        self.fanout = ChannelFanout(lcfg.fanout)
        self.network = AfferentCuneateNetwork(ncfg)
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        m = Module()
        m.submodules.fanout = fan = self.fanout
        m.submodules.network = net = self.network
        m.submodules.link = link = self.link
        hold, fault = link_fanout_wiring(m, self, fan, link)
        m.d.comb += link_network_wiring(self, net, link, writer=fan, hold=hold, fault=fault)
        return m
