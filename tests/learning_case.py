"""A learning layer small enough for a face's test: what the learning layer's payload, board
and AXI tests share (pytest puts ``tests/`` on the import path)."""

import numpy as np

from cuneate.golden.aidp import AidpParams
from cuneate.golden.cuneate_layer import presentations
from cuneate.hdl.plasticity import PlasticityConfig


def small_layer(seed=4, S=6, M=2, K=3, clock_hz=2000.0 * 400):
    """A layer of ``M`` CNs of ``K`` synapses on ``S`` afferents that learns and fires
    within two short presentations (10 ms windows, 24 ticks each), and the presentations."""
    rng = np.random.default_rng(seed)
    src = np.array([np.sort(rng.choice(S, K, replace=False)) for _ in range(M)])
    cfg = PlasticityConfig(n_sources=S, sources=src, weights=rng.uniform(0, 6, (M, K)),
                           rule=AidpParams(eta=2e-3, latency_ms=1.0), clock_hz=clock_hz)
    rng = np.random.default_rng(seed)
    tpl = [[np.sort(rng.uniform(0, 10, rng.integers(5, 15))) for _ in range(S)]
           for _ in range(2)]
    return cfg, presentations(tpl, [0, 1], (0, 10), 0.5, 1.0, 2.0, 4)
