"""The payload signature: the one interface every block that can sit behind a face (the UART
host link, the AXI and Wishbone faces) implements, and what a face needs to size itself.

A *payload* is a time-multiplexed block seen from outside, as a :class:`wiring.Signature`
(:func:`payload_signature`) on :mod:`amaranth.lib.stream`:

``write`` (in, stream of ``addr``, ``value``, ``last``)
    The host's values: a neuron's current, or a channel's sample (the channel fan-out). A
    write lands in the block's memory and is in effect from the next sweep that starts after
    it; ``last`` closes a burst (the fan-out runs its table after one). ``ready`` may fall
    while the block works on a burst (the fan-out), never for a bare core.
``spikes`` (out, stream of ``index``, ``sweep``)
    Every spike once, in the order each population's neurons fire, tagged with its id
    (:attr:`PayloadInfo.populations`) and the (wrapping) number of the sweep it belongs to.
``tick`` (in), ``busy`` (out), ``sweep_done`` (out)
    A tick starts a sweep; the face holds ticks, and writes meant for the next sweep, while
    ``busy``; ``sweep_done`` pulses once every spike of a sweep has been handed to ``spikes``
    (a face closes a batch or asserts TLAST on it); each is offered on ``spikes`` at the latest
    :data:`SPIKES_SETTLE` cycles after it, or stays offered until it is taken.
``clamp_flags`` (out), ``clamp_clear`` (in), ``overflow`` (out), ``overrun`` (out)
    Sticky flags: the clamps that acted, by kind (:attr:`PayloadInfo.clamp_kinds`); a spike
    dropped on a full FIFO; a tick that came while a sweep was still issued.

Blocks register a :class:`PayloadSpec` for their configuration type (:func:`implements`;
``hdl/<block>/payload.py``), and :func:`payload_spec` finds it: a spec derives the
:class:`PayloadInfo` once, builds the component, gives the same block at another clock
(:meth:`PayloadSpec.retimed`: the faces raise the clock to fit their own cycles) and its
bit-exact model (:class:`PayloadTwin`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from .config import ConfigError

__all__ = ["PayloadInfo", "PayloadSpec", "BlockSpec", "PayloadTwin", "payload_signature",
           "write_layout", "spike_layout", "write_port", "implements", "payload_spec", "SPECS",
           "SPIKES_SETTLE", "BlockPayload"]

#: cycles after ``sweep_done`` by which every spike of the sweep is offered on ``spikes`` (a
#: core's spike FIFO, a block RAM, delivers a spike pushed with the sweep's last update a few
#: cycles later)
SPIKES_SETTLE = 7


@dataclass(frozen=True)
class PayloadInfo:
    """What a face needs to know of the block behind it, derived once by its spec.

    ``written``: what a written value is (``"current"`` or ``"channel sample"``), ``n_written``
    the addresses, ``value_format`` its fixed-point format (``value_width`` bits);
    ``populations``: ``(name, first id, count)`` of the spike ids (``n_spike_ids`` in all);
    ``busy_cycles``: the cycles one tick keeps the block busy at worst, the writes of a burst
    and the work after it included (a sweep must hold them); ``max_spikes_per_tick``: the
    neurons that can fire in one sweep; ``write_map``: a block whose write addresses mean
    different things (the learning layer) names its ranges, ``(name, first, count, meaning)``
    each (empty: every address is a ``written`` value)."""

    block: str
    written: str
    n_written: int
    value_format: object
    populations: tuple
    sweep_width: int
    clock_hz: float
    update_hz: float
    cycles_per_tick: int
    busy_cycles: int
    clamp_kinds: tuple
    rounding: str = "nearest"
    parts: tuple = field(default=(), compare=False)
    write_map: tuple = ()

    @property
    def value_width(self) -> int:
        return self.value_format.width

    @property
    def n_spike_ids(self) -> int:
        return sum(count for _, _, count in self.populations)

    @property
    def max_spikes_per_tick(self) -> int:
        return self.n_spike_ids

    @property
    def dt_ms(self) -> float:
        return 1000.0 / self.update_hz

    def writes(self):
        """What a host writes, as its driver and transport see a core's currents:
        ``n_neurons`` values in the format ``I``, at ``update_hz``, rounded by ``rounding``,
        with no accepted range of their own (``current_range`` None)."""
        from types import SimpleNamespace
        return SimpleNamespace(n_neurons=self.n_written, I=self.value_format,
                               update_hz=self.update_hz, rounding=self.rounding,
                               current_range=None)

    def to_dict(self) -> dict:
        return {"block": self.block, "written": self.written, "n_written": self.n_written,
                "value_format": str(self.value_format), "value_width": self.value_width,
                "populations": [{"name": n, "first": f, "count": c}
                                for n, f, c in self.populations],
                "n_spike_ids": self.n_spike_ids, "sweep_width": self.sweep_width,
                "clock_hz": self.clock_hz, "update_hz": self.update_hz,
                "cycles_per_tick": self.cycles_per_tick, "busy_cycles": self.busy_cycles,
                "max_spikes_per_tick": self.max_spikes_per_tick,
                "clamp_kinds": list(self.clamp_kinds), "parts": list(self.parts),
                "write_map": [{"name": n, "first": f, "count": c, "meaning": d}
                              for n, f, c, d in self.write_map]}


def write_layout(info: PayloadInfo) -> data.StructLayout:
    """A written value: its address, raw bits and the end of its burst."""
    return data.StructLayout({"addr": range(max(info.n_written, 2)),
                              "value": info.value_format.shape(), "last": 1})


def spike_layout(info: PayloadInfo) -> data.StructLayout:
    """A spike: its id and the (wrapping) number of its sweep."""
    return data.StructLayout({"index": range(max(info.n_spike_ids, 2)),
                              "sweep": info.sweep_width})


def payload_signature(info: PayloadInfo) -> wiring.Signature:
    """The payload signature of a block described by ``info`` (module docstring)."""
    return wiring.Signature({
        "write": In(stream.Signature(write_layout(info))),
        "spikes": Out(stream.Signature(spike_layout(info))),
        "tick": In(1), "busy": Out(1), "sweep_done": Out(1),
        "clamp_flags": Out(max(len(info.clamp_kinds), 1)), "clamp_clear": In(1),
        "overflow": Out(1), "overrun": Out(1),
    })


def write_port(write, block) -> list:
    """The statements handing a payload's ``write`` stream, always ready, to the current write
    port of ``block`` (``i_wr_en``, ``i_wr_addr``, ``i_wr_data``), a value a cycle."""
    return [write.ready.eq(1), block.i_wr_en.eq(write.valid),
            block.i_wr_addr.eq(write.payload.addr), block.i_wr_data.eq(write.payload.value)]


class BlockPayload(wiring.Component):
    """A payload component of ``spec`` (kept as :attr:`spec`): its signature is
    :func:`payload_signature` of ``spec.info``; ``parts`` are its blocks, kept as attributes of
    those names so a simulation can watch them (a subclass wires them in ``elaborate``)."""

    def __init__(self, spec, **parts):
        self.spec = spec
        for name, part in parts.items():
            setattr(self, name, part)
        super().__init__(payload_signature(spec.info))


class PayloadTwin:
    """The bit-exact model of a payload as a face drives it: :meth:`write` a raw value (in
    effect from the next sweep), :meth:`end_burst` after a burst's last write, :meth:`sweep`
    runs one sweep and returns the ids that fired, in the order the block sends them;
    :meth:`clamp_flags` the block's sticky clamp flags."""

    def write(self, addr: int, raw: int) -> None:
        raise NotImplementedError

    def end_burst(self) -> None:
        """A burst ended (``last``): a block that works on bursts does so now."""

    def sweep(self):
        raise NotImplementedError

    def clamp_flags(self) -> int:
        """The sticky clamp flags so far, one bit per :attr:`PayloadInfo.clamp_kinds`."""
        raise NotImplementedError


