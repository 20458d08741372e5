"""Engines for the coincidence detector: one input schedule, five engines, one spike convention.

A run is a list of input spike ticks per source (a spike stamped with tick ``T`` is the
afferent spike at ``T dt`` ms) and a number of ticks; every engine reports the targets' spikes
with the golden convention (update of tick ``T`` -> ``(T + 1) dt``):

``golden``
    :func:`cuneate.golden.cuneate.simulate_cuneate` (float64 PSP sums, forward Euler) with the
    exact delays and weights.
``fixed``
    The bit-exact twin :class:`cuneate.hdl.cuneate.CoincidenceTwin`.
``amaranth``
    The Amaranth simulator on :class:`cuneate.hdl.cuneate.CoincidenceDetector`.
``icarus``, ``verilator``
    cocotb on the generated Verilog (bench ``cuneate.sim.benches.cuneate_tb``, test ``engine``;
    Icarus runs the yosys-lowered netlist).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..golden import cuneate as gcun
from ..hdl.cuneate import CoincidenceConfig, CoincidenceDetector, CoincidenceTwin, \
    coincidence_verilog
from ..hdl.izhikevich import CLAMP_KINDS

__all__ = ["COINCIDENCE_ENGINES", "CoincidenceRun", "run_coincidence", "events_by_tick"]

COINCIDENCE_ENGINES = ("golden", "fixed", "amaranth", "icarus", "verilator")


@dataclass
class CoincidenceRun:
    engine: str
    dt_ms: float
    n_ticks: int
    spikes_ms: list           # per target
    merged: int = 0
    wall_s: float = 0.0
    clamp_counts: dict = field(default_factory=dict)
    clamp_sticky: int = 0


def _clamps(words) -> tuple[dict, int]:
    """Per-kind counts and the sticky OR of per-update clamp words (bit order CLAMP_KINDS)."""
    counts = {k: 0 for k in CLAMP_KINDS}
    sticky = 0
    for w in words:
        sticky |= int(w)
        for b, k in enumerate(CLAMP_KINDS):
            counts[k] += (int(w) >> b) & 1
    return counts, sticky


def events_by_tick(input_ticks, n_sources: int) -> dict[int, list[int]]:
    """``{tick: [sources]}`` from per-source tick arrays (checked against the population)."""
    if len(input_ticks) != n_sources:
        raise ValueError(f"the input schedule has {len(input_ticks)} sources, the detector "
                         f"{n_sources}")
    out: dict[int, list[int]] = {}
    for s, ts in enumerate(input_ticks):
        for t in np.asarray(ts, dtype=np.int64).ravel():
            if t < 0:
                raise ValueError(f"source {s}: input tick {int(t)} < 0")
            out.setdefault(int(t), []).append(s)
    return out


def run_coincidence(engine: str, cfg: CoincidenceConfig, input_ticks, n_ticks: int,
                    build_dir: Path | None = None) -> CoincidenceRun:
    """Run ``n_ticks`` with ``input_ticks`` (one tick array per source) on ``engine``."""
    if engine not in COINCIDENCE_ENGINES:
        raise ValueError(f"unknown engine {engine!r}; known: {', '.join(COINCIDENCE_ENGINES)}")
    by_tick = events_by_tick(input_ticks, cfg.n_sources)
    dt = cfg.dt_ms
    t0 = time.perf_counter()
    merged = 0
    clamps: tuple[dict, int] = ({}, 0)
    if engine == "golden":
        times = [np.asarray(ts, dtype=np.float64) * dt for ts in input_ticks]
        r = gcun.simulate_cuneate(times, cfg.delays * dt, n_ticks * dt, dt_ms=dt, J=1.0,
                                  weights=cfg.weights_real,
                                  params=[cfg.param_sets[s] for s in cfg.target_sets_],
                                  tau_rise_ms=cfg.tau_rise_ms, tau_decay_ms=cfg.tau_decay_ms)
        spikes = [np.asarray(s) for s in r.spikes_ms]
    elif engine == "fixed":
        twin = CoincidenceTwin(cfg)
        spikes = twin.run(input_ticks, n_ticks)
        merged = twin.merged
        clamps = (dict(twin.clamp_counts), twin.clamp_sticky)
    else:
        if engine == "amaranth":
            pairs, merged, words = _run_amaranth(cfg, by_tick, n_ticks)
        else:
            pairs, merged, words = _run_cocotb(engine, cfg, by_tick, n_ticks, build_dir)
        clamps = _clamps(words)
        spikes = [np.array([(k + 1) * dt for k, t in sorted(pairs) if t == tgt])
                  for tgt in range(cfg.n_targets)]
    return CoincidenceRun(engine, dt, n_ticks, spikes, merged, time.perf_counter() - t0,
                          clamps[0], clamps[1])


def _run_amaranth(cfg: CoincidenceConfig, by_tick: dict, n_ticks: int):
    from amaranth.sim import Simulator
    dut = CoincidenceDetector(cfg)
    pairs, out, words = [], {}, []

    async def tb(ctx):
        for k in range(n_ticks):
            for s in by_tick.get(k, []):
                ctx.set(dut.in_valid, 1)
                ctx.set(dut.in_source, s)
                await ctx.tick()
            ctx.set(dut.in_valid, 0)
            ctx.set(dut.tick, 1)
            await ctx.tick()
            ctx.set(dut.tick, 0)
            while True:
                await ctx.tick()
                if ctx.get(dut.spike_valid):
                    pairs.append((ctx.get(dut.spike_tick), ctx.get(dut.spike_target)))
                if ctx.get(dut.upd_valid) and ctx.get(dut.upd_clamp):
                    words.append(ctx.get(dut.upd_clamp))
                if not ctx.get(dut.busy) and not ctx.get(dut.upd_valid):
                    break
        out["merged"] = ctx.get(dut.merged_count)

    sim = Simulator(dut)
    sim.add_clock(1.0 / cfg.clock_hz)
    sim.add_testbench(tb)
    sim.run()
    return pairs, out["merged"], words


def _run_cocotb(simulator: str, cfg: CoincidenceConfig, by_tick: dict, n_ticks: int,
                build_dir: Path | None):
    from .runner import run_cocotb

    def go(bd: Path):
        bd.mkdir(parents=True, exist_ok=True)
        src = bd / "coincidence_detector.v"
        src.write_text(coincidence_verilog(cfg, lowered=simulator == "icarus"))
        rep = run_cocotb(simulator, [src], "coincidence_detector",
                         "cuneate.sim.benches.cuneate_tb", bd,
                         config={"detector": cfg.to_kwargs(), "ticks": n_ticks,
                                 "events": {str(k): v for k, v in by_tick.items()}},
                         testcase="engine").report
        return [tuple(p) for p in rep["spikes"]], rep["merged"], rep["clamp_words"]
    if build_dir is not None:
        return go(Path(build_dir))
    with tempfile.TemporaryDirectory(prefix="cuneate-coinc-") as d:
        return go(Path(d))
