"""The on-chip afferent -> cuneate network behind the host link: :class:`LinkedNetwork`, the
board top of the ``board`` engine's network scenes (as :class:`~cuneate.hdl.link.LinkedCore` is
for an Izhikevich core)."""

from __future__ import annotations

from amaranth import Module, Mux
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..lib.config import ConfigError
from ..network import AfferentCuneateNetwork, NetworkConfig
from .config import LinkConfig
from .core import HostLink

__all__ = ["LinkedNetwork"]


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
    its spikes and the next tick's spikes never reach the batch logic before the close.

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
        if ncfg.tick_source != "external":
            raise ConfigError("the host link drives the network's ticks: the network needs "
                              "tick_source='external'")
        if lcfg.fanout is not None:
            raise ConfigError("a link with a channel fan-out writes channel samples: its board "
                              "top is LinkedFanoutCore")
        if lcfg.core.to_kwargs() != ncfg.core.to_kwargs() or lcfg.n_cores != 1:
            raise ConfigError("the link of a network serves its afferent core (ncfg.core) "
                              "alone")
        if lcfg.n_spike_ids != ncfg.n_afferents + ncfg.n_targets:
            raise ConfigError(f"the link of a network carries the spike ids of "
                              f"{ncfg.n_afferents} afferents and {ncfg.n_targets} cuneate "
                              f"neurons: spike_ids = {ncfg.n_afferents + ncfg.n_targets}, "
                              f"not {lcfg.n_spike_ids}")
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
        N = self.ncfg.n_afferents
        m.d.comb += [
            link.rx.eq(self.rx), self.tx.eq(link.tx), self.running.eq(link.running),
            self.overflow.eq(net.afferent_overflow | (net.cuneate_overflow_count != 0)
                             | (net.overrun_count != 0)),
            net.i_wr_en.eq(link.i_wr_en), net.i_wr_addr.eq(link.i_wr_addr),
            net.i_wr_data.eq(link.i_wr_data), net.tick.eq(link.tick),
            link.core_busy.eq(net.busy | net.tick_open),
            link.spike_valid.eq(net.out_valid), net.out_ready.eq(link.spike_ready),
            link.spike_index.eq(Mux(net.out_population, N + net.out_index, net.out_index)),
            link.spike_sweep.eq(net.out_tick),
            link.sweep_done.eq(net.tick_done),
        ]
        return m
