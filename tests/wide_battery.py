"""The core's accuracy yardstick: the four presets x 15 currents (3.5..100 mV/ms), 1 s at
16 kHz, run once in float64 and float32 Euler (shared by the tests that measure against it)."""

from functools import lru_cache
from types import SimpleNamespace

import numpy as np

from cuneate.golden import izhikevich as golden
from cuneate.hdl.izhikevich import IzhikevichConfig

PRESETS = ("RS", "IB", "CH", "FS")
CURRENTS = [3.5, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 70, 100]


@lru_cache(maxsize=1)
def wide_battery():
    """``names`` and ``cur`` (one train each), the float64 and float32 golden runs ``g64``,
    ``g32``, and ``config(**kw)``: the core of one neuron a train at 16 kHz."""
    names = [p for p in PRESETS for _ in CURRENTS]
    cur = np.array([i for _ in PRESETS for i in CURRENTS], dtype=float)
    n = len(names)
    g64 = golden.simulate(names, lambda t: cur, n_neurons=n, duration_ms=1000.0)
    g32 = golden.simulate(names, lambda t: cur, n_neurons=n, duration_ms=1000.0,
                          dtype=np.float32)

    def config(**kw):
        return IzhikevichConfig(n_neurons=n, clock_hz=16e3 * n, param_sets=PRESETS,
                                neuron_sets=[PRESETS.index(p) for p in names], **kw)
    return SimpleNamespace(names=names, cur=cur, g64=g64, g32=g32, config=config)
