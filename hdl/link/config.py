"""Link parameters (:class:`LinkConfig`), checked against the core they serve (an Izhikevich
or a LIF core: the link takes its current and sweep-number formats, neuron count and sweep
rate): the frame sizes of :mod:`cuneate.hdl.link.codec` bound the batch capacity and the
currents per write."""

from __future__ import annotations

from ..izhikevich import ConfigError, IzhikevichConfig
from ..lif import LifConfig
from .codec import MAX_FRAME, MIN_FRAME, SPIKE_HEADER, current_bytes

__all__ = ["LinkConfig", "link_config", "LINK_IDLE_CYCLES"]

#: idle cycles per sweep a core behind the link keeps beyond its ``n_neurons`` (the sweep's
#: pipeline tail and the tick generator's jitter: a sweep must end before the next tick is due)
LINK_IDLE_CYCLES = 16


class LinkConfig:
    """Link parameters checked against the core they serve.

    ``n_neurons`` (the core's neurons times ``n_cores``) are the neurons the host writes
    currents to; with a channel ``fanout`` (:class:`~cuneate.hdl.fanout.FanoutConfig`) the host
    writes its ``n_channels`` samples instead (``n_written`` values of ``current_width`` bits).
    ``spike_ids`` (default ``n_neurons``, at most 65536) are the neuron ids spike frames may
    carry, for blocks behind the link with neurons the host does not write (the network's
    cuneate neurons follow its afferents). The core's formats (currents, sweep numbers) are
    the link's; the core is an :class:`~cuneate.hdl.izhikevich.IzhikevichConfig`
    (:class:`~cuneate.hdl.link.LinkedCore`, :class:`~cuneate.hdl.link.LinkedNetwork`,
    :class:`~cuneate.hdl.link.LinkedFanoutCore`) or a :class:`~cuneate.hdl.lif.LifConfig`
    (:class:`~cuneate.hdl.link.LinkedLif`, one core). ``neuron_sets`` (one parameter-set index
    per global id) starts each core of an array with its own sets."""

    def __init__(self, core: IzhikevichConfig | LifConfig, clocks_per_bit: int = 16,
                 batch_sweeps: int = 16, batch_capacity: int = 79, rx_fifo_depth: int = 512,
                 tx_fifo_depth: int = 16, counter_width: int = 32, n_cores: int = 1,
                 spike_ids: int | None = None, fanout=None, neuron_sets=None):
        if not isinstance(core, (IzhikevichConfig, LifConfig)):
            raise ConfigError(f"the link serves an Izhikevich or a LIF core, not "
                              f"{type(core).__name__}")
        if core.tick_source != "external":
            raise ConfigError("the host link drives the core's ticks: the core needs "
                              "tick_source='external'")
        if isinstance(n_cores, bool) or not isinstance(n_cores, int) or n_cores < 1:
            raise ConfigError(f"n_cores must be an integer >= 1, not {n_cores!r}")
        if n_cores > 1 and isinstance(core, LifConfig):
            raise ConfigError(f"a LIF core is linked alone (n_cores = 1), not {n_cores}")
        if core.n_neurons * n_cores > 1 << 16:
            raise ConfigError(f"the link addresses at most 65536 neurons, "
                              f"not {core.n_neurons * n_cores}")
        n_core = core.n_neurons * n_cores
        if fanout is not None:
            if fanout.n_neurons != n_core or fanout.I != core.I:
                raise ConfigError(f"the fan-out feeds {fanout.n_neurons} afferents in "
                                  f"{fanout.I}; the core behind the link has {n_core} in "
                                  f"{core.I}")
            need = n_core + fanout.n_channels + fanout.cycles_per_run + LINK_IDLE_CYCLES
            if core.cycles_per_tick < need:
                raise ConfigError(f"a sweep of {core.cycles_per_tick} cycles cannot hold a sweep "
                                  f"of {n_core} neurons, the writes of {fanout.n_channels} "
                                  f"channels and a fan-out run of {fanout.cycles_per_run} "
                                  f"cycles ({need} with the link's idle cycles)")
        if spike_ids is None:
            spike_ids = n_core
        if isinstance(spike_ids, bool) or not isinstance(spike_ids, int) or \
                not n_core <= spike_ids <= 1 << 16:
            raise ConfigError(f"spike_ids must be an integer in {n_core}..65536 (the "
                              f"core's neurons and up to 65536 spike ids), not {spike_ids!r}")
        if not 1 <= batch_sweeps <= 255:
            raise ConfigError(f"batch_sweeps must be 1..255, not {batch_sweeps}")
        max_spikes = (MAX_FRAME - MIN_FRAME - SPIKE_HEADER) // 3
        if not 1 <= batch_capacity <= max_spikes:
            raise ConfigError(f"batch_capacity must be 1..{max_spikes} (one frame), "
                              f"not {batch_capacity}")
        if core.cycles_per_tick < 10:
            raise ConfigError("the link needs sweeps at least 10 cycles apart (a spike batch "
                              "closes within 9 cycles of its last sweep)")
        if core.sweep_number_width < 9:
            raise ConfigError("the link needs sweep numbers of at least 9 bits")
        if not 8 <= counter_width <= 32:
            raise ConfigError(f"counter_width must be 8..32, not {counter_width}")
        if neuron_sets is not None:
            if n_cores == 1 or not isinstance(core, IzhikevichConfig):
                raise ConfigError("neuron_sets of the link are an array's (n_cores > 1); a "
                                  "single core takes them in its own configuration")
            from ..izhikevich.array import core_configs
            core_configs(core, n_cores, neuron_sets)          # refuses what cannot be held
            neuron_sets = tuple(int(s) for s in neuron_sets)
        #: each global id's initial parameter set when the cores of an array differ
        #: (:func:`~cuneate.hdl.izhikevich.array.core_configs`), else None
        self.neuron_sets = neuron_sets
        self.counter_width = int(counter_width)
        self.core = core
        #: cores behind the link (an :class:`~cuneate.hdl.izhikevich.array.IzhikevichArray`
        #: when more than one) and the global neuron ids it addresses
        self.n_cores = int(n_cores)
        self.n_neurons = core.n_neurons * self.n_cores
        #: the ids spikes carry (``n_neurons`` and above: neurons behind the link that the host
        #: does not write, e.g. a network's cuneate population after its afferents)
        self.n_spike_ids = int(spike_ids)
        self.clocks_per_bit = int(clocks_per_bit)
        self.batch_sweeps = int(batch_sweeps)
        self.batch_capacity = int(batch_capacity)
        self.rx_fifo_depth = int(rx_fifo_depth)
        self.tx_fifo_depth = int(tx_fifo_depth)
        #: the channel fan-out between the link and the core (``None``: the host writes the
        #: core's currents); with it the host writes channel samples in its sample format
        self.fanout = fanout
        #: the values the host writes (currents, or channel samples) and their width
        self.n_written = fanout.n_channels if fanout is not None else self.n_neurons
        self.current_width = fanout.S.width if fanout is not None else core.I.width
        self.current_bytes = current_bytes(self.current_width)
        self.max_currents = (MAX_FRAME - MIN_FRAME - 2) // self.current_bytes

    @property
    def baud(self) -> float:
        return self.core.clock_hz / self.clocks_per_bit

    def to_dict(self) -> dict:
        return {"clocks_per_bit": self.clocks_per_bit, "baud": self.baud,
                "batch_sweeps": self.batch_sweeps, "batch_capacity": self.batch_capacity,
                "rx_fifo_depth": self.rx_fifo_depth, "tx_fifo_depth": self.tx_fifo_depth,
                "current_bytes": self.current_bytes, "max_currents": self.max_currents,
                "counter_width": self.counter_width, "n_cores": self.n_cores,
                "n_neurons": self.n_neurons, "n_spike_ids": self.n_spike_ids,
                "n_written": self.n_written, "value_width": self.current_width,
                "fanout": None if self.fanout is None else self.fanout.to_dict()}


def link_config(core_kwargs: dict | None = None, **link_kwargs) -> LinkConfig:
    """A :class:`LinkConfig` for a core built from ``core_kwargs`` (external tick forced)."""
    kw = dict(core_kwargs or {})
    kw["tick_source"] = "external"
    return LinkConfig(IzhikevichConfig(**kw), **link_kwargs)
