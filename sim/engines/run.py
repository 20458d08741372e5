"""What an engine run produced, the same record for every block, and the helpers the engines
share to read a core's spike stream.

Spike times follow the golden convention everywhere: the update of tick (sweep) ``k`` reports
its spike at ``(k + 1) dt`` ms (:func:`~cuneate.golden.izhikevich.spike_times`, the one
conversion, with its inverse :func:`~cuneate.golden.izhikevich.spike_ticks`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...golden.izhikevich import spike_ticks, spike_times

__all__ = ["EngineRun", "TickUnwrap", "unwrap_ticks", "spike_times", "spike_ticks",
           "times_from_pairs"]


def times_from_pairs(pairs, n: int, dt_ms: float, first: int = 0) -> list[np.ndarray]:
    """Spike times (ms) per neuron ``first .. first + n - 1`` from ``(tick, neuron)`` pairs
    (other neurons' pairs are left out)."""
    out: list[list[int]] = [[] for _ in range(n)]
    for k, i in pairs:
        if first <= i < first + n:
            out[int(i) - first].append(int(k))
    return [spike_times(np.sort(ks), dt_ms) for ks in out]


@dataclass
class EngineRun:
    """One run of a block on one engine.

    ``spikes_ms``: one array or list of spike times (ms) per neuron, in the block's neuron
    order; with several populations (``populations``: name -> ``(first, count)``) they follow
    each other. ``clamp_counts``: updates clamped per kind (``None`` where the engine cannot
    see them: the ``board`` engine's link carries spikes, not clamps, golden has none);
    ``clamp_sticky``: the sticky flags (per kind, or the block's bit mask); ``counters``: what
    the engine counted besides (writes, input events merged into an earlier one of their tick:
    ``merged_count``, link events, a simulator's cycles and wall time, ...). ``values``: what
    a block puts out besides spikes, one row per tick (the channel fan-out's afferent currents
    in mV/ms, one row per sample; a NIR readout layer's membrane); ``None`` where there is
    nothing.
    """

    engine: str
    dt_ms: float
    n_ticks: int
    spikes_ms: list
    clamp_counts: dict | None = field(default_factory=dict)
    clamp_sticky: object = field(default_factory=dict)
    wall_s: float = 0.0
    counters: dict = field(default_factory=dict)
    populations: dict = field(default_factory=dict)
    values: np.ndarray | None = None

    def population(self, name: str) -> list:
        """The spike trains of population ``name``."""
        first, count = self.populations[name]
        return self.spikes_ms[first:first + count]

    @property
    def spikes(self) -> np.ndarray | None:
        """The spikes as a raster ``(n_ticks, n_neurons)`` of bools (``None`` for a run with no
        spike trains: a readout layer, the fan-out)."""
        if self.spikes_ms is None:
            return None
        out = np.zeros((self.n_ticks, len(self.spikes_ms)), dtype=bool)
        for i in range(len(self.spikes_ms)):
            out[self.spike_ticks(i), i] = True
        return out

    def spike_ticks(self, neuron: int) -> np.ndarray:
        """The ticks whose updates made neuron ``neuron``'s spikes."""
        return spike_ticks(self.spikes_ms[neuron], self.dt_ms)

    def counts(self) -> np.ndarray:
        """Spikes per neuron."""
        if self.spikes_ms is None:
            return np.zeros(0, np.int64)
        return np.array([len(s) for s in self.spikes_ms], dtype=np.int64)


class TickUnwrap:
    """Absolute tick numbers from a stream that carries them modulo ``2**width``, in order."""

    def __init__(self, width: int):
        self.width, self.base, self.last = int(width), 0, -1

    def __call__(self, raw: int) -> int:
        if raw < self.last:
            self.base += 1 << self.width
        self.last = raw
        return self.base + raw


def unwrap_ticks(ticks, width: int) -> list[int]:
    """:class:`TickUnwrap` over a whole sequence."""
    u = TickUnwrap(width)
    return [u(int(t)) for t in ticks]
