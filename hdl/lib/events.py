"""Input spike events of the layers that take afferent spikes between ticks (coincidence,
learning): a twin's ``spike_in``, which marks each source pending for the next tick and counts
the events and those merged into one (a source can spike once a tick)."""

from __future__ import annotations

import numpy as np

__all__ = ["SpikeEvents"]


class SpikeEvents:
    """Mixin of a twin with ``cfg.n_sources``, ``pending`` (bool per source), ``events`` and
    ``merged``."""

    def spike_in(self, sources) -> None:
        """Input spike events (source indices) before the next tick."""
        for s in np.atleast_1d(np.asarray(sources, dtype=np.int64)):
            if not 0 <= s < self.cfg.n_sources:
                raise ValueError(f"spike source {int(s)} is outside 0 .. "
                                 f"{self.cfg.n_sources - 1}")
            self.events += 1
            if self.pending[s]:
                self.merged += 1
            self.pending[s] = True
