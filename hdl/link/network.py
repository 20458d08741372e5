"""The on-chip afferent -> cuneate network behind the host link: :class:`LinkedNetwork`, the
board top of the ``board`` engine's network scenes (as :class:`~cuneate.hdl.link.LinkedCore` is
for an Izhikevich core), and what every board top of the network shares with it
(:func:`check_network_link`, :func:`link_network_wiring`; the other such top is
:class:`~cuneate.hdl.link.LinkedFanoutNetwork`, channels fanned out on chip)."""

from __future__ import annotations

from amaranth import Module, Mux
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..lib.config import ConfigError
from ..network import AfferentCuneateNetwork, NetworkConfig
from .config import LinkConfig
from .core import HostLink

__all__ = ["LinkedNetwork", "check_network_link", "link_network_wiring"]


def check_network_link(ncfg: NetworkConfig, lcfg: LinkConfig) -> None:
    """Refuse, in one line (:class:`~cuneate.hdl.lib.config.ConfigError`), a network and a link
    that no board top of the network joins: a network not on the link's ticks, a link that
    does not serve its afferent core alone, spike ids not those of both populations."""
    if ncfg.tick_source != "external":
        raise ConfigError("the host link drives the network's ticks: the network needs "
                          "tick_source='external'")
    if lcfg.core.to_kwargs() != ncfg.core.to_kwargs() or lcfg.n_cores != 1:
        raise ConfigError("the link of a network serves its afferent core (ncfg.core) alone")
    if lcfg.n_spike_ids != ncfg.n_afferents + ncfg.n_targets:
        raise ConfigError(f"the link of a network carries the spike ids of "
                          f"{ncfg.n_afferents} afferents and {ncfg.n_targets} cuneate "
                          f"neurons: spike_ids = {ncfg.n_afferents + ncfg.n_targets}, "
                          f"not {lcfg.n_spike_ids}")


def link_network_wiring(top, net: AfferentCuneateNetwork, link: HostLink, writer=None,
                        hold=None, fault=None) -> list:
    """The connections every board top of the network behind a :class:`HostLink` shares: the
    pins ``rx``, ``tx`` and ``running``; the afferents' currents from ``writer``'s host write
    port (``i_wr_en``, ``i_wr_addr``, ``i_wr_data``: the link's own by default, or a block
    between them, the channel fan-out); the link's ticks into the network; the spike stream
    of both populations in one id space (afferent ``i`` as ``i``, cuneate ``j`` as
    ``n_afferents + j``, the tick the network reports them at as their sweep); ``sweep_done``
    the network's ``tick_done``; ``core_busy`` the network's ``busy | tick_open``, ORed with
    ``hold`` if given (the top's own reasons to hold the next tick and the next frame's
    writes); ``overflow`` the network's FIFO drops and tick overruns, ORed with ``fault`` if
    given."""
    N = net.cfg.n_afferents
    writer = link if writer is None else writer
    overflow = net.afferent_overflow | (net.cuneate_overflow_count != 0) | \
        (net.overrun_count != 0)
    busy = net.busy | net.tick_open
    return [
        link.rx.eq(top.rx), top.tx.eq(link.tx), top.running.eq(link.running),
        top.overflow.eq(overflow if fault is None else overflow | fault),
        net.i_wr_en.eq(writer.i_wr_en), net.i_wr_addr.eq(writer.i_wr_addr),
        net.i_wr_data.eq(writer.i_wr_data), net.tick.eq(link.tick),
        link.core_busy.eq(busy if hold is None else busy | hold),
        link.spike_valid.eq(net.out_valid), net.out_ready.eq(link.spike_ready),
        link.spike_index.eq(Mux(net.out_population, N + net.out_index, net.out_index)),
        link.spike_sweep.eq(net.out_tick),
        link.sweep_done.eq(net.tick_done),
    ]


class LinkedNetwork(wiring.Component):
    """The on-chip afferent -> cuneate network (:class:`~cuneate.hdl.network
    .AfferentCuneateNetwork`) behind a :class:`HostLink`: the pins are ``rx`` and ``tx``; status
    outputs ``running`` and ``overflow`` (a network FIFO dropped a spike or a tick overran:
    impossible while the link paces the ticks) for LEDs. The two parts are the attributes
    ``network`` and ``link``.

    The host writes the afferents' currents (ids ``0 .. n_afferents - 1``); spikes of both
    populations leave in one id space, afferent ``i`` as ``i`` and cuneate ``j`` as
    ``n_afferents + j`` (``lcfg.n_spike_ids == n_afferents + n_targets``), with the tick the
    network reports them at as their sweep. The link's ``sweep_done`` is the network's
    ``tick_done`` (every spike of the tick handed over) and its ``core_busy`` holds the next tick
    while the network is busy or its tick is still open, so a spike batch never closes before
    its spikes and the next tick's spikes never reach the batch logic before the close
    (:func:`link_network_wiring`).

    Parameters
    ----------
    ncfg
        The network (:class:`~cuneate.hdl.network.NetworkConfig`, ``tick_source="external"``).
    lcfg
        The link; its core is the network's afferent core (``ncfg.core``: the current and
        sweep-number formats) and its ``spike_ids`` cover both populations.
    """

    def __init__(self, ncfg: NetworkConfig, lcfg: LinkConfig):
        self._MustUse__silence = True           # until checked: a refused top is never used
        if lcfg.fanout is not None:
            raise ConfigError("a link with a channel fan-out writes channel samples: its board "
                              "top is LinkedFanoutNetwork")
        check_network_link(ncfg, lcfg)
        self._MustUse__silence = False
        self.ncfg, self.lcfg = ncfg, lcfg
        super().__init__({"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1),
                          "overflow": Out(1)})
        self.network = AfferentCuneateNetwork(ncfg)
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        m = Module()
        m.submodules.network = net = self.network
        m.submodules.link = link = self.link
        m.d.comb += link_network_wiring(self, net, link)
        return m
