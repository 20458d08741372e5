"""Hardware engines behind ``cuneate simulate izhikevich --engine fixed|amaranth|icarus|verilator``.

All engines run the same core configuration and report spikes with the golden convention (a
spike produced by update k is at (k+1) dt ms), so their outputs are directly comparable:

``fixed``
    The bit-exact NumPy twin.
``amaranth``
    The Amaranth simulator on the core.
``icarus``, ``verilator``
    cocotb on the generated Verilog.

The simulated core runs with an external tick every ``max(n, 8)`` cycles (one update per clock,
no idle cycles) - the results depend only on ``update_hz`` (dt), not on the clock.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ..hdl.izhikevich import PIPELINE_DEPTH, IzhikevichConfig, IzhikevichTwin

__all__ = ["engine_config", "run_hardware_engine", "run_cocotb_engine", "HARDWARE_ENGINES"]

HARDWARE_ENGINES = ("fixed", "amaranth", "icarus", "verilator")
MIN_NEURONS = 8


def engine_config(params: dict, n: int, update_hz: float) -> IzhikevichConfig:
    """Core configuration for ``n`` neurons with one parameter set (padded to >= 8 neurons)."""
    N = max(n, MIN_NEURONS)
    return IzhikevichConfig(n_neurons=N, clock_hz=update_hz * N, update_hz=update_hz,
                            param_sets=((params["a"], params["b"], params["c"], params["d"]),),
                            tick_source="external", spike_fifo_depth=max(16, N + 4))


def _sweeps(duration_ms: float, dt_ms: float) -> int:
    return int(round(duration_ms / dt_ms))


def _to_times(spike_sweeps, n, dt_ms):
    return [[(k + 1) * dt_ms for k in sorted(spike_sweeps[i])] for i in range(n)]


def run_hardware_engine(engine: str, params: dict, currents, duration_ms: float,
                        update_hz: float = 16e3, clock_hz: float | None = None,
                        build_dir: Path | None = None):
    """Run ``engine``; returns ``(dt_ms, spikes_ms)`` with one list per neuron."""
    if engine not in HARDWARE_ENGINES:
        raise ValueError(f"unknown engine {engine!r}; known: {', '.join(HARDWARE_ENGINES)}")
    n = len(currents)
    cfg = engine_config(params, n, update_hz)
    dt_ms = cfg.dt_ms
    n_sweeps = _sweeps(duration_ms, dt_ms)
    cur = np.zeros(cfg.n_neurons)
    cur[:n] = currents
    for x in currents:
        if not cfg.I.contains(x):
            raise ValueError(f"current {x:g} is outside the core's input format {cfg.I} "
                             f"[{cfg.I.min_value:g}, {cfg.I.max_value:g}]")
    if engine == "fixed":
        twin = IzhikevichTwin(cfg)
        spikes = twin.run(cur, n_sweeps)
        return dt_ms, [s.tolist() for s in spikes[:n]]
    if engine == "amaranth":
        return dt_ms, _to_times(_run_amaranth(cfg, cur, n_sweeps), n, dt_ms)
    return dt_ms, _to_times(_run_cocotb(engine, cfg, cur, n_sweeps, build_dir), n, dt_ms)


def _run_amaranth(cfg: IzhikevichConfig, cur, n_sweeps: int):
    from amaranth.sim import Simulator
    from ..hdl.izhikevich import IzhikevichCore
    dut = IzhikevichCore(cfg)
    N = cfg.n_neurons
    raw = cfg.I.to_raw(cur)
    spikes = [[] for _ in range(N)]

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
            if ctx.get(dut.spike_valid):
                r = ctx.get(dut.spike_sweep)
                if r < last:
                    base += 1 << width
                last = r
                spikes[ctx.get(dut.spike_index)].append(base + r)
        assert not ctx.get(dut.overrun) and not ctx.get(dut.spike_overflow)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return spikes


def run_cocotb_engine(simulator: str, cfg: IzhikevichConfig, cur, n_sweeps: int,
                      build_dir: Path):
    """Generate the core for ``cfg`` and run the cocotb ``engine`` bench in ``build_dir``;
    returns the :class:`~cuneate.sim.runner.CocotbRun` (its report has the spike sweeps)."""
    from ..hdl.generate import izhikevich_verilog
    from .runner import run_cocotb
    build_dir = Path(build_dir)
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "izhikevich_core.v"
    src.write_text(izhikevich_verilog(cfg))
    core = {"n_neurons": cfg.n_neurons, "clock_hz": cfg.clock_hz, "update_hz": cfg.update_hz,
            "param_sets": [list(s) for s in cfg.sets], "tick_source": "external",
            "spike_fifo_depth": cfg.spike_fifo_depth}
    return run_cocotb(simulator, [src], "izhikevich_core", "cuneate.sim.benches.izhikevich_tb",
                      build_dir, config={"core": core, "currents": list(map(float, cur)),
                                         "sweeps": n_sweeps}, testcase="engine")


def _run_cocotb(simulator: str, cfg: IzhikevichConfig, cur, n_sweeps: int,
                build_dir: Path | None):
    if build_dir is not None:
        return run_cocotb_engine(simulator, cfg, cur, n_sweeps, build_dir).report["spike_sweeps"]
    with tempfile.TemporaryDirectory(prefix=f"cuneate-{simulator}-") as tmp:
        return run_cocotb_engine(simulator, cfg, cur, n_sweeps, Path(tmp)).report["spike_sweeps"]
