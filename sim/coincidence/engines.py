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

:class:`CoincidenceEngine` is the block's engine interface; each engine implements it and
registers itself (:func:`~cuneate.sim.engines.registry.implements`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...golden import coincidence as gcun
from ...golden import izhikevich as giz
from ...hdl.coincidence import (CLAMP_KINDS, CoincidenceConfig, CoincidenceDetector,
                                CoincidenceTwin, coincidence_verilog)
from ..engines.amaranth import simulate
from ..engines.engine import BlockEngine
from ..engines.registry import engine_for, implements
from ..engines.run import EngineRun, times_from_pairs

__all__ = ["CoincidenceEngine", "run_coincidence", "events_by_tick",
           "clamp_tally"]


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


class CoincidenceEngine(BlockEngine):
    """The coincidence detector on one engine: :meth:`run` input spike ticks."""

    block = "coincidence"

    def run(self, cfg: CoincidenceConfig, input_ticks, n_ticks: int) -> EngineRun:
        """``n_ticks`` ticks with ``input_ticks`` (one tick array per source): the targets'
        spikes, the input events of those ticks (``events``) and the ones merged with an
        earlier one of the same tick (``merged_count``), the clamps."""
        by_tick = events_by_tick(input_ticks, cfg.n_sources)
        t0 = time.perf_counter()
        spikes, merged, counts, sticky = self.spikes(cfg, input_ticks, by_tick, n_ticks)
        events = sum(len(s) for k, s in by_tick.items() if k < n_ticks)
        return EngineRun(self.name, cfg.dt_ms, n_ticks, spikes, counts, sticky,
                         time.perf_counter() - t0,
                         {"events": events, "merged_count": int(merged)})

    def spikes(self, cfg, input_ticks, by_tick: dict, n_ticks: int):
        """``(spike times per target, merged events, clamp counts, sticky)``: by default from
        :meth:`pairs`."""
        pairs, merged, words = self.pairs(cfg, by_tick, n_ticks)
        counts, sticky = clamp_tally(words)
        return times_from_pairs(pairs, cfg.n_targets, cfg.dt_ms), merged, counts, sticky

    def pairs(self, cfg, by_tick: dict, n_ticks: int):
        """``((tick, target) spike pairs, merged events, per-update clamp words)``."""
        raise NotImplementedError


@implements("coincidence", "golden", speed=8e5)
class CoincidenceGolden(CoincidenceEngine):
    """The float64 model (:func:`~cuneate.golden.coincidence.simulate_cuneate`'s scheme) with
    the exact delays and weights: each target's drive summed over its connected sources
    (weight > 0; a weight of 0 disconnects a pair), then every target integrated at once."""

    def spikes(self, cfg, input_ticks, by_tick, n_ticks):
        dt = cfg.dt_ms
        times = [np.asarray(ts, dtype=np.float64) * dt for ts in input_ticks]
        grid = np.arange(n_ticks) * dt
        drive = np.zeros((n_ticks, cfg.n_targets))
        for k in range(cfg.n_targets):
            src = np.flatnonzero(cfg.weights_real[k])
            if src.size:
                drive[:, k] = gcun.psp_drive([times[s] for s in src], cfg.delays[k, src] * dt,
                                             grid, J=1.0, weights=cfg.weights_real[k, src],
                                             tau_rise_ms=cfg.tau_rise_ms,
                                             tau_decay_ms=cfg.tau_decay_ms)[:, 0]
        r = giz.simulate([cfg.param_sets[s] for s in cfg.target_sets_], drive, n_steps=n_ticks,
                         n_neurons=cfg.n_targets, dt_ms=dt, scheme="euler")
        return [np.asarray(s) for s in r.spikes_ms], 0, {}, 0


@implements("coincidence", "fixed", speed=8e4)
class CoincidenceFixed(CoincidenceEngine):
    """The bit-exact twin."""

    def spikes(self, cfg, input_ticks, by_tick, n_ticks):
        twin = CoincidenceTwin(cfg)
        spikes = twin.run(input_ticks, n_ticks)
        return spikes, twin.merged, dict(twin.clamp_counts), twin.clamp_sticky


@implements("coincidence", "amaranth", speed=5e3)
class CoincidenceAmaranth(CoincidenceEngine):
    """The Amaranth simulator on the detector."""

    def pairs(self, cfg, by_tick, n_ticks):
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


@implements("coincidence", "icarus", speed=5e3)
@implements("coincidence", "verilator", speed=5e4)
class CoincidenceCocotb(CoincidenceEngine):
    """cocotb on the detector's Verilog (Icarus: the yosys-lowered netlist)."""

    def pairs(self, cfg, by_tick, n_ticks):
        events = {str(k): v for k, v in by_tick.items()}
        rep = self.engine_bench(lambda low: coincidence_verilog(cfg, lowered=low),
                                "coincidence_detector",
                                {"detector": cfg.to_kwargs(), "ticks": n_ticks, "events": events})
        return [tuple(p) for p in rep["spikes"]], rep["merged"], rep["clamp_words"]


def run_coincidence(engine: str, cfg: CoincidenceConfig, input_ticks, n_ticks: int,
                    build_dir: Path | None = None) -> EngineRun:
    """Run ``n_ticks`` with ``input_ticks`` (one tick array per source) on ``engine``."""
    return engine_for("coincidence", engine, build_dir=build_dir).run(cfg, input_ticks,
                                                                      n_ticks)


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
