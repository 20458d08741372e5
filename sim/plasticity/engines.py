"""Engines of the learning layer: one presentation protocol, six engines, one result.

A run is a :class:`~cuneate.golden.cuneate_layer.Presentations` (jittered afferent spikes,
tick-stamped, presentation after presentation) and a learn flag per presentation (its window's
end applies the step, or only clears the drives). Every engine reports the CNs' spikes per
presentation (tick within it), the spike counts within each window and the weights after it:

``golden``
    :func:`cuneate.golden.cuneate_layer.simulate_layer` (float64, AIDP) from the configuration's
    real initial weights and parameters.
``fixed``
    The bit-exact twin :class:`~cuneate.hdl.plasticity.PlasticityTwin` (compiled kernel).
``amaranth``
    The Amaranth simulator on :class:`~cuneate.hdl.plasticity.LearningLayer` (short runs).
``icarus``, ``verilator``
    cocotb on the generated Verilog (bench :mod:`cuneate.sim.plasticity.bench`, test
    ``engine``; Icarus runs the yosys-lowered netlist).
``verilator-fast``
    The Verilog compiled by Verilator with the C++ harness (:mod:`cuneate.sim.plasticity.fast`):
    whole protocols.
``board``, ``axi``
    The layer's payload (:mod:`cuneate.hdl.plasticity.payload`) behind the UART link or the
    AXI face, driven through the face's host transport (:class:`PlasticityFace`): every
    tick's afferent spikes, each window's end and the readout requests are writes
    (:func:`face_schedule`), the weights come back in readout sweeps (the snapshots too).

The RTL engines read every weight back through the layer's host port at the end.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...golden.cuneate_layer import LayerParams, simulate_layer
from ...hdl.plasticity import CLAMP_KINDS, PlasticityConfig
from ...hdl.plasticity.core import LearningLayer, learning_verilog
from ...hdl.plasticity.payload import (LearningSpec, readout_parts, weights_from_ids,
                                       write_addresses)
from ...hdl.plasticity.twin import PlasticityTwin
from ..engines.amaranth import simulate
from ..engines.engine import BlockEngine
from ..engines.registry import engine_for, implements
from .fast import run_fast

__all__ = ["PlasticityEngine", "PlasticityFace", "LearningRun", "run_learning", "golden_layer",
           "face_schedule", "FacePlan"]


@dataclass
class LearningRun:
    """One engine's run of a protocol: every CN spike (``spike_pres``, ``spike_tick``,
    ``spike_cn``), ``counts`` ``(n, M)`` within each window, the final ``weights`` (mV/ms;
    ``weights_raw`` for the fixed-point engines), ``snapshots`` (``(presentations done,
    weights)``, the initial weights first), clamp counts per kind (fixed-point engines)."""

    engine: str
    spike_pres: np.ndarray
    spike_tick: np.ndarray
    spike_cn: np.ndarray
    counts: np.ndarray
    weights: np.ndarray
    weights_raw: np.ndarray | None = None
    snapshots: list = field(default_factory=list)
    clamp_counts: dict = field(default_factory=dict)
    seconds: float = 0.0
    extra: dict = field(default_factory=dict)

    def trains(self, dt_ms: float, window_ticks: int) -> list[list[np.ndarray]]:
        """Spike times (ms from the presentation's start, ``(k + 1) dt``) within the window,
        per presentation per CN."""
        n, M = self.counts.shape
        out = [[np.zeros(0) for _ in range(M)] for _ in range(n)]
        keep = self.spike_tick < window_ticks
        for p, k, j in zip(self.spike_pres[keep], self.spike_tick[keep], self.spike_cn[keep]):
            out[int(p)][int(j)] = np.append(out[int(p)][int(j)], (k + 1) * dt_ms)
        return out


def golden_layer(cfg: PlasticityConfig) -> LayerParams:
    """The golden layer of a configuration (one Izhikevich set for every CN)."""
    sets = {cfg.target_sets_[j] for j in range(cfg.n_targets)}
    if len(sets) != 1:
        raise ValueError("the golden layer takes one Izhikevich parameter set for every CN")
    return LayerParams(cfg.src, cfg.n_sources, cfg.dt_ms, cfg.tau_syn_ms, cfg.g_inh,
                       cfg.param_sets[sets.pop()])


def _chunks(n: int, every: int):
    if not every:
        return [(0, n)]
    edges = list(range(0, n, every)) + [n]
    return list(zip(edges[:-1], edges[1:]))


def run_learning(engine: str, cfg: PlasticityConfig, pres, learn=True,
                 snapshot_every: int = 0, build_dir: Path | None = None) -> LearningRun:
    """Run the presentations ``pres`` on ``engine`` from ``cfg``'s initial weights."""
    return engine_for("plasticity", engine, build_dir=build_dir).run(cfg, pres, learn,
                                                                      snapshot_every)


class PlasticityEngine(BlockEngine):
    """The learning layer on one engine: :meth:`run` a protocol of presentations."""

    block = "plasticity"

    def run(self, cfg: PlasticityConfig, pres, learn=True, snapshot_every: int = 0
            ) -> LearningRun:
        """The presentations ``pres`` from ``cfg``'s initial weights, a learn flag per
        presentation (or one for all), the weights kept every ``snapshot_every``."""
        flags = np.broadcast_to(np.asarray(learn, dtype=bool), (pres.n,)).copy()
        t0 = time.perf_counter()
        run = self.learn(cfg, pres, flags, snapshot_every)
        run.seconds = time.perf_counter() - t0
        return run

    def learn(self, cfg, pres, flags, snapshot_every: int) -> LearningRun:
        """One engine's run (:meth:`run` times it)."""
        raise NotImplementedError


@implements("plasticity", "golden", speed=5e7)
class PlasticityGolden(PlasticityEngine):
    """:func:`~cuneate.golden.cuneate_layer.simulate_layer` (float64, AIDP)."""

    def learn(self, cfg, pres, flags, snapshot_every):
        r = simulate_layer(pres, cfg.weights_real, golden_layer(cfg), "aidp", cfg.rule, flags,
                           snapshot_every)
        return LearningRun(self.name, r.spike_pres, r.spike_tick, r.spike_cn, r.counts,
                           r.weights, None, r.snapshots,
                           extra={"drive_max": r.drive_max, "step": r.step})


@implements("plasticity", "fixed", speed=3e7)
class PlasticityFixed(PlasticityEngine):
    """The bit-exact twin (compiled kernel), the weights kept between chunks."""

    def learn(self, cfg, pres, flags, snapshot_every):
        twin = PlasticityTwin(cfg)
        parts, snaps = [], [(0, twin.weights.copy())]
        for a, b in _chunks(pres.n, snapshot_every):
            out = twin.run(pres.select(range(a, b)), flags[a:b])
            out["spike_pres"] = out["spike_pres"] + a
            parts.append(out)
            if snapshot_every and b < pres.n:
                snaps.append((b, twin.weights.copy()))
        cat = (lambda k: np.concatenate([p[k] for p in parts]))
        return LearningRun(self.name, cat("spike_pres"), cat("spike_tick"), cat("spike_cn"),
                           cat("counts"), twin.weights.copy(), twin.w.copy(), snaps,
                           dict(twin.clamp_counts))


@implements("plasticity", "verilator-fast", speed=1e6)
class PlasticityVerilatorFast(PlasticityEngine):
    """The Verilog compiled by Verilator with the C++ harness: whole protocols."""

    def learn(self, cfg, pres, flags, snapshot_every):
        lsb = cfg.W.lsb
        r = run_fast(cfg, pres, flags, snapshot_every, self.build_dir)
        snaps = [(0, cfg.weights_raw * lsb)] + [((i + 1) * snapshot_every, s * lsb)
                                                 for i, s in enumerate(r["snapshots"])]
        return LearningRun(self.name, r["spike_pres"], r["spike_tick"], r["spike_cn"],
                           r["counts"], r["weights"] * lsb, r["weights"], snaps,
                           r["clamp_counts"], extra={"summary": r["summary"]})


class PlasticityRtl(PlasticityEngine):
    """An HDL simulator tick by tick: the spike pairs, the weights read back through the
    layer's host port and the clamp counts (:meth:`pairs`)."""

    def learn(self, cfg, pres, flags, snapshot_every):
        by_tick, windows = _schedule(pres, flags)
        pairs, weights, clamps = self.pairs(cfg, by_tick, windows, pres.n * pres.n_ticks)
        w_raw = np.asarray(weights, dtype=np.int64).reshape(cfg.n_targets, cfg.n_synapses)
        tk = np.asarray([t for t, _ in pairs], dtype=np.int64).reshape(-1)
        cn = np.asarray([j for _, j in pairs], dtype=np.int64).reshape(-1)
        order = np.lexsort((cn, tk))
        tk, cn = tk[order], cn[order]
        sp, st = tk // pres.n_ticks, tk % pres.n_ticks
        counts = np.zeros((pres.n, cfg.n_targets), np.int64)
        inside = st < pres.window_ticks
        np.add.at(counts, (sp[inside], cn[inside]), 1)
        lsb = cfg.W.lsb
        return LearningRun(self.name, sp, st, cn, counts, w_raw * lsb, w_raw,
                           [(0, cfg.weights_raw * lsb)], dict(clamps))

    def pairs(self, cfg, by_tick: dict, windows: dict, n_ticks: int):
        raise NotImplementedError


@implements("plasticity", "amaranth", speed=2e3)
class PlasticityAmaranth(PlasticityRtl):
    """The Amaranth simulator on :class:`~cuneate.hdl.plasticity.LearningLayer`."""

    def pairs(self, cfg, by_tick, windows, n_ticks):
        return _run_amaranth(cfg, by_tick, windows, n_ticks)


@implements("plasticity", "icarus", speed=5e3)
@implements("plasticity", "verilator", speed=3e4)
class PlasticityCocotb(PlasticityRtl):
    """cocotb on the generated Verilog (the bench's ``engine`` test)."""

    def pairs(self, cfg, by_tick, windows, n_ticks):
        rep = self.engine_bench(lambda low: learning_verilog(cfg, lowered=low),
                                "learning_layer",
                                {"layer": cfg.to_kwargs(), "ticks": n_ticks,
                                 "events": {str(k): v for k, v in by_tick.items()},
                                 "windows": {str(k): a for k, a in windows.items()}})
        return rep["spikes"], rep["weights"], rep["clamp_counts"]


class PlasticityFace(PlasticityEngine):
    """The layer behind a face (an engine with a host transport, :meth:`stream`): the
    protocol as writes (:func:`face_schedule`), the CNs' spikes and, in the readout sweeps
    after every ``snapshot_every`` presentations and after the last, every weight
    (:meth:`readout_synapses` a sweep). Face engines see no clamp counts (the faces carry
    spikes)."""

    def readout_synapses(self, cfg) -> int | None:
        """Synapses a readout sweep sends (``None``: a CN's all)."""
        return None

    def learn(self, cfg, pres, flags, snapshot_every):
        spec = LearningSpec(cfg, self.readout_synapses(cfg))
        plan = face_schedule(cfg, pres, flags, snapshot_every, spec.readout_synapses)
        got, counters = self.stream(spec, plan.writes, plan.n_sweeps)
        M, K, C = cfg.n_targets, cfg.n_synapses, plan.parts
        tick = plan.tick_of_sweep[got.tick]
        cn = tick >= 0
        if np.any(got.neuron[cn] >= M) or np.any(got.neuron[~cn] < M):
            raise ValueError(f"{self.name}: a CN spike in a readout sweep or a readout id in "
                             f"a tick")
        lsb = cfg.W.lsb
        order = np.argsort(got.tick[~cn], kind="stable")      # readout ids grouped by sweep
        r_sweep, r_id = got.tick[~cn][order], got.neuron[~cn][order]
        reads = []                              # raw weights at each readout
        for i in range(len(plan.readouts)):
            sweeps = np.flatnonzero(plan.tick_of_sweep == -1 - i).reshape(M, C)
            bounds = np.searchsorted(r_sweep, np.stack([sweeps[:, 0], sweeps[:, -1] + 1], 1))
            reads.append(np.stack([weights_from_ids(cfg, r_id[lo:hi])
                                   for lo, hi in bounds]).reshape(M, K))
        snaps = [(0, cfg.weights_raw * lsb)] + [(done, w * lsb) for done, w in
                                                zip(plan.readouts[:-1], reads[:-1])]
        sp, st, j = tick[cn] // pres.n_ticks, tick[cn] % pres.n_ticks, got.neuron[cn]
        counts = np.zeros((pres.n, M), np.int64)
        inside = st < pres.window_ticks
        np.add.at(counts, (sp[inside], j[inside]), 1)
        return LearningRun(self.name, sp, st, j, counts, reads[-1] * lsb, reads[-1], snaps,
                           extra={"counters": counters})


@dataclass
class FacePlan:
    """A protocol as a face's writes: ``writes`` (``{sweep: [(first address, raw values),
    ...]}``), ``n_sweeps``, the layer's tick of each sweep (``tick_of_sweep``; ``-1 - i`` in
    the sweeps of readout ``i``: ``parts`` sweeps a CN, CN after CN) and the presentations
    done at each readout (``readouts``, the last after the protocol)."""

    writes: dict
    n_sweeps: int
    tick_of_sweep: np.ndarray
    readouts: list
    parts: int


def face_schedule(cfg: PlasticityConfig, pres, flags, snapshot_every: int = 0,
                  readout_synapses: int | None = None) -> FacePlan:
    """The protocol as a face's writes (the write map of
    :func:`~cuneate.hdl.plasticity.payload.write_addresses`): each tick's afferent spikes as
    one write of every afferent (1: a spike), each presentation's window end before the next
    one's first tick; after every ``snapshot_every`` presentations and after the last, with
    the window end, every readout request (``readout_synapses`` synapses a sweep), and one
    readout sweep each."""
    amap = write_addresses(cfg, readout_synapses)
    S, n_req = cfg.n_sources, amap["readout"][1]
    writes: dict = {}
    ticks_of: list[int] = []
    readouts: list = []

    def add(k, first, raw):
        writes.setdefault(int(k), []).append((first, np.asarray(raw, dtype=np.int64)))
    for p in range(pres.n):
        a, b = pres.offsets[p], pres.offsets[p + 1]
        ticks, srcs = pres.ticks[a:b], pres.sources[a:b]
        first = len(ticks_of)
        for k in np.unique(ticks):
            vec = np.zeros(S, np.int64)
            vec[srcs[ticks == k]] = 1
            add(first + k, 0, vec)
        ticks_of += range(p * pres.n_ticks, (p + 1) * pres.n_ticks)
        add(len(ticks_of), amap["learn"][0], [int(flags[p])])
        if p == pres.n - 1 or (snapshot_every and (p + 1) % snapshot_every == 0):
            add(len(ticks_of), amap["readout"][0], np.ones(n_req, np.int64))
            ticks_of += [-1 - len(readouts)] * n_req
            readouts.append(p + 1)
    return FacePlan(writes, len(ticks_of), np.asarray(ticks_of, dtype=np.int64), readouts,
                    readout_parts(cfg, readout_synapses))


def _schedule(pres, flags):
    """Events per global tick and the window ends (global tick -> apply)."""
    by_tick: dict = {}
    for p in range(pres.n):
        a, b = pres.offsets[p], pres.offsets[p + 1]
        for k, s in zip(pres.ticks[a:b], pres.sources[a:b]):
            by_tick.setdefault(int(p * pres.n_ticks + k), []).append(int(s))
    windows = {int((p + 1) * pres.n_ticks - 1): bool(flags[p]) for p in range(pres.n)}
    return by_tick, windows


def _run_amaranth(cfg: PlasticityConfig, by_tick: dict, windows: dict, n_ticks: int):
    dut = LearningLayer(cfg)
    pairs, weights, out = [], [], {}

    async def cyc(ctx, n=1):
        for _ in range(n):
            await ctx.tick()
            if ctx.get(dut.spike_valid):
                pairs.append((ctx.get(dut.spike_tick), ctx.get(dut.spike_target)))
            if ctx.get(dut.w_rd_resp_valid):
                weights.append(ctx.get(dut.w_rd_resp_data))

    async def settle(ctx):
        await cyc(ctx, 2)
        while ctx.get(dut.busy):
            await cyc(ctx)
        await cyc(ctx, 6)

    async def tb(ctx):
        for k in range(n_ticks):
            for s in by_tick.get(k, []):
                ctx.set(dut.in_valid, 1)
                ctx.set(dut.in_source, s)
                await cyc(ctx)
            ctx.set(dut.in_valid, 0)
            ctx.set(dut.tick, 1)
            await cyc(ctx)
            ctx.set(dut.tick, 0)
            await settle(ctx)
            if k in windows:
                ctx.set(dut.learn, 1)
                ctx.set(dut.learn_apply, int(windows[k]))
                await cyc(ctx)
                ctx.set(dut.learn, 0)
                await settle(ctx)
        for a in range(cfg.n_targets * cfg.n_synapses):
            ctx.set(dut.w_rd_valid, 1)
            ctx.set(dut.w_rd_addr, a)
            await cyc(ctx)
            ctx.set(dut.w_rd_valid, 0)
            await cyc(ctx, 4)
        out["clamps"] = {k: ctx.get(getattr(dut, f"clamp_count_{k}")) for k in CLAMP_KINDS}

    simulate(dut, tb, cfg.clock_hz)
    return pairs, weights, out["clamps"]
