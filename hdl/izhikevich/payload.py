"""The Izhikevich core, or an array of cores over global ids, as a payload
(:mod:`cuneate.hdl.lib.payload`): currents in, spikes out."""

from __future__ import annotations

import numpy as np

from ..lib.config import ConfigError
from ..lib.core_payload import CoreSpec
from ..lib.payload import PayloadInfo, PayloadTwin, implements
from .array import IzhikevichArray, core_configs
from .config import CLAMP_KINDS, IzhikevichConfig
from .core import IzhikevichCore
from .twin import IzhikevichArrayTwin

__all__ = ["IzhikevichSpec"]


@implements(IzhikevichConfig)
class IzhikevichSpec(CoreSpec):
    """``n_cores`` cores of ``config`` (an :class:`~cuneate.hdl.izhikevich.array
    .IzhikevichArray` when more than one), ``neuron_sets`` one initial parameter set per global
    id when the cores differ (:func:`~cuneate.hdl.izhikevich.array.core_configs`). A sweep
    keeps the block busy for ``n_neurons`` cycles (the pipeline's tail within the faces' idle
    cycles)."""

    def __init__(self, config: IzhikevichConfig, n_cores: int = 1, neuron_sets=None):
        if isinstance(n_cores, bool) or not isinstance(n_cores, int) or n_cores < 1:
            raise ConfigError(f"n_cores must be an integer >= 1, not {n_cores!r}")
        if neuron_sets is not None:
            if n_cores == 1:
                raise ConfigError("neuron_sets of a payload are an array's (n_cores > 1); a "
                                  "single core takes them in its own configuration")
            core_configs(config, n_cores, neuron_sets)           # refuses what cannot be held
            neuron_sets = tuple(int(s) for s in neuron_sets)
        self.config, self.n_cores, self.neuron_sets = config, n_cores, neuron_sets
        ids = config.n_neurons * n_cores
        self.info = PayloadInfo(
            block="izhikevich_array" if n_cores > 1 else "izhikevich_core",
            written="current", n_written=ids, value_format=config.I,
            populations=(("neurons", 0, ids),), sweep_width=config.sweep_number_width,
            clock_hz=config.clock_hz, update_hz=config.update_hz,
            cycles_per_tick=config.cycles_per_tick, busy_cycles=config.n_neurons,
            clamp_kinds=CLAMP_KINDS, rounding=config.rounding,
            parts=({"block": "izhikevich_core", "neurons": config.n_neurons,
                    "cores": n_cores},))

    def options(self) -> dict:
        return {"n_cores": self.n_cores, "neuron_sets": self.neuron_sets}

    def core(self):
        return IzhikevichArray(self.config, self.n_cores, neuron_sets=self.neuron_sets) \
            if self.n_cores > 1 else IzhikevichCore(self.config)

    def twin(self) -> "_ArrayTwin":
        return _ArrayTwin(IzhikevichArrayTwin(self.config, self.n_cores,
                                              neuron_sets=self.neuron_sets))


class _ArrayTwin(PayloadTwin):
    def __init__(self, twin: IzhikevichArrayTwin):
        self.model = twin

    def write(self, addr: int, raw: int) -> None:
        self.model.set_current_raw(addr, raw)

    def sweep(self) -> np.ndarray:
        return np.flatnonzero(self.model.sweep())

    def clamp_flags(self) -> int:
        return int(np.bitwise_or.reduce([t.clamp_sticky for t in self.model.twins]))
