"""Hardware engines behind ``cuneate simulate izhikevich --engine fixed|amaranth|icarus|verilator``.

All engines run the same core configuration and report spikes with the golden convention (a
spike produced by update k is at (k+1) dt ms), so their outputs are directly comparable:

``fixed``
    The bit-exact NumPy twin.
``amaranth``
    The Amaranth simulator on the core.
``icarus``, ``verilator``
    cocotb on the generated Verilog.
``verilator-fast``
    The generated Verilog compiled by Verilator with a C++ harness
    (:mod:`cuneate.sim.verilator_harness`): no Python per cycle, same spikes and clamp counters.

A core is described by its constructor keywords (``core``, as for
:class:`~cuneate.hdl.izhikevich.IzhikevichConfig`); :func:`engine_core` turns them into the
configuration an engine simulates: the same parameter sets, formats, accepted range and
rounding, at least 8 neurons (unused ones idle at zero current), and an external tick every
``max(n, 8)`` cycles (one update per clock, no idle cycles) - results depend only on the update
rate (dt), not on the clock. Every engine also reports the core's clamp counters.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..hdl.izhikevich import CLAMP_KINDS, PIPELINE_DEPTH, IzhikevichConfig, IzhikevichTwin

__all__ = ["HARDWARE_ENGINES", "EngineRun", "engine_core", "run_engine", "engine_config",
           "run_hardware_engine", "run_cocotb_engine", "MIN_NEURONS"]

HARDWARE_ENGINES = ("fixed", "amaranth", "icarus", "verilator", "verilator-fast")
MIN_NEURONS = 8


@dataclass
class EngineRun:
    """What an engine run produced."""

    engine: str
    dt_ms: float
    n_sweeps: int
    spikes_ms: list[list[float]]
    clamp_counts: dict = field(default_factory=dict)
    clamp_sticky: dict = field(default_factory=dict)
    wall_s: float = 0.0


def engine_core(core: dict, n: int) -> IzhikevichConfig:
    """The configuration an engine simulates for ``n`` neurons of the core ``core``
    (constructor keywords); raises :class:`~cuneate.hdl.izhikevich.ConfigError`."""
    N = max(n, MIN_NEURONS)
    kw = dict(core)
    update_hz = float(kw.get("update_hz", 16e3))
    kw.update(n_neurons=N, clock_hz=update_hz * N, update_hz=update_hz,
              tick_source="external", spike_fifo_depth=max(16, N + 4))
    ns = kw.get("neuron_sets")
    if ns is not None:
        ns = list(ns)[:n]
        kw["neuron_sets"] = ns + [0] * (N - len(ns))
    for k in ("v_init", "u_init"):
        if kw.pop(k, None) is not None:
            raise ValueError("engines start every neuron at its set's initial state "
                             f"({k} is not an engine option)")
    return IzhikevichConfig.from_kwargs(kw)


def engine_config(params: dict, n: int, update_hz: float) -> IzhikevichConfig:
    """Core configuration for ``n`` neurons with one parameter set ``params`` (a, b, c, d)."""
    return engine_core({"param_sets": ((params["a"], params["b"], params["c"], params["d"]),),
                        "update_hz": update_hz}, n)


def _sweeps(duration_ms: float, dt_ms: float) -> int:
    return int(round(duration_ms / dt_ms))


def _to_times(spike_sweeps, n, dt_ms):
    return [[(k + 1) * dt_ms for k in sorted(spike_sweeps[i])] for i in range(n)]


def run_engine(engine: str, core: dict, currents, duration_ms: float,
               build_dir: Path | None = None, progress=None) -> EngineRun:
    """Run ``engine`` on ``len(currents)`` neurons of ``core`` with constant currents (mV/ms).

    ``progress``, if given, is called with the number of sweeps done (the twin and the Amaranth
    simulator report as they go; cocotb runs report from the simulator's progress file).
    """
    if engine not in HARDWARE_ENGINES:
        raise ValueError(f"unknown engine {engine!r}; known: {', '.join(HARDWARE_ENGINES)}")
    n = len(currents)
    cfg = engine_core(core, n)
    n_sweeps = _sweeps(duration_ms, cfg.dt_ms)
    cur = np.zeros(cfg.n_neurons)
    cur[:n] = currents
    for x in currents:
        if not cfg.I.contains(x):
            raise ValueError(f"current {x:g} is outside the core's input format {cfg.I} "
                             f"[{cfg.I.min_value:g}, {cfg.I.max_value:g}]")
    t0 = time.perf_counter()
    if engine == "fixed":
        twin = IzhikevichTwin(cfg)
        spikes = [s.tolist() for s in twin.run(cur, n_sweeps, progress=progress)[:n]]
        rep = twin.clamp_report()
        return EngineRun(engine, cfg.dt_ms, n_sweeps, spikes, rep["counts"], rep["sticky"],
                         time.perf_counter() - t0)
    if engine == "verilator-fast":
        from .verilator_harness import run_harness
        run = run_harness(cfg, cur, n_sweeps, build_root=build_dir)
        if progress is not None:
            progress(n_sweeps)
        ks = run.spikes_per_neuron(n)
        return EngineRun(engine, cfg.dt_ms, n_sweeps, [((k + 1) * cfg.dt_ms).tolist() for k in ks],
                         dict(run.summary["clamp_counts"]), run.clamp_sticky(),
                         time.perf_counter() - t0)
    if engine == "amaranth":
        sweeps, counts, sticky = _run_amaranth(cfg, cur, n_sweeps, progress)
    else:
        rep = _run_cocotb(engine, cfg, cur, n_sweeps, build_dir, progress)
        sweeps, counts, sticky = rep["spike_sweeps"], rep["clamp_counts"], rep["clamp_sticky"]
    return EngineRun(engine, cfg.dt_ms, n_sweeps, _to_times(sweeps, n, cfg.dt_ms), counts,
                     sticky, time.perf_counter() - t0)


def run_hardware_engine(engine: str, params: dict, currents, duration_ms: float,
                        update_hz: float = 16e3, clock_hz: float | None = None,
                        build_dir: Path | None = None):
    """Run ``engine`` with one parameter set (a, b, c, d); returns ``(dt_ms, spikes_ms)``."""
    core = {"param_sets": ((params["a"], params["b"], params["c"], params["d"]),),
            "update_hz": update_hz}
    r = run_engine(engine, core, currents, duration_ms, build_dir)
    return r.dt_ms, r.spikes_ms


def _run_amaranth(cfg: IzhikevichConfig, cur, n_sweeps: int, progress=None):
    from amaranth.sim import Simulator
    from ..hdl.izhikevich import IzhikevichCore
    dut = IzhikevichCore(cfg)
    N = cfg.n_neurons
    raw = cfg.I.to_raw(cur)
    spikes = [[] for _ in range(N)]
    counts = {k: 0 for k in CLAMP_KINDS}
    out = {}

    async def bench(ctx):
        ctx.set(dut.spike_ready, 1)
        for i in range(N):
            ctx.set(dut.i_wr_en, 1)
            ctx.set(dut.i_wr_addr, i)
            ctx.set(dut.i_wr_data, int(raw[i]))
            await ctx.tick()
        ctx.set(dut.i_wr_en, 0)
        width = cfg.sweep_number_width
        base, last = 0, 0
        for c in range(n_sweeps * N + PIPELINE_DEPTH + cfg.spike_fifo_depth + 4):
            ctx.set(dut.tick, int(c % N == 0 and c // N < n_sweeps))
            await ctx.tick()
            if ctx.get(dut.sweep_done):
                for k in CLAMP_KINDS:
                    counts[k] += ctx.get(getattr(dut, f"sweep_clamps_{k}"))
                if progress is not None and (c // N + 1) % 1000 == 0:
                    progress(c // N + 1)
            if ctx.get(dut.spike_valid):
                r = ctx.get(dut.spike_sweep)
                if r < last:
                    base += 1 << width
                last = r
                spikes[ctx.get(dut.spike_index)].append(base + r)
        assert not ctx.get(dut.overrun) and not ctx.get(dut.spike_overflow)
        out["sticky"] = ctx.get(dut.clamp_flags)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    sticky = {k: bool(out["sticky"] >> i & 1) for i, k in enumerate(CLAMP_KINDS)}
    return spikes, counts, sticky


def run_cocotb_engine(simulator: str, cfg: IzhikevichConfig, cur, n_sweeps: int,
                      build_dir: Path, progress=None):
    """Generate the core for ``cfg`` and run the cocotb ``engine`` bench in ``build_dir``;
    returns the :class:`~cuneate.sim.runner.CocotbRun` (its report has the spike sweeps and the
    clamp counters)."""
    from ..hdl.izhikevich import izhikevich_verilog
    from .runner import run_cocotb
    build_dir = Path(build_dir)
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "izhikevich_core.v"
    src.write_text(izhikevich_verilog(cfg))
    return run_cocotb(simulator, [src], "izhikevich_core", "cuneate.sim.benches.izhikevich_tb",
                      build_dir, config={"core": cfg.to_kwargs(),
                                         "currents": list(map(float, cur)),
                                         "sweeps": n_sweeps}, testcase="engine",
                      progress=progress)


def _run_cocotb(simulator: str, cfg: IzhikevichConfig, cur, n_sweeps: int,
                build_dir: Path | None, progress=None) -> dict:
    if build_dir is not None:
        return run_cocotb_engine(simulator, cfg, cur, n_sweeps, build_dir, progress).report
    with tempfile.TemporaryDirectory(prefix=f"cuneate-{simulator}-") as tmp:
        return run_cocotb_engine(simulator, cfg, cur, n_sweeps, Path(tmp), progress).report
