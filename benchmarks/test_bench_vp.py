"""Victor-Purpura matrices: the compiled matrix (golden/metrics_kernel.py) against Elephant's
``victor_purpura_distance`` and the pairwise NumPy programme, on trains the size of the texture
experiment's (one channel of the seeds' condition: 100 trials of ~50 spikes; the grid's
spatial VP: 500 trials across five conditions).

Printed and written to ``benchmarks/results/vp_matrix.json``: trains, spikes and seconds per
matrix for each implementation (the fastest of three runs; Elephant once, it is slow), and the
largest difference between them (they compute the same programme). Only sanity is asserted.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from cuneate.golden.metrics import victor_purpura, victor_purpura_matrix

from .conftest import report

pytestmark = pytest.mark.benchmark

Q_PER_MS = 0.005


def _trains(rng, n, mean_spikes, t_ms=1400.0):
    return [np.sort(rng.uniform(0, t_ms, rng.poisson(mean_spikes))) for _ in range(n)]


def _best(fn, repeats=3):
    out, best = None, np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return out, best


def test_vp_matrix_speed():
    import neo
    import quantities as pq
    from elephant.spike_train_dissimilarity import victor_purpura_distance
    rng = np.random.default_rng(1)
    victor_purpura_matrix(_trains(rng, 3, 5), Q_PER_MS)            # load the compiled kernel
    rows = []
    for n, spikes in ((100, 50), (500, 50), (100, 200)):
        trains = _trains(rng, n, spikes)
        total = int(sum(len(t) for t in trains))
        mat, t_c = _best(lambda: victor_purpura_matrix(trains, Q_PER_MS))
        rows.append({"implementation": "cuneate compiled (numba, parallel)", "trains": n,
                     "spikes": total, "seconds": t_c, "max_abs_diff": 0.0})
        if n <= 100:
            sub = trains[:40]
            t0 = time.perf_counter()
            ref = np.array([[victor_purpura(a, b, Q_PER_MS) for b in sub] for a in sub])
            t_np = (time.perf_counter() - t0) * (n * (n - 1)) / (40 * 39)
            rows.append({"implementation": "cuneate pairwise NumPy (40 trains, scaled)",
                         "trains": n, "spikes": total, "seconds": t_np,
                         "max_abs_diff": float(np.abs(ref - mat[:40, :40]).max())})
            st = [neo.SpikeTrain(t * pq.ms, t_stop=1400.0 * pq.ms) for t in trains]
            t0 = time.perf_counter()
            e = victor_purpura_distance(st, cost_factor=Q_PER_MS * 1000.0 * pq.Hz)
            rows.append({"implementation": f"elephant {__import__('elephant').__version__}",
                         "trains": n, "spikes": total, "seconds": time.perf_counter() - t0,
                         "max_abs_diff": float(np.abs(np.asarray(e) - mat).max())})
    report("vp_matrix", "Victor-Purpura matrix (q = 5/s): seconds per matrix", rows)
    assert all(r["seconds"] > 0 for r in rows)
    assert all(r["max_abs_diff"] < 1e-9 for r in rows)
