"""The limit table: per device and pipeline depth, the bounds on neurons at 16 kHz (block RAM,
multipliers, fmax; :func:`cuneate.boards.sizing.limits`), the largest count the sizing
accepts, and what a real build reaches (place and route with the open tools where the device
has them: the ULX3S at its largest count at the deepest depth, the iCEBreaker at its largest
count), as a fraction of the tightest bound. Prints the table and writes
``benchmarks/results/device_limits.json``; asserts only that each build ran."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cuneate.boards.build import build_target
from cuneate.boards.sizing import limits
from cuneate.boards.targets import TARGETS
from cuneate.hdl.izhikevich.config import PIPELINE_STAGES

pytestmark = pytest.mark.benchmark

RESULTS = Path(__file__).parent / "results"
BUILDS = {"ulx3s": max(PIPELINE_STAGES), "icebreaker": PIPELINE_STAGES[0]}


def test_device_limit_table(tmp_path):
    rows = []
    for name, target in TARGETS.items():
        for depth in (PIPELINE_STAGES[0], max(PIPELINE_STAGES)):
            lim = limits(target, depth)
            bounds = [b for b in (lim["bram"], lim["multiplier"], lim["fmax"]) if b]
            row = {"board": name, "device": target["device"], "depth": depth, **lim,
                   "tightest": min(bounds)}
            if BUILDS.get(name) == depth and target.get("bitstream"):
                r = build_target(name, tmp_path / f"{name}_{depth}", n_neurons=lim["largest"],
                                 pipeline_stages=depth, seed=1)
                pr = r["place_route"]
                row["build"] = {"neurons": r["neurons"], "cores": r["cores"],
                                "clock_mhz": r["core"]["clock_hz"] / 1e6,
                                "fmax_mhz": pr["min_fmax_mhz"], "timing_met": pr["timing_met"],
                                "resources": pr["resources"], "seconds": r["build_seconds"]}
                assert r["bitstream"], r
            rows.append(row)
    print("\nneurons at 16 kHz: bounds, largest accepted by the sizing, and real builds")
    print(f"{'board':11s} {'depth':>5s} {'BRAM bound':>10s} {'mult bound':>10s} "
          f"{'fmax bound':>10s} {'largest':>8s} {'of tightest':>11s}  build")
    for r in rows:
        b = r.get("build")
        built = (f"{b['neurons']} neurons, {b['cores']} core{'s' if b['cores'] > 1 else ''} "
                 f"at {b['clock_mhz']:g} MHz, fmax {b['fmax_mhz']:.1f} MHz "
                 f"({'met' if b['timing_met'] else 'NOT met'}), {b['seconds']:.0f} s"
                 if b else "-")
        fmax = f"{r['fmax']:10d}" if r["fmax"] else f"{'-':>10s}"
        print(f"{r['board']:11s} {r['depth']:5d} {r['bram']:10d} {r['multiplier']:10d} "
              f"{fmax} {r['largest']:8d} "
              f"{100 * r['largest'] / r['tightest']:10.0f} %  {built}")
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "device_limits.json").write_text(json.dumps(rows, indent=2, default=str))
