"""The bit-exact twin of a NIR network on chip: one :class:`~cuneate.hdl.lif.LifTwin` per layer,
run layer after layer (the chain is feed-forward: layer ``l``'s spikes of sweep ``k`` are layer
``l + 1``'s input spikes of sweep ``k + 1``, exactly as the cores pass them on one tick)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lif.twin import LifTwin
from .config import NirNetworkConfig

__all__ = ["NirNetworkTwin", "NetworkRun"]


@dataclass
class NetworkRun:
    """Per layer: ``spikes`` (sweeps, n_neurons of the core) bool; ``v_raw`` (sweeps, n) the
    readout layer's membrane after each update (raw, its state format) or None; clamp reports."""

    spikes: list
    v_raw: np.ndarray | None
    clamps: list


class NirNetworkTwin:
    """Bit-exact model of :class:`~cuneate.hdl.nir.NirNetwork`.

    ``currents`` (per layer, raw values of its current format, one per neuron) are the host's
    constant currents (the Affine biases); :meth:`run` takes the input spikes of every sweep."""

    def __init__(self, config: NirNetworkConfig, currents_raw: list | None = None):
        self.cfg = config
        self.currents = [np.zeros(c.n_neurons, dtype=np.int64) if currents_raw is None
                         else np.asarray(currents_raw[i], dtype=np.int64)
                         for i, c in enumerate(config.layers)]

    def run(self, inputs) -> NetworkRun:
        """``inputs`` (sweeps, n_inputs) bool: the input spikes sent before each tick."""
        x = np.asarray(inputs, dtype=bool)
        T = x.shape[0]
        spikes, clamps, v_raw = [], [], None
        last = self.cfg.n_layers - 1
        for li, c in enumerate(self.cfg.layers):
            twin = LifTwin(c)
            if li:
                prev = spikes[-1]
                x = np.vstack([np.zeros((1, prev.shape[1]), dtype=bool), prev[:-1]])
            xin = x if c.n_inputs else None
            if li == last and self.cfg.readout:
                twin.I[:] = self.currents[li]
                v_raw = np.zeros((T, c.n_neurons), dtype=np.int64)
                out = np.zeros((T, c.n_neurons), dtype=bool)
                for k in range(T):
                    out[k] = twin.sweep(None if xin is None else xin[k])
                    v_raw[k] = twin.v
            else:
                ks, ns = twin.run_raw(self.currents[li], T, xin)
                out = np.zeros((T, c.n_neurons), dtype=bool)
                out[ks, ns] = True
            spikes.append(out)
            clamps.append(twin.clamp_report())
        return NetworkRun(spikes, v_raw, clamps)