class PayloadSpec:
    """A block's configuration as a payload: subclasses set :attr:`info` and implement
    :meth:`build`, :meth:`retimed` and :meth:`twin`."""

    #: the configuration types the spec serves (set by :func:`implements`)
    serves: tuple = ()
    info: PayloadInfo

    def build(self) -> wiring.Component:
        """The payload component (its signature :func:`payload_signature` of :attr:`info`)."""
        raise NotImplementedError

    def retimed(self, clock_hz: float) -> "PayloadSpec":
        """The same block at ``clock_hz``, its tick external (driven by the face)."""
        raise NotImplementedError

    def twin(self) -> PayloadTwin:
        raise NotImplementedError

    @property
    def external(self) -> bool:
        """Whether the block takes its ticks from the face."""
        raise NotImplementedError

    def to_dict(self) -> dict:
        return self.info.to_dict()


class BlockSpec(PayloadSpec):
    """The spec of one block built from its configuration (:attr:`config`: ``to_kwargs``,
    ``tick_source``, ``clock_hz``): :meth:`retimed` rebuilds it with the tick external,
    :meth:`build` refuses an internal tick and makes :meth:`component`."""

    config: object

    @property
    def external(self) -> bool:
        return self.config.tick_source == "external"

    def config_from(self, kw: dict):
        """The configuration of constructor keywords ``kw`` (as ``to_kwargs`` gives them)."""
        return type(self.config)(**kw)

    def options(self) -> dict:
        """The spec's own options besides the configuration (kept when retimed)."""
        return {}

    def retimed(self, clock_hz: float | None = None) -> "BlockSpec":
        kw = self.config.to_kwargs() | {"tick_source": "external"}
        if clock_hz is not None:
            kw["clock_hz"] = clock_hz
        return type(self)(self.config_from(kw), **self.options())

    def component(self) -> wiring.Component:
        raise NotImplementedError

    def build(self) -> wiring.Component:
        if not self.external:
            raise ConfigError(f"a payload's ticks come from its face: the {self.info.block} "
                              f"needs tick_source='external' (retimed() gives it)")
        return self.component()


