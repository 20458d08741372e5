"""The default job behind ``make demo``: generate the hardware and summarize the models."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["run_demo"]


def golden_summary() -> list[str]:
    from ..golden.izhikevich import PRESETS, simulate
    from ..golden.metrics import isi_stats
    lines = ["golden Izhikevich (forward Euler, dt = 1/16 ms, 1 s per neuron):",
             f"  {'preset':6s} {'I':>6s} {'spikes':>7s} {'mean ISI ms':>12s} {'CV':>6s}"]
    presets = list(PRESETS)
    currents = [4.0, 10.0, 30.0]
    names = [(p, i) for p in presets for i in currents]
    t0 = time.perf_counter()
    res = simulate([p for p, _ in names], lambda t: np.array([i for _, i in names]),
                   duration_ms=1000.0)
    elapsed = time.perf_counter() - t0
    for (p, i), s in zip(names, res.spikes_ms):
        st = isi_stats(s)
        mean = f"{st['mean_isi_ms']:.2f}" if st["mean_isi_ms"] is not None else "-"
        cv = f"{st['cv_isi']:.3f}" if st["cv_isi"] is not None else "-"
        lines.append(f"  {p:6s} {i:6.1f} {len(s):7d} {mean:>12s} {cv:>6s}")
    lines.append(f"  ({len(names)} neurons x 16000 updates in {elapsed:.2f} s)")
    return lines


def run_demo(out: Path) -> int:
    out.mkdir(parents=True, exist_ok=True)
    try:
        from ..hdl.generate import generate_izhikevich
    except ImportError:
        generate_izhikevich = None
    if generate_izhikevich is not None:
        files = generate_izhikevich(out)
        print("generated hardware:")
        for f in files:
            print(f"  {f}")
    for line in golden_summary():
        print(line)
    return 0
