"""Brian2 on the speed benchmark's work, run in Brian2's own environment (numpy < 2.3).

``python brian2_peer.py TARGET N DURATION_MS [THREADS]`` prints one JSON line: the run time
(network ``run`` only; for ``cpp_standalone`` the time the compiled binary reports, without code
generation and compilation), updates per second, the spike count and Brian2's version.
``cpp_standalone`` runs on ``THREADS`` OpenMP threads (default: every core). The work: N Izhikevich RS
neurons, constant currents spread evenly over 0..20 mV/ms, forward Euler, dt = 1/16 ms, from
v = -65 mV, u = b v (the golden model's start), threshold v >= 30 mV, reset v = c, u += d.
"""

import json
import sys
import tempfile
import time


def main(target: str, n: int, duration_ms: float, threads: int | None = None) -> dict:
    import os

    import brian2
    import numpy as np
    from brian2 import (NeuronGroup, SpikeMonitor, defaultclock, device, ms, prefs, run,
                        set_device)
    threads = threads or os.cpu_count() or 1
    if target == "cpp_standalone":
        d = tempfile.mkdtemp(prefix="brian2-standalone-")
        set_device("cpp_standalone", directory=d, build_on_run=True)
        prefs.devices.cpp_standalone.openmp_threads = threads
    else:
        prefs.codegen.target = target
    defaultclock.dt = (1.0 / 16.0) * ms
    eqs = """dv/dt = (0.04*v**2 + 5*v + 140 - u + I) / ms : 1
             du/dt = a*(b*v - u) / ms : 1
             I : 1 (constant)
             a : 1 (constant)
             b : 1 (constant)"""
    g = NeuronGroup(n, eqs, threshold="v >= 30", reset="v = -65; u += 8", method="euler")
    g.a, g.b = 0.02, 0.2
    g.I = np.linspace(0.0, 20.0, n)
    g.v = -65.0
    g.u = 0.2 * -65.0
    mon = SpikeMonitor(g, record=False)
    t0 = time.perf_counter()
    run(duration_ms * ms)
    wall = time.perf_counter() - t0
    if target == "cpp_standalone":
        wall = float(device._last_run_time)
    steps = int(round(duration_ms * 16))
    return {"target": target, "neurons": n, "run_s": wall, "updates_per_s": n * steps / wall,
            "spikes": int(mon.num_spikes), "brian2": brian2.__version__,
            "threads": threads if target == "cpp_standalone" else 1}


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1], int(sys.argv[2]), float(sys.argv[3]),
                          int(sys.argv[4]) if len(sys.argv) > 4 else None)))