#: configuration type -> the spec class that makes it a payload
SPECS: dict[type, type] = {}


def implements(*config_types):
    """Class decorator: the spec serves these configuration types (:func:`payload_spec`)."""
    def register(cls):
        cls.serves = tuple(config_types)
        for t in config_types:
            SPECS[t] = cls
        return cls
    return register


def payload_spec(config, **kw) -> PayloadSpec:
    """The payload of a block configuration (a spec is returned as it is); ``kw`` go to the
    block's spec (an Izhikevich array's ``n_cores`` and ``neuron_sets``, a ``fanout`` in front
    of the block)."""
    fanout = kw.pop("fanout", None)
    if isinstance(config, PayloadSpec):
        spec = config
        if kw:
            raise ConfigError(f"a payload spec takes no more options ({', '.join(kw)})")
    else:
        cls = _spec_class(config)
        spec = cls(config, **_options(cls, config, kw))
    if fanout is not None:                   # an adapter in front of the block
        spec = _spec_class(fanout)(fanout, inner=spec)
    return spec


def _options(cls: type, config, kw: dict) -> dict:
    """``kw`` if the spec class takes them all, else a one-line refusal naming the first."""
    import inspect
    params = inspect.signature(cls.__init__).parameters
    for k in kw:
        if k not in params:
            raise ConfigError(f"a {type(config).__name__} behind a face takes no {k} (it is "
                              f"one block; {cls.__name__} takes: "
                              f"{', '.join(list(params)[2:]) or 'no options'})")
    return kw


def _spec_class(config) -> type:
    _discover()
    for t in type(config).__mro__:
        if t in SPECS:
            return SPECS[t]
    raise ConfigError(f"no block behind a face takes a {type(config).__name__}")


def _discover() -> None:
    """Import every block's ``payload`` module (``hdl/<block>/payload.py``): each registers
    its spec, so a new block behind the faces is one module and nothing else."""
    import importlib
    import pkgutil
    from pathlib import Path
    hdl = Path(__file__).resolve().parents[1]
    for mod in pkgutil.iter_modules([str(hdl)]):
        if mod.ispkg and (hdl / mod.name / "payload.py").is_file():
            importlib.import_module(f"{__package__.rsplit('.', 1)[0]}.{mod.name}.payload")
