"""The LIF core as a payload (:mod:`cuneate.hdl.lib.payload`): host currents in, spikes out. A
payload carries no input spikes, so the core takes host currents alone (no weights)."""

from __future__ import annotations

import numpy as np

from ..lib.config import ConfigError
from ..lib.core_payload import CoreSpec
from ..lib.payload import PayloadInfo, PayloadTwin, implements
from .config import CLAMP_KINDS, LifConfig
from .core import LifCore
from .twin import LifTwin

__all__ = ["LifSpec"]


@implements(LifConfig)
class LifSpec(CoreSpec):
    """One LIF core of ``config``; a sweep keeps it busy for ``n_neurons`` cycles."""

    def __init__(self, config: LifConfig):
        if config.n_inputs:
            raise ConfigError(f"a face carries no input spikes: a LIF core behind one takes "
                              f"host currents alone (no weights), not {config.n_inputs} inputs")
        self.config = config
        self.info = PayloadInfo(
            block="lif_core", written="current", n_written=config.n_neurons,
            value_format=config.I, populations=(("neurons", 0, config.n_neurons),),
            sweep_width=config.sweep_number_width, clock_hz=config.clock_hz,
            update_hz=config.update_hz, cycles_per_tick=config.cycles_per_tick,
            busy_cycles=config.n_neurons, clamp_kinds=CLAMP_KINDS, rounding=config.rounding,
            parts=({"block": "lif_core", "neurons": config.n_neurons},))

    def core(self) -> LifCore:
        return LifCore(self.config)

    def twin(self) -> "_LifTwin":
        return _LifTwin(LifTwin(self.config))


class _LifTwin(PayloadTwin):
    def __init__(self, twin: LifTwin):
        self.model = twin

    def write(self, addr: int, raw: int) -> None:
        self.model.I[int(addr)] = raw

    def sweep(self) -> np.ndarray:
        return np.flatnonzero(self.model.sweep())

    def clamp_flags(self) -> int:
        return int(self.model.clamp_sticky)
