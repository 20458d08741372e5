"""Simulation speed of every engine: NumPy twin, float golden model, cocotb on Icarus/Verilator,
and the Amaranth simulator.

Figures are printed and written to ``benchmarks/results/speed_*.json``. Only sanity is asserted
(runs complete, figures positive); speeds depend on the machine. "x real time" compares with the
core itself, which does ``n_neurons * update_hz`` updates per second (16 kHz per neuron).
"""

from __future__ import annotations

import importlib.util
import statistics
import time
from pathlib import Path

import numpy as np
import pytest

from cuneate.golden import izhikevich as golden
from cuneate.hdl.izhikevich import IzhikevichConfig, IzhikevichTwin

pytestmark = pytest.mark.benchmark

UPDATE_HZ = 16e3
SIZES = (2500, 10000)
REPEATS = 3


def _median_time(fn, repeats: int = REPEATS) -> tuple[float, list[float]]:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), times


# ----------------------------------------------------------------------------------------------
# NumPy: bit-exact twin and float golden model

def twin_rate(n: int, sweeps: int = 200) -> dict:
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=UPDATE_HZ * n, update_hz=UPDATE_HZ)
    twin = IzhikevichTwin(cfg)
    twin.set_currents(10.0)
    for _ in range(5):                                   # warm-up
        twin.sweep()
    spikes = [0]

    def run():
        spikes[0] = 0                                    # spikes of the last repeat
        for _ in range(sweeps):
            spikes[0] += int(twin.sweep().sum())

    t, times = _median_time(run)
    ups = n * sweeps / t
    return {"engine": "twin (int64)", "neurons": n, "updates": n * sweeps, "median_s": t,
            "updates_per_s": ups, "x_real_time": ups / (n * UPDATE_HZ),
            "spikes": spikes[0], "times_s": times}


def golden_rate(n: int, dtype=np.float64, duration_ms: float = 20.0) -> dict:
    dt = golden.DEFAULT_DT_MS
    steps = int(round(duration_ms / dt))
    golden.simulate("RS", 10.0, n_steps=5, n_neurons=n, dtype=dtype)     # warm-up
    out = {}

    def run():
        out["r"] = golden.simulate("RS", 10.0, duration_ms=duration_ms, n_neurons=n,
                                   dtype=dtype)

    t, times = _median_time(run)
    ups = n * steps / t
    return {"engine": f"golden ({np.dtype(dtype).name})", "neurons": n, "updates": n * steps,
            "median_s": t, "updates_per_s": ups, "x_real_time": ups / (n * UPDATE_HZ),
            "spikes": int(np.sum(out["r"].spike_counts)), "times_s": times}


def test_numpy_engines(bench):
    rows = []
    for n in SIZES:
        rows.append(twin_rate(n))
        rows.append(golden_rate(n, np.float64))
        rows.append(golden_rate(n, np.float32))
    bench.report("speed_numpy", "NumPy engines: updates per second (RS, I = 10 mV/ms, median "
                 f"of {REPEATS})", rows,
                 columns=["engine", "neurons", "updates", "median_s", "updates_per_s",
                          "x_real_time", "spikes"])
    for r in rows:
        assert r["updates_per_s"] > 0 and r["spikes"] > 0, r


# ----------------------------------------------------------------------------------------------
# LIF and coincidence-detector twins: stage functions against the compiled kernel

def _lif_program(n: int, sweeps: int, n_inputs: int = 8):
    from cuneate.hdl.lif import LifConfig
    rng = np.random.default_rng(0)
    cfg = LifConfig(n_neurons=n, clock_hz=UPDATE_HZ * n, update_hz=UPDATE_HZ,
                    weights=rng.uniform(-10, 40, (n, n_inputs)),
                    param_sets=[{"tau_m_ms": 10.0, "t_ref_ms": 1.0}])
    cur = np.asarray(cfg.I.to_raw(np.linspace(0.0, 30.0, n)), dtype=np.int64)
    return cfg, cur, rng.random((sweeps, n_inputs)) < 0.1


