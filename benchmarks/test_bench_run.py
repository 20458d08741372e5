"""The default scene (``cuneate run``): wall time per stage and per engine, accuracy per engine.

All 40 trials x 2 gratings are neurons of one core sized to the scene (80 neurons), so each
engine builds and runs once. Printed and written to ``benchmarks/results/run_default.json``;
only sanity is asserted (every engine ran, decoded, and the hardware engines equal the twin).
"""

import time

import pytest

from cuneate.sim.scenes import run_scene
from cuneate.sim.scenes import default_scene

from .conftest import report

pytestmark = pytest.mark.benchmark


def test_default_scene(bench_build):
    t0 = time.perf_counter()
    r = run_scene(default_scene(), build_dir=bench_build / "run_default")
    total = time.perf_counter() - t0
    rows = []
    for e, s in r.timing["engines_s"].items():
        sim_ms = r.counters.get(e, {}).get("simulate_ms")
        rows.append({"engine": e, "wall_s": s, "simulate_s": sim_ms / 1000 if sim_ms else s,
                     "ticks": r.n_ticks, "neurons": len(r.neurons),
                     "ticks_per_s": r.n_ticks / (sim_ms / 1000 if sim_ms else s),
                     "accuracy_pct": 100 * r.decoded[e].accuracy})
    report("run_default", "cuneate run (default scene): per engine", rows,
           {"stages_s": {k: v for k, v in r.timing.items() if k != "engines_s"},
            "total_s": total, "agreement": r.agreement})
    assert set(r.spikes) == {"golden", "fixed", "verilator"}
    assert r.agreement["verilator vs fixed"]["identical_trains"] == len(r.neurons)
