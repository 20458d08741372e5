"""Link parameters (:class:`LinkConfig`), checked against the payload they serve (the block
behind the link, :mod:`cuneate.hdl.lib.payload`: the link takes its value and sweep-number
formats, ids and sweep rate): the frame sizes of :mod:`cuneate.hdl.link.codec` bound the batch
capacity and the values per write."""

from __future__ import annotations

from ..lib.config import ConfigError
from ..lib.payload import PayloadSpec, payload_spec
from .codec import MAX_FRAME, MIN_FRAME, SPIKE_HEADER, current_bytes

__all__ = ["LinkConfig", "link_config", "LINK_IDLE_CYCLES", "sweep_cycles"]

#: idle cycles per sweep a block behind the link keeps beyond its work (the sweep's pipeline
#: tail and the tick generator's jitter: a sweep must end before the next tick is due)
LINK_IDLE_CYCLES = 16
#: the most ids a frame's u16 fields address
MAX_IDS = 1 << 16


def sweep_cycles(info) -> int:
    """The cycles a sweep of a block (its :class:`~cuneate.hdl.lib.payload.PayloadInfo`)
    needs behind a board's link: the block's work a tick and the link's idle cycles."""
    return info.busy_cycles + LINK_IDLE_CYCLES


class LinkConfig:
    """Link parameters checked against the payload they serve.

    ``payload``: a :class:`~cuneate.hdl.lib.payload.PayloadSpec`, or a block configuration
    (:func:`~cuneate.hdl.lib.payload.payload_spec` makes the spec, with ``n_cores`` and
    ``neuron_sets`` for an Izhikevich array and a channel ``fanout`` in front of the block);
    its ticks come from the link. The host writes ``n_written`` values of ``current_width``
    bits (currents, or a fan-out's channel samples); spikes carry ids below ``n_spike_ids``."""

    def __init__(self, payload, clocks_per_bit: int = 16, batch_sweeps: int = 16,
                 batch_capacity: int = 79, rx_fifo_depth: int = 512,
                 tx_fifo_depth: int = 16, counter_width: int = 32, n_cores: int | None = None,
                 fanout=None, neuron_sets=None):
        kw = {k: v for k, v in (("n_cores", n_cores), ("neuron_sets", neuron_sets))
              if v is not None}
        spec = payload_spec(payload, fanout=fanout, **kw)
        if not spec.external:
            raise ConfigError("the host link drives the block's ticks: it needs "
                              "tick_source='external'")
        info = spec.info
        for what, n in (("values the host writes", info.n_written),
                        ("spike ids", info.n_spike_ids)):
            if n > MAX_IDS:
                raise ConfigError(f"the link addresses at most {MAX_IDS} {what}, not {n}")
        # a block that works on a burst (the fan-out's run) keeps the idle cycles too
        need = sweep_cycles(info) if info.written == "channel sample" else info.busy_cycles
        if info.cycles_per_tick < need:
            raise ConfigError(f"a sweep of {info.cycles_per_tick} cycles cannot hold the "
                              f"{info.block}'s {info.busy_cycles} cycles of work a tick"
                              + (f" ({need} with the link's idle cycles)"
                                 if need > info.busy_cycles else ""))
        if not 1 <= batch_sweeps <= 255:
            raise ConfigError(f"batch_sweeps must be 1..255, not {batch_sweeps}")
        max_spikes = (MAX_FRAME - MIN_FRAME - SPIKE_HEADER) // 3
        if not 1 <= batch_capacity <= max_spikes:
            raise ConfigError(f"batch_capacity must be 1..{max_spikes} (one frame), "
                              f"not {batch_capacity}")
        if info.cycles_per_tick < 10:
            raise ConfigError("the link needs sweeps at least 10 cycles apart (a spike batch "
                              "closes within 9 cycles of its last sweep)")
        if info.sweep_width < 9:
            raise ConfigError("the link needs sweep numbers of at least 9 bits")
        if not 8 <= counter_width <= 32:
            raise ConfigError(f"counter_width must be 8..32, not {counter_width}")
        #: the block behind the link and what the link knows of it
        self.payload, self.info = spec, info
        self.counter_width = int(counter_width)
        self.clocks_per_bit = int(clocks_per_bit)
        self.batch_sweeps = int(batch_sweeps)
        self.batch_capacity = int(batch_capacity)
        self.rx_fifo_depth = int(rx_fifo_depth)
        self.tx_fifo_depth = int(tx_fifo_depth)
        self.n_written = info.n_written
        self.n_spike_ids = info.n_spike_ids
        self.current_width = info.value_width
        self.current_bytes = current_bytes(self.current_width)
        self.max_currents = (MAX_FRAME - MIN_FRAME - 2) // self.current_bytes

    @property
    def core(self):
        """The configuration of the block's (first) time-multiplexed core: its formats and
        rates (a network's afferent core, the core behind a fan-out)."""
        return _core_of(self.payload)

    @property
    def fanout(self):
        """The channel fan-out in front of the block, or None."""
        return getattr(self.payload, "fanout", None)

    @property
    def n_cores(self) -> int:
        return getattr(_inner(self.payload), "n_cores", 1)

    @property
    def neuron_sets(self):
        return getattr(_inner(self.payload), "neuron_sets", None)

    @property
    def n_neurons(self) -> int:
        """The neurons whose currents the block takes (behind a fan-out: its afferents)."""
        return _inner(self.payload).info.n_written

    @property
    def baud(self) -> float:
        return self.info.clock_hz / self.clocks_per_bit

    def to_dict(self) -> dict:
        return {"clocks_per_bit": self.clocks_per_bit, "baud": self.baud,
                "batch_sweeps": self.batch_sweeps, "batch_capacity": self.batch_capacity,
                "rx_fifo_depth": self.rx_fifo_depth, "tx_fifo_depth": self.tx_fifo_depth,
                "current_bytes": self.current_bytes, "max_currents": self.max_currents,
                "counter_width": self.counter_width, "n_cores": self.n_cores,
                "n_neurons": self.n_neurons, "n_spike_ids": self.n_spike_ids,
                "n_written": self.n_written, "value_width": self.current_width,
                "payload": self.info.to_dict(),
                "fanout": None if self.fanout is None else self.fanout.to_dict()}


def _inner(spec: PayloadSpec) -> PayloadSpec:
    return getattr(spec, "inner", spec)


def _core_of(spec: PayloadSpec):
    cfg = _inner(spec).config
    return getattr(cfg, "core", cfg)


def link_config(core_kwargs: dict | None = None, **link_kwargs) -> LinkConfig:
    """A :class:`LinkConfig` for an Izhikevich core built from ``core_kwargs`` (external tick
    forced)."""
    from ..izhikevich import IzhikevichConfig
    kw = dict(core_kwargs or {})
    kw["tick_source"] = "external"
    return LinkConfig(IzhikevichConfig(**kw), **link_kwargs)
