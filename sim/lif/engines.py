"""Engines for the LIF core: one host program, six engines, one spike convention.

A run is a :class:`LifProgram`: per sweep (tick) the host currents of every neuron (real
values, written before that sweep's tick) and the input spike vector of that sweep. Every engine
reports spikes with the golden convention (update ``k`` -> ``(k + 1) dt``):

``golden``
    The float64 models of :mod:`cuneate.golden.lif` with the exact (unquantized) parameters,
    weights and currents: :func:`~cuneate.golden.lif.simulate_lif` (continuous, exact
    integration) or :func:`~cuneate.golden.lif.simulate_discrete_lif` per parameter set.
``fixed``
    The bit-exact twin :class:`cuneate.hdl.lif.LifTwin`.
``amaranth``
    The Amaranth simulator on :class:`cuneate.hdl.lif.LifCore`.
``icarus``, ``verilator``
    cocotb on the generated Verilog (bench :mod:`cuneate.sim.lif.bench`, test ``engine``).
``board``
    The core behind the UART link (:mod:`cuneate.sim.engines.board`).

:class:`LifEngine` is the block's engine interface; each engine implements it and registers
itself (:func:`~cuneate.sim.engines.registry.implements`).

The hardware engines run an external-tick core; per sweep the host waits for the previous sweep
to finish issuing, writes the currents that changed, sends the input spikes and ticks, so the
results depend only on the program, not on the clock.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...golden import lif as golden
from ...hdl.lib.config import MIN_NEURONS
from ...hdl.lif import CLAMP_KINDS, PIPELINE_DEPTH, LifConfig, LifCore, LifTwin, lif_verilog
from ..engines.amaranth import simulate, spikes_then_tick
from ..engines.cocotb import run_bench
from ..engines.engine import BlockEngine
from ..engines.registry import engine_for, implements
from ..engines.run import EngineRun, TickUnwrap, spike_times

__all__ = ["LifEngine", "LifProgram", "engine_config", "run_lif", "current_runs"]


@dataclass
class LifProgram:
    """``currents`` (n_sweeps, n) real host currents; ``inputs`` (n_sweeps, n_inputs) spikes
    or None."""

    currents: np.ndarray
    inputs: np.ndarray | None = None

    @property
    def n_sweeps(self) -> int:
        return int(self.currents.shape[0])

    @classmethod
    def constant(cls, currents, n_sweeps: int, inputs=None) -> "LifProgram":
        cur = np.asarray(currents, dtype=np.float64)
        return cls(np.tile(cur, (n_sweeps, 1)), inputs)


def engine_config(core: dict, n: int) -> LifConfig:
    """The configuration the engines simulate for ``n`` neurons of ``core`` (constructor
    keywords): at least :data:`~cuneate.hdl.lib.config.MIN_NEURONS` neurons (idle ones get
    zero current and zero weights), external tick. Raises :class:`~cuneate.hdl.lif.ConfigError`."""
    N = max(n, MIN_NEURONS)
    kw = dict(core)
    kw.update(n_neurons=N, clock_hz=float(kw.get("update_hz", 16e3)) * N * 4,
              tick_source="external", spike_fifo_depth=max(16, 2 * N + 4))
    ns = kw.get("neuron_sets")
    if ns is not None:
        kw["neuron_sets"] = list(ns)[:n] + [0] * (N - min(n, len(ns)))
    w = kw.get("weights")
    if w is not None:
        w = np.asarray(w, dtype=np.float64)
        kw["weights"] = np.vstack([w, np.zeros((N - w.shape[0], w.shape[1]))]) \
            if w.shape[0] < N else w
    vi = kw.get("v_init")
    if vi is not None and len(vi) < N:
        kw["v_init"] = list(vi) + [0.0] * (N - len(vi))
    return LifConfig.from_kwargs(kw)


def _pad(program: LifProgram, N: int) -> np.ndarray:
    cur = np.asarray(program.currents, dtype=np.float64)
    if cur.shape[1] < N:
        cur = np.hstack([cur, np.zeros((cur.shape[0], N - cur.shape[1]))])
    return cur


class LifEngine(BlockEngine):
    """The LIF block on one engine: :meth:`run` a :class:`LifProgram`."""

    block = "lif"

    def build(self, core: dict, n: int) -> LifConfig:
        """The core this engine simulates for ``n`` neurons of ``core`` (:func:`engine_config`)."""
        return engine_config(core, n)

    def run(self, cfg: LifConfig, cur: np.ndarray, inputs, n: int) -> EngineRun:
        """Host currents ``cur`` ``(n_sweeps, n_neurons)`` and input spikes ``inputs`` (or
        ``None``) on ``cfg``; the spikes of its first ``n`` neurons."""
        t0 = time.perf_counter()
        steps, counts, sticky, counters = self.sweeps(cfg, cur, inputs)
        spikes = [spike_times(np.sort(steps[i]), cfg.dt_ms).tolist() for i in range(n)]
        return EngineRun(self.name, cfg.dt_ms, cur.shape[0], spikes, counts, sticky,
                         time.perf_counter() - t0, counters=counters)

    def sweeps(self, cfg: LifConfig, cur: np.ndarray, inputs):
        """``(spike ticks per neuron, clamp counts, sticky flags, counters)``; by default
        through :meth:`transport` (the currents that change written for their sweep,
        :func:`current_runs`; no clamps seen). A transport carries host currents alone: a
        program with input spikes is refused."""
        if inputs is not None and np.any(inputs):
            raise ValueError(f"the {self.name} engine's transport carries no input spikes: a "
                             f"LIF program on it has host currents alone")
        raw = np.asarray(cfg.I.to_raw(cur), dtype=np.int64)
        got, counters = self.stream(cfg, current_runs(raw), raw.shape[0])
        steps: list[list[int]] = [[] for _ in range(cfg.n_neurons)]
        for k, i in zip(got.tick.tolist(), got.neuron.tolist()):
            steps[i].append(k)
        return steps, {}, {}, counters


def run_lif(engine: str, cfg: LifConfig, program: LifProgram, n: int | None = None,
            build_dir: Path | None = None) -> EngineRun:
    """Run ``program`` on ``engine``; returns the spikes of the first ``n`` neurons."""
    impl = engine_for("lif", engine, build_dir=build_dir)
    N = cfg.n_neurons
    n = N if n is None else n
    cur = _pad(program, N)
    if cur.shape[1] != N:
        raise ValueError(f"the program has currents for {cur.shape[1]} neurons, the core {N}")
    if program.inputs is not None and np.shape(program.inputs) != (program.n_sweeps,
                                                                   cfg.n_inputs):
        raise ValueError(f"input spikes must have shape ({program.n_sweeps}, {cfg.n_inputs})")
    if engine != "golden" and not (np.all(cur >= cfg.I.min_value)
                                   and np.all(cur <= cfg.I.max_value)):
        raise ValueError(f"a current lies outside the core's input format {cfg.I} "
                         f"[{cfg.I.min_value:g}, {cfg.I.max_value:g}]")
    return impl.run(cfg, cur, program.inputs, n)


@implements("lif", "fixed", speed=3e5)
class LifFixed(LifEngine):
    """The bit-exact twin."""

    def sweeps(self, cfg, cur, inputs):
        twin = LifTwin(cfg)
        ks, ns = twin.run_raw(np.asarray(cfg.I.to_raw(cur), dtype=np.int64), cur.shape[0],
                              inputs)
        steps = [[] for _ in range(cfg.n_neurons)]
        for k, i in zip(ks.tolist(), ns.tolist()):
            steps[i].append(k)
        rep = twin.clamp_report()
        return steps, rep["counts"], rep["sticky"], {}


@implements("lif", "amaranth", speed=3.3e3)
class LifAmaranth(LifEngine):
    """The Amaranth simulator on the core."""

    def sweeps(self, cfg, cur, inputs):
        rep = _run_amaranth(cfg, _host_program(cfg, cur, inputs))
        return rep["spike_sweeps"], rep["clamp_counts"], rep["clamp_sticky"], {}


@implements("lif", "icarus", speed=3.3e3)
@implements("lif", "verilator", speed=3.3e4)
class LifCocotb(LifEngine):
    """cocotb on the generated Verilog (the bench's ``engine`` test)."""

    def sweeps(self, cfg, cur, inputs):
        rep = run_bench(self.name, lif_verilog(cfg), "lif_core", "lif",
                        {"core": cfg.to_kwargs(), "program": _host_program(cfg, cur, inputs)},
                        self.build_dir, testcase="engine").report
        return rep["spike_sweeps"], rep["clamp_counts"], rep["clamp_sticky"], {}


def current_runs(raw: np.ndarray) -> dict[int, list[tuple[int, np.ndarray]]]:
    """The host's writes of a program's raw currents ``(n_sweeps, n)``: per sweep the runs of
    consecutive neurons whose current changes there, ``{sweep: [(first, raw values), ...]}``
    (every neuron at sweep 0, where the core's currents are 0)."""
    out: dict[int, list[tuple[int, np.ndarray]]] = {}
    prev = np.zeros(raw.shape[1], dtype=np.int64)
    for k in range(raw.shape[0]):
        idx = np.arange(raw.shape[1]) if k == 0 else np.flatnonzero(raw[k] != prev)
        if idx.size:
            cuts = np.flatnonzero(np.diff(idx) != 1) + 1
            out[k] = [(int(r[0]), raw[k, r[0]:r[-1] + 1]) for r in np.split(idx, cuts)]
        prev = raw[k]
    return out


def _run_golden(cfg: LifConfig, cur: np.ndarray, inputs, build_dir=None):
    N = cfg.n_neurons
    drive = cur.copy()
    if inputs is not None and cfg.n_inputs and cfg.synapses:
        # difference-of-exponentials currents: a spike of tick m adds w K((k - m) dt) at k
        t = np.arange(cur.shape[0]) * cfg.dt_ms
        pre = [np.flatnonzero(inputs[:, i]) * cfg.dt_ms for i in range(cfg.n_inputs)]
        for typ, taus, sign in (("exc", cfg.ampa, 1.0), ("inh", cfg.gaba, -1.0)):
            cols = np.flatnonzero(cfg.input_exc == (typ == "exc"))
            if cols.size:
                drive += sign * golden.synaptic_current([pre[i] for i in cols], t, *taus,
                                                        latency_ms=0.0,
                                                        weight=cfg.weights[:, cols].T)
    elif inputs is not None and cfg.n_inputs:
        drive += np.asarray(inputs, dtype=np.float64) @ cfg.weights.T
    sel = np.asarray(cfg.neuron_sets)
    steps: list[list[int]] = [[] for _ in range(N)]
    if cfg.form == "continuous":
        sets = cfg.sets
        res = golden.simulate_lif(
            drive, cfg.dt_ms, n_neurons=N, record=False,
            tau_m_ms=np.array([sets[s].tau_m_ms for s in sel]),
            v_th=np.array([sets[s].v_th for s in sel]),
            v_reset=np.array([sets[s].v_reset for s in sel]),
            v_rest=np.array([sets[s].v_rest for s in sel]),
            t_ref_ms=np.array([cfg.n_ref[s] * cfg.dt_ms for s in sel]),
            v0=np.asarray(cfg._v_init))
        return [list(map(int, s)) for s in res.spike_steps]
    for si, s in enumerate(cfg.sets):
        idx = np.flatnonzero(sel == si)
        if not idx.size:
            continue
        res = golden.simulate_discrete_lif(drive[:, idx], np.eye(idx.size), alpha=s.alpha,
                                           u_th=s.v_th, u_rest=s.v_reset,
                                           refractory_steps=s.refractory_steps,
                                           u0=np.asarray(cfg._v_init)[idx])
        for j, n in enumerate(idx):
            steps[n] = list(map(int, np.flatnonzero(res.spikes[:, j])))
    return steps


@implements("lif", "golden", speed=8e5)
class LifGolden(LifEngine):
    """The float64 models with the exact parameters, weights and currents."""

    def sweeps(self, cfg, cur, inputs):
        return _run_golden(cfg, cur, inputs), {}, {}, {}


def _host_program(cfg: LifConfig, cur: np.ndarray, inputs) -> list:
    """Per sweep: raw currents when they changed (else None) and the input sources."""
    raw = cfg.I.to_raw(cur)
    ops, prev = [], None
    for k in range(raw.shape[0]):
        row = [int(x) for x in raw[k]]
        srcs = [] if inputs is None else [int(s) for s in np.flatnonzero(inputs[k])]
        ops.append([row if row != prev else None, srcs])
        prev = row
    return ops


def _run_amaranth(cfg: LifConfig, ops) -> dict:
    dut = LifCore(cfg)
    N = cfg.n_neurons
    spikes = [[] for _ in range(N)]
    counts = {k: 0 for k in CLAMP_KINDS}
    out = {}
    unwrap = TickUnwrap(cfg.sweep_number_width)

    async def bench(ctx):
        ctx.set(dut.spike_ready, 1)

        async def step():
            await ctx.tick()
            if ctx.get(dut.sweep_done):
                for k in CLAMP_KINDS:
                    counts[k] += ctx.get(getattr(dut, f"sweep_clamps_{k}"))
            if ctx.get(dut.spike_valid):
                spikes[ctx.get(dut.spike_index)].append(unwrap(ctx.get(dut.spike_sweep)))

        for row, srcs in ops:
            while ctx.get(dut.busy):
                await step()
            if row is not None:
                ctx.set(dut.i_wr_en, 1)
                for i in range(N):
                    ctx.set(dut.i_wr_addr, i)
                    ctx.set(dut.i_wr_data, row[i])
                    await step()
                ctx.set(dut.i_wr_en, 0)
            await spikes_then_tick(ctx, dut, srcs, step, bool(cfg.n_inputs))
        for _ in range(N + PIPELINE_DEPTH + cfg.spike_fifo_depth + 4):
            await step()
        assert not ctx.get(dut.overrun) and not ctx.get(dut.spike_overflow)
        out["sticky"] = ctx.get(dut.clamp_flags)

    simulate(dut, bench)
    return {"spike_sweeps": spikes, "clamp_counts": counts,
            "clamp_sticky": {k: bool(out["sticky"] >> i & 1) for i, k in enumerate(CLAMP_KINDS)}}
