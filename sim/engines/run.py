"""What an engine run produced, the same record for every block, and the helpers the engines
share to read a core's spike stream.

Spike times follow the golden convention everywhere: the update of tick (sweep) ``k`` reports
its spike at ``(k + 1) dt`` ms.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["EngineRun", "TickUnwrap", "unwrap_ticks", "times_from_pairs"]


@dataclass
class EngineRun:
    """One run of a block on one engine.

    ``spikes_ms``: one array or list of spike times (ms) per neuron, in the block's neuron
    order; with several populations (``populations``: name -> ``(first, count)``) they follow
    each other. ``clamp_counts``: updates clamped per kind (``None`` where the engine cannot
    see them: the ``board`` engine's link carries spikes, not clamps); ``clamp_sticky``: the
    sticky flags (per kind, or the block's bit mask); ``counters``: what the engine counted besides
    (writes, merged input events, link events, ...).
    """

    engine: str
    dt_ms: float
    n_ticks: int
    spikes_ms: list
    clamp_counts: dict = field(default_factory=dict)
    clamp_sticky: object = field(default_factory=dict)
    wall_s: float = 0.0
    counters: dict = field(default_factory=dict)
    populations: dict = field(default_factory=dict)

    @property
    def n_sweeps(self) -> int:
        return self.n_ticks

    def population(self, name: str) -> list:
        """The spike trains of population ``name``."""
        first, count = self.populations[name]
        return self.spikes_ms[first:first + count]

    @property
    def afferent_ms(self) -> list:
        return self.population("afferent")

    @property
    def cuneate_ms(self) -> list:
        return self.population("cuneate")

    @property
    def merged(self) -> int:
        """Input events the block merged with an earlier one of the same tick."""
        return int(self.counters.get("merged_count", 0))


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


def times_from_pairs(pairs, n: int, dt_ms: float) -> list[np.ndarray]:
    """Spike times (ms) per neuron ``0 .. n - 1`` from ``(tick, neuron)`` pairs."""
    out: list[list[int]] = [[] for _ in range(n)]
    for k, i in pairs:
        out[int(i)].append(int(k))
    return [(np.sort(np.asarray(ks, dtype=np.float64)) + 1) * dt_ms for ks in out]
