"""A host's current writes to a core in a cycle-level test bench."""


class RandomWrites:
    """Writes to ``n`` neurons of ``cfg``'s core, currents uniform in ``[lo, hi)`` mV/ms: each
    neuron once, in order (drawn at construction), then a random neuron with probability
    ``rate`` a cycle."""

    def __init__(self, cfg, rng, n, lo, hi, rate):
        self.cfg, self.rng, self.n, self.lo, self.hi, self.rate = cfg, rng, n, lo, hi, rate
        self.pending = [(k, self.raw()) for k in range(n)]

    def raw(self) -> int:
        return int(self.cfg.I.to_raw(self.rng.uniform(self.lo, self.hi)))

    def next(self):
        """This cycle's write, ``(neuron, raw current)``, or ``None``."""
        if self.pending:
            return self.pending.pop(0)
        if self.rng.random() < self.rate:
            return int(self.rng.integers(self.n)), self.raw()
        return None