def lif_rates(n: int, sweeps: int = 2000) -> list[dict]:
    from cuneate.hdl.lif import LifTwin
    cfg, cur, x = _lif_program(n, sweeps)
    rows, spikes = [], {}
    for kernel in ("stages", "numba"):
        LifTwin(cfg, kernel=kernel).run_raw(cur, 2, x[:2])             # warm-up / compile
        out = {}

        def run():
            twin = LifTwin(cfg, kernel=kernel)
            out["k"] = twin.run_raw(cur, sweeps, x)[0].size

        t, times = _median_time(run)
        spikes[kernel] = out["k"]
        rows.append({"engine": f"LIF twin ({kernel})", "neurons": n, "updates": n * sweeps,
                     "median_s": t, "updates_per_s": n * sweeps / t, "spikes": out["k"],
                     "times_s": times})
    for r in rows:
        r["speedup_vs_stages"] = rows[0]["median_s"] / r["median_s"]
        r["spikes_equal"] = spikes["stages"] == spikes["numba"]
    return rows


def coincidence_rates(targets: int, ticks: int = 2000, sources: int = 8) -> list[dict]:
    from cuneate.hdl.coincidence import CoincidenceConfig, CoincidenceTwin
    rng = np.random.default_rng(1)
    cfg = CoincidenceConfig(n_sources=sources, n_targets=targets,
                            delays_ticks=rng.integers(0, 64, (targets, sources)),
                            weights=rng.uniform(0.5, 4.0, (targets, sources)),
                            max_delay_ticks=64, clock_hz=UPDATE_HZ * targets * (sources + 8)
                            + 2 * UPDATE_HZ)
    ins = [np.sort(rng.integers(0, ticks, ticks // 8)) for _ in range(sources)]
    rows, spikes = [], {}
    for kernel in ("stages", "numba"):
        CoincidenceTwin(cfg, kernel=kernel).run(ins, 2)                 # warm-up / compile
        out = {}

        def run():
            out["n"] = sum(map(len, CoincidenceTwin(cfg, kernel=kernel).run(ins, ticks)))

        t, times = _median_time(run)
        spikes[kernel] = out["n"]
        rows.append({"engine": f"coincidence twin ({kernel})", "neurons": targets,
                     "updates": targets * ticks, "median_s": t,
                     "updates_per_s": targets * ticks / t, "spikes": out["n"],
                     "times_s": times})
    for r in rows:
        r["speedup_vs_stages"] = rows[0]["median_s"] / r["median_s"]
        r["spikes_equal"] = spikes["stages"] == spikes["numba"]
    return rows


def test_lif_and_coincidence_twins(bench):
    rows = []
    for n in SIZES:
        rows += lif_rates(n)
    for m in (256, 2048):
        rows += coincidence_rates(m)
    bench.report("speed_lif_coincidence", "LIF (8 weighted inputs, 10 % active) and coincidence "
                 "(8 delayed afferents) twins: stage functions vs compiled kernel, median of "
                 f"{REPEATS}", rows,
                 columns=["engine", "neurons", "updates", "median_s", "updates_per_s",
                          "speedup_vs_stages", "spikes", "spikes_equal"])
    for r in rows:
        assert r["updates_per_s"] > 0 and r["spikes"] > 0 and r["spikes_equal"], r


# ----------------------------------------------------------------------------------------------
# cocotb on the generated Verilog

def _scoreboard_cases() -> dict:
    """The CASES table of tests/sim/test_izhikevich_cocotb.py (loaded by path, so the benchmark
    always measures the configuration the test suite checks)."""
    path = Path(__file__).resolve().parents[1] / "tests" / "sim" / "test_izhikevich_cocotb.py"
    spec = importlib.util.spec_from_file_location("_bench_izh_cocotb_cases", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.CASES


def cocotb_scoreboard_rate(simulator: str, build_root: Path, case: str = "n240_mixed") -> dict:
    from cuneate.hdl.izhikevich import izhikevich_verilog
    from cuneate.sim.izhikevich.bench import make_config
    from cuneate.sim.engines.cocotb import run_cocotb

    spec = dict(_scoreboard_cases()[case], seed=11)
    cfg = make_config(spec["core"])
    build_dir = build_root / f"scoreboard_{case}_{simulator}"
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "izhikevich_core.v"
    src.write_text(izhikevich_verilog(cfg))
    t0 = time.perf_counter()
    run = run_cocotb(simulator, [src], "izhikevich_core", "cuneate.sim.izhikevich.bench",
                     build_dir, config=spec, testcase="scoreboard")
    total = time.perf_counter() - t0
    r = run.report
    return {"simulator": simulator, "test": f"scoreboard {case}", "neurons": cfg.n_neurons,
            "cycles": r["cycles"], "sim_wall_s": r["wall_s"], "cycles_per_s": r["cycles_per_s"],
            "build_and_run_s": total, "updates_checked": r["updates_checked"],
            "twin_mismatches": r["twin_mismatches"]}


def cocotb_engine_rate(simulator: str, build_root: Path, n: int = 240,
                       sweeps: int = 100) -> dict:
    from cuneate.sim.izhikevich.engines import run_engine

    core = {"param_sets": (golden.PRESETS["RS"].as_tuple(),), "update_hz": UPDATE_HZ}
    currents = np.linspace(0.0, 40.0, n)
    t0 = time.perf_counter()
    run = run_engine(simulator, core, currents, sweeps * 1000.0 / UPDATE_HZ,
                     build_root / f"engine_n{n}_{simulator}")
    total = time.perf_counter() - t0
    r = run.counters
    return {"simulator": simulator, "test": f"engine n{n} x {sweeps} sweeps",
            "neurons": n, "cycles": r["cycles"], "sim_wall_s": r["wall_s"],
            "cycles_per_s": r["cycles"] / r["wall_s"], "build_and_run_s": total,
            "spikes": int(run.counts().sum())}


@pytest.mark.parametrize("simulator", ["icarus", "verilator"])
def test_cocotb(simulator, bench, bench_build):
    rows = [cocotb_scoreboard_rate(simulator, bench_build),
            cocotb_engine_rate(simulator, bench_build)]
    bench.report(f"speed_cocotb_{simulator}", f"cocotb on {simulator}: simulated cycles per "
                 "second (Python bench in the loop every cycle)", rows,
                 columns=["simulator", "test", "neurons", "cycles", "sim_wall_s",
                          "cycles_per_s", "build_and_run_s"])
    assert rows[0]["twin_mismatches"] == 0 and rows[0]["updates_checked"] > 0
    assert rows[1]["spikes"] > 0
    for r in rows:
        assert r["cycles"] > 0 and r["cycles_per_s"] > 0, r


# ----------------------------------------------------------------------------------------------
# Amaranth simulator

def amaranth_rate(n: int = 16, cycles: int = 4000) -> list[dict]:
    """Cycles per second of the Amaranth simulator on an ``n``-neuron core, (a) free-running
    (internal tick, no testbench) and (b) driven per cycle by an async testbench that sets the
    external tick and polls the spike stream, like the ``amaranth`` engine does."""
    from amaranth.sim import Simulator
    from cuneate.hdl.izhikevich import IzhikevichCore

    rows = []
    # (a) free-running
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=UPDATE_HZ * n, update_hz=UPDATE_HZ)
    t0 = time.perf_counter()
    dut = IzhikevichCore(cfg)
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    t1 = time.perf_counter()
    sim.run_until(100e-6)                          # first cycles include compilation
    t2 = time.perf_counter()
    sim.run_until((100 + cycles) * 1e-6)
    t3 = time.perf_counter()
    rows.append({"mode": "free-running (internal tick)", "neurons": n, "cycles": cycles,
                 "setup_s": (t1 - t0) + (t2 - t1), "run_s": t3 - t2,
                 "cycles_per_s": cycles / (t3 - t2)})

    # (b) the `amaranth` engine of `cuneate simulate` (testbench-driven, external tick)
    from cuneate.golden.izhikevich import PRESETS
    from cuneate.sim.izhikevich.engines import run_engine
    core = {"param_sets": (PRESETS["RS"].as_tuple(),), "update_hz": UPDATE_HZ}
    currents = list(np.linspace(0.0, 40.0, n))
    sweeps = cycles // n
    t0 = time.perf_counter()
    spikes = run_engine("amaranth", core, currents, sweeps * 1000.0 / UPDATE_HZ).spikes_ms
    run_s = time.perf_counter() - t0
    rows.append({"mode": "amaranth engine (external tick)", "neurons": n,
                 "cycles": sweeps * n, "setup_s": 0.0, "run_s": run_s,
                 "cycles_per_s": sweeps * n / run_s, "spikes": sum(map(len, spikes))})
    return rows


def test_amaranth_simulator(bench):
    rows = amaranth_rate()
    bench.report("speed_amaranth", "Amaranth simulator: cycles per second (small core)", rows,
                 columns=["mode", "neurons", "cycles", "setup_s", "run_s", "cycles_per_s"])
    for r in rows:
        assert r["cycles_per_s"] > 0, r
    assert rows[1]["spikes"] > 0


# ----------------------------------------------------------------------------------------------
# Brian2 as the peer: the same work in one run (RS, currents 0..20, dt 1/16 ms, 1 s, Euler)

PEER_SIZES = (1000, 10000, 100000)
PEER_TARGETS = ("numpy", "cython", "cpp_standalone")
#: cpp_standalone on one thread too: OpenMP's barriers (several per step) stall when other
#: work shares the cores, so its single-thread figure is the steadier one under load
PEER_SINGLE = "cpp_standalone"
#: the goals of the speed table: golden and twin against Brian2's cython and C++ targets
PEER_GOALS = {"cython": 3.0, "cpp_standalone": 1.5}


def _brian2_python(bench_build: Path) -> tuple[str | None, str]:
    """Brian2 in its own environment (it needs numpy < 2.3): ``build/bench/brian2-venv``,
    created on first use. Returns (python, reason if unavailable)."""
    import subprocess
    import sys
    venv = bench_build / "brian2-venv"
    py = venv / "bin" / "python"
    if not py.exists():
        r = subprocess.run([sys.executable, "-m", "venv", str(venv)], capture_output=True,
                           text=True)
        if r.returncode:
            return None, f"venv failed: {r.stderr.strip()[-200:]}"
        r = subprocess.run([str(py), "-m", "pip", "install", "-q", "brian2", "numpy<2.3"],
                           capture_output=True, text=True)
        if r.returncode:
            return None, f"pip install brian2 failed: {r.stderr.strip()[-300:]}"
    return str(py), ""


def _peer(py: str, target: str, n: int, threads: int | None = None) -> dict:
    import json
    import subprocess
    script = Path(__file__).with_name("brian2_peer.py")
    # the first run of a target compiles (cython: cached on disk; standalone: every run);
    # the cython figure is the second run's
    for _ in range(2 if target == "cython" else 1):
        r = subprocess.run([py, str(script), target, str(n), "1000"]
                           + ([str(threads)] if threads else []), capture_output=True,
                           text=True, timeout=3600)
    if r.returncode:
        return {"target": target, "neurons": n, "error": r.stderr.strip()[-200:]}
    rec = json.loads(r.stdout.strip().splitlines()[-1])
    if threads:
        rec["target"] += f" ({threads} thread)"
    return rec


def _ours(n: int) -> list[dict]:
    cur = np.linspace(0.0, 20.0, n)
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=UPDATE_HZ * n, update_hz=UPDATE_HZ)
    IzhikevichTwin(cfg).run(cur, 16000)                 # compile (or load) its loop
    t0 = time.perf_counter()
    tsp = IzhikevichTwin(cfg).run(cur, 16000)
    tt = time.perf_counter() - t0
    # per-neuron constants as a zero-copy (steps, neurons) broadcast: the compiled loop runs
    # every step of a thread's neurons in one call
    golden.simulate("RS", np.broadcast_to(cur, (16, n)), n_neurons=n, duration_ms=1.0)
    t0 = time.perf_counter()
    g = golden.simulate("RS", np.broadcast_to(cur, (16000, n)), n_neurons=n,
                        duration_ms=1000.0)
    tg = time.perf_counter() - t0
    return [{"target": "cuneate golden (float64)", "neurons": n, "run_s": tg,
             "updates_per_s": n * 16000 / tg, "spikes": int(sum(map(len, g.spikes_ms)))},
            {"target": "cuneate twin (fixed point)", "neurons": n, "run_s": tt,
             "updates_per_s": n * 16000 / tt, "spikes": int(sum(map(len, tsp)))}]


def test_against_brian2(bench, bench_build):
    """cuneate's golden and twin against Brian2's numpy, cython and cpp_standalone (OpenMP on
    every core) targets on the same work, in one run; ratios against the goals
    (:data:`PEER_GOALS`), spike-count agreement, the load of the machine before and after;
    the bandwidth bound."""
    import os
    py, why = _brian2_python(Path(bench_build))
    load_before = os.getloadavg()
    rows, versions = [], set()
    for n in PEER_SIZES:
        ours = _ours(n)
        peers = ([_peer(py, t, n) for t in PEER_TARGETS] + [_peer(py, PEER_SINGLE, n, 1)]
                 if py else [])
        versions |= {p["brian2"] for p in peers if "brian2" in p}
        for o in ours:
            for p in peers:
                if "updates_per_s" in p:
                    x = o["updates_per_s"] / p["updates_per_s"]
                    o[f"x {p['target']}"] = x
                    goal = PEER_GOALS.get(p["target"])
                    if goal is not None:
                        o[f"goal {p['target']}"] = f">= {goal:g}: " + \
                            ("met" if x >= goal else "NOT met")
            if peers and "spikes" in peers[0]:
                o["brian2 spikes"] = peers[0]["spikes"]
                if "golden" in o["target"]:         # the same scheme (the twin's is fixed point)
                    o["spikes equal"] = o["spikes"] == peers[0]["spikes"]
        rows += ours + peers
    # bandwidth bound of the twin: bytes touched per update (v, u, I, set: 4 x 8 B read, 2 x 8 B
    # written) against a measured copy bandwidth
    a = np.ones(200_000_000 // 8)
    b = np.empty_like(a)
    np.copyto(b, a)                                       # fault the pages in first
    t0 = time.perf_counter()
    for _ in range(5):
        np.copyto(b, a)
    bw = 5 * 2 * a.nbytes / (time.perf_counter() - t0)
    rows.append({"target": "copy bandwidth bound (48 B per update, 100k+ neurons)",
                 "neurons": None,
                 "updates_per_s": bw / 48})
    load = (load_before, os.getloadavg())
    title = ("RS, currents 0..20 mV/ms, dt 1/16 ms, 1 s, Euler: updates per second; Brian2 "
             f"{', '.join(sorted(versions)) or '-'} (targets {', '.join(PEER_TARGETS)}, "
             f"cpp_standalone on {os.cpu_count()} OpenMP threads); load average before "
             f"{load[0][0]:.2f}, after {load[1][0]:.2f}")
    if not py:
        title += f" (Brian2 unavailable: {why})"
    bench.report("speed_brian2", title, rows, extra={"load_average": load,
                                                      "brian2": sorted(versions)},
                 columns=["target", "neurons", "run_s", "updates_per_s", "spikes",
                          "x cython", "goal cython", "x cpp_standalone",
                          "goal cpp_standalone", "x cpp_standalone (1 thread)",
                          "brian2 spikes", "spikes equal", "threads"])
    assert all(r["updates_per_s"] > 0 for r in rows if "updates_per_s" in r)
