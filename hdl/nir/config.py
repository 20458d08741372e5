"""Configuration of a NIR network on chip: a chain of LIF cores sharing one tick.

:class:`NirNetworkConfig` holds one :class:`~cuneate.hdl.lif.LifConfig` per layer (discrete
form, external tick; built by :mod:`cuneate.sim.nir.mapping` from a NIR graph) and checks that
they chain: layer ``l + 1``'s input sources are layer ``l``'s neurons (its weight memory has one
column per neuron of layer ``l``, padding included), every layer runs at the same update rate,
and one tick leaves every core time to finish its sweep (``settle_cycles``) before the next, so
every spike of sweep ``k`` reaches the next core before tick ``k + 1``. Refused at construction,
one line each (:class:`~cuneate.hdl.lib.config.ConfigError`).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..lib.config import ConfigError
from ..lif.config import PIPELINE_DEPTH, LifConfig

__all__ = ["NirNetworkConfig", "ConfigError"]


@dataclass
class NirNetworkConfig:
    """A chain of LIF cores (see the module docstring).

    Parameters
    ----------
    layers
        One :class:`LifConfig` (or its constructor keywords) per layer, in order.
    n_real
        The neurons of each layer that belong to the network (the rest pad a core to its
        minimum size: zero weights, never an output).
    readout
        The last layer is non-spiking (NIR's LI, CubaLI): its output is the membrane value of
        every update, read on its ``upd_v`` probe.
    clock_hz
        The clock; ``clock_hz / update_hz`` cycles per tick must cover ``settle_cycles``.
    """

    layers: list
    n_real: list
    readout: bool = False
    clock_hz: float | None = None

    def __post_init__(self):
        self.layers = [c if isinstance(c, LifConfig) else LifConfig.from_kwargs(c)
                       for c in self.layers]
        if not self.layers:
            raise ConfigError("a NIR network needs at least one layer")
        self.n_real = [int(n) for n in self.n_real]
        if len(self.n_real) != len(self.layers):
            raise ConfigError("n_real needs one count per layer")
        first = self.layers[0]
        for i, (c, n) in enumerate(zip(self.layers, self.n_real)):
            if c.form != "discrete" or c.tick_source != "external":
                raise ConfigError(f"layer {i}: a network layer is a discrete-form LIF core with "
                                  f"an external tick")
            if not 0 < n <= c.n_neurons:
                raise ConfigError(f"layer {i}: {n} neurons do not fit its core of "
                                  f"{c.n_neurons}")
            if c.update_hz != first.update_hz:
                raise ConfigError(f"layer {i}: update rate {c.update_hz:g} Hz differs from "
                                  f"layer 0's {first.update_hz:g} Hz")
            if i and c.n_inputs != self.layers[i - 1].n_neurons:
                raise ConfigError(f"layer {i}: {c.n_inputs} input sources, but layer {i - 1} "
                                  f"has {self.layers[i - 1].n_neurons} neurons")
            if i and not c.n_inputs:
                raise ConfigError(f"layer {i}: takes no input from layer {i - 1}")
        # a tick starts every core; each must finish (issue + pipeline) and its spikes must
        # reach the next core before the next tick
        self.settle_cycles = max(c.n_neurons for c in self.layers) + PIPELINE_DEPTH + 2
        self.update_hz = first.update_hz
        self.dt_ms = first.dt_ms
        if self.clock_hz is None:
            self.clock_hz = float(self.update_hz * self.settle_cycles)
        cycles = self.clock_hz / self.update_hz
        if cycles + 1e-9 < self.settle_cycles:
            raise ConfigError(f"{cycles:g} cycles per tick do not cover the {self.settle_cycles} "
                              f"a tick needs (the largest layer plus the pipeline)")
        self.n_inputs = first.n_inputs
        self.sweep_number_width = first.sweep_number_width

    @property
    def n_layers(self) -> int:
        return len(self.layers)

    def to_kwargs(self) -> dict:
        """JSON-friendly constructor keywords."""
        return {"layers": [c.to_kwargs() for c in self.layers], "n_real": list(self.n_real),
                "readout": bool(self.readout), "clock_hz": float(self.clock_hz)}

    @classmethod
    def from_kwargs(cls, kw: dict) -> "NirNetworkConfig":
        return cls(**kw)

    def to_dict(self) -> dict:
        """What a user of the generated Verilog needs (written beside it as JSON)."""
        return {"block": "NirNetwork", "layers": [c.to_dict() for c in self.layers],
                "n_real": self.n_real, "readout": self.readout, "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "dt_ms": self.dt_ms,
                "settle_cycles": self.settle_cycles,
                "latency": "a spike of layer l in sweep k acts on layer l + 1 in sweep k + 1"}
