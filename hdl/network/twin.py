"""The bit-exact twin of the afferent -> cuneate network: the two blocks' twins on one tick."""

from __future__ import annotations

import numpy as np

from ..coincidence.twin import CoincidenceTwin
from ..izhikevich.twin import IzhikevichTwin
from .config import NetworkConfig

__all__ = ["NetworkTwin"]


class NetworkTwin:
    """Bit-exact model of :class:`AfferentCuneateNetwork` composed of the two blocks' twins."""

    def __init__(self, config: NetworkConfig):
        self.cfg = config
        self.core = IzhikevichTwin(config.core)
        self.det = CoincidenceTwin(config.det)
        self.ticks = 0
        self.last_inputs = np.zeros(config.n_targets, dtype=np.int64)

    def set_currents(self, values, index=None):
        return self.core.set_currents(values, index)

    def tick(self):
        """One tick: the detector stamps the previous sweep's afferent spikes and updates, the
        core sweeps; returns ``(afferent spikes, cuneate spikes)`` of this tick."""
        cun = self.det.tick()
        self.det.ticks -= 1                       # the input sums this tick used
        self.last_inputs = self.det.inputs()
        self.det.ticks += 1
        aff = self.core.sweep()
        F = self.cfg.first_source
        src = np.flatnonzero(aff[F:F + self.cfg.n_sources])
        if src.size:
            self.det.spike_in(src)
        self.ticks += 1
        return aff, cun
