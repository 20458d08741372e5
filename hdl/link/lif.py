"""A LIF core behind the host link: :class:`LinkedLif`, the board top of the ``board`` engine's
LIF block and the taxel-skin scenes (as :class:`~cuneate.hdl.link.LinkedCore` is for an
Izhikevich core)."""

from __future__ import annotations

from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..lib.config import ConfigError
from ..lif import LifConfig, LifCore
from .config import LinkConfig
from .core import HostLink, linked_core_module

__all__ = ["LinkedLif"]


class LinkedLif(wiring.Component):
    """A :class:`~cuneate.hdl.lif.LifCore` behind a :class:`HostLink`: the pins are ``rx`` and
    ``tx``; status outputs ``running`` and ``overflow`` (the core's spike FIFO overflowed or a
    tick overran: impossible while the link paces the ticks) for LEDs. The two parts are the
    attributes ``core`` and ``link``.

    The host writes the neurons' currents (the core's current format, ids ``0 .. n_neurons -
    1``) through the link's write port, which lands them between two sweeps exactly as the
    other engines write them; the link drives the core's ticks and batches its spikes, with
    the core's sweep number as their sweep. The link carries no input spikes and no parameter
    set selections: the core takes host currents alone (no weights) and keeps the neuron sets
    of its configuration.

    Parameters
    ----------
    lcfg
        The link; its core is the LIF core (a :class:`~cuneate.hdl.lif.LifConfig` with
        ``tick_source="external"``, linked alone, spike ids its neurons).
    """

    def __init__(self, lcfg: LinkConfig):
        self._MustUse__silence = True           # until checked: a refused top is never used
        cfg = lcfg.core
        if not isinstance(cfg, LifConfig):
            raise ConfigError(f"a linked LIF core needs a link of a LIF core (LifConfig), not "
                              f"of {type(cfg).__name__}")
        if lcfg.fanout is not None:
            raise ConfigError("a link with a channel fan-out writes channel samples: its board "
                              "top is LinkedFanoutCore")
        if cfg.n_inputs:
            raise ConfigError(f"the link carries no input spikes: a linked LIF core takes host "
                              f"currents alone (no weights), not {cfg.n_inputs} inputs")
        if lcfg.n_spike_ids != cfg.n_neurons:
            raise ConfigError(f"the spikes of a linked LIF core carry its {cfg.n_neurons} "
                              f"neuron ids: spike_ids = {cfg.n_neurons}, not {lcfg.n_spike_ids}")
        self._MustUse__silence = False
        self.lcfg = lcfg
        super().__init__({"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1),
                          "overflow": Out(1)})
        # built here so that a simulation can watch the writes toward the core
        self.core = LifCore(cfg)
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        return linked_core_module(self, self.core, self.link)
