"""Engines for the coincidence detector: one input schedule, five engines, one spike convention.

A run is a list of input spike ticks per source (a spike stamped with tick ``T`` is the
afferent spike at ``T dt`` ms) and a number of ticks; every engine reports the targets' spikes
with the golden convention (update of tick ``T`` -> ``(T + 1) dt``):

``golden``
    :func:`cuneate.golden.coincidence.simulate_cuneate` (float64 PSP sums, forward Euler) with the
    exact delays and weights.
``fixed``
    The bit-exact twin :class:`cuneate.hdl.coincidence.CoincidenceTwin`.
``amaranth``
    The Amaranth simulator on :class:`cuneate.hdl.coincidence.CoincidenceDetector`.
``icarus``, ``verilator``
    cocotb on the generated Verilog (bench :mod:`cuneate.sim.coincidence.bench`, test
    ``engine``; Icarus runs the yosys-lowered netlist).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...golden import coincidence as gcun
from ...hdl.coincidence import (CLAMP_KINDS, CoincidenceConfig, CoincidenceDetector,
                                CoincidenceTwin, coincidence_verilog)
from ..engines.amaranth import simulate
from ..engines.registry import block_engines, check_engine
from ..engines.run import EngineRun

__all__ = ["COINCIDENCE_ENGINES", "CoincidenceRun", "run_coincidence", "events_by_tick",
           "clamp_tally"]

#: The engines the coincidence block runs on (the registry's list).
COINCIDENCE_ENGINES = block_engines("coincidence")
#: A coincidence run is an :class:`~cuneate.sim.engines.run.EngineRun`.
CoincidenceRun = EngineRun


def clamp_tally(words) -> tuple[dict, int]:
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
    check_engine("coincidence", engine)
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
        clamps = clamp_tally(words)
        spikes = [np.array([(k + 1) * dt for k, t in sorted(pairs) if t == tgt])
                  for tgt in range(cfg.n_targets)]
    return EngineRun(engine, dt, n_ticks, spikes, clamps[0], clamps[1],
                     time.perf_counter() - t0, {"merged_count": int(merged)})


async def pulse_tick(ctx, dut, sources) -> None:
    """Input spike events ``sources`` (one per cycle), then one ``tick`` pulse."""
    for s in sources:
        ctx.set(dut.in_valid, 1)
        ctx.set(dut.in_source, s)
        await ctx.tick()
    ctx.set(dut.in_valid, 0)
    ctx.set(dut.tick, 1)
    await ctx.tick()
    ctx.set(dut.tick, 0)


def _run_amaranth(cfg: CoincidenceConfig, by_tick: dict, n_ticks: int):
    dut = CoincidenceDetector(cfg)
    pairs, out, words = [], {}, []

    def sample(ctx) -> bool:
        """Record this cycle's output spike and clamp word; False once the tick is done."""
        if ctx.get(dut.spike_valid):
            pairs.append((ctx.get(dut.spike_tick), ctx.get(dut.spike_target)))
        if ctx.get(dut.upd_valid) and ctx.get(dut.upd_clamp):
            words.append(ctx.get(dut.upd_clamp))
        return bool(ctx.get(dut.busy) or ctx.get(dut.upd_valid))

    async def tb(ctx):
        for k in range(n_ticks):
            await pulse_tick(ctx, dut, by_tick.get(k, []))
            await ctx.tick()
            while sample(ctx):
                await ctx.tick()
        out["merged"] = ctx.get(dut.merged_count)

    simulate(dut, tb, cfg.clock_hz)
    return pairs, out["merged"], words


def _run_cocotb(simulator: str, cfg: CoincidenceConfig, by_tick: dict, n_ticks: int,
                build_dir: Path | None):
    from ..engines.cocotb import run_engine_bench
    rep = run_engine_bench(simulator, lambda low: coincidence_verilog(cfg, lowered=low),
                           "coincidence_detector", "coincidence",
                           {"detector": cfg.to_kwargs(), "ticks": n_ticks, "events":
                            {str(k): v for k, v in by_tick.items()}}, build_dir)
    return [tuple(p) for p in rep["spikes"]], rep["merged"], rep["clamp_words"]
