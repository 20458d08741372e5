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
    cocotb on the generated Verilog (bench ``cuneate.sim.benches.cuneate_tb``, test ``engine``;
    Icarus runs the yosys-lowered netlist).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..golden import coincidence as gcun
from ..hdl.coincidence import CoincidenceConfig, CoincidenceDetector, CoincidenceTwin, \
    coincidence_verilog
from ..hdl.izhikevich import CLAMP_KINDS

__all__ = ["COINCIDENCE_ENGINES", "CoincidenceRun", "run_coincidence", "events_by_tick",
           "NetworkRun", "run_network", "current_writes"]

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


# ----------------------------------------------------------------------------------------------
# the afferent -> cuneate network
@dataclass
class NetworkRun:
    engine: str
    dt_ms: float
    n_ticks: int
    afferent_ms: list          # per afferent neuron
    cuneate_ms: list           # per cuneate neuron
    counters: dict = field(default_factory=dict)
    wall_s: float = 0.0


def current_writes(cfg, currents) -> dict[int, list[tuple[int, int]]]:
    """``{tick: [(afferent, raw current), ...]}``: the host writes before each tick (only the
    currents that changed; every one before tick 0)."""
    cur = np.asarray(currents, dtype=np.float64)
    if cur.ndim != 2 or cur.shape[1] != cfg.n_afferents:
        raise ValueError(f"currents must be (n_ticks, {cfg.n_afferents}), got {cur.shape}")
    raw = cfg.core.I.to_raw(cur)
    writes, last = {}, None
    for k in range(raw.shape[0]):
        idx = range(cfg.n_afferents) if last is None else np.flatnonzero(raw[k] != last)
        if len(idx):
            writes[k] = [(int(i), int(raw[k, i])) for i in idx]
        last = raw[k]
    return writes


def run_network(engine: str, cfg, currents, build_dir: Path | None = None) -> NetworkRun:
    """Run the network (:class:`cuneate.hdl.network.NetworkConfig`) with host currents
    ``(n_ticks, n_afferents)`` (mV/ms, written before each tick) on ``engine``. Spike times use
    the golden convention for both populations (update of tick ``T`` -> ``(T + 1) dt``); the
    golden engine runs the float64 afferents and feeds their spikes, stamped one tick later,
    to the float64 cuneate model."""
    from ..golden import izhikevich as giz
    from ..hdl.network import NetworkTwin
    if engine not in COINCIDENCE_ENGINES:
        raise ValueError(f"unknown engine {engine!r}; known: {', '.join(COINCIDENCE_ENGINES)}")
    if cfg.tick_source != "external":               # the engines tick the network themselves
        cfg = type(cfg)(**(cfg.to_kwargs() | {"tick_source": "external"}))
    cur = np.asarray(currents, dtype=np.float64)
    writes = current_writes(cfg, cur)
    n, N, M, F, S = cur.shape[0], cfg.n_afferents, cfg.n_targets, cfg.first_source, \
        cfg.n_sources
    dt = cfg.dt_ms
    t0 = time.perf_counter()
    counters: dict = {}
    if engine == "golden":
        params = [cfg.afferent_param_sets[s] for s in cfg.core.neuron_sets]
        r = giz.simulate(params, cur, n_steps=n, n_neurons=N, dt_ms=dt)
        aff = [np.asarray(s, dtype=np.float64) for s in r.spikes_ms]
        det = cfg.det
        g = gcun.simulate_cuneate([aff[F + s] for s in range(S)], det.delays * dt, n * dt,
                                  dt_ms=dt, J=1.0, weights=det.weights_real,
                                  params=[det.param_sets[s] for s in det.target_sets_],
                                  tau_rise_ms=det.tau_rise_ms, tau_decay_ms=det.tau_decay_ms)
        cun = [np.asarray(s, dtype=np.float64) for s in g.spikes_ms]
    else:
        if engine == "fixed":
            tw = NetworkTwin(cfg)
            pa, pc = [], []
            for k in range(n):
                for i, raw in writes.get(k, []):
                    tw.core.I[i] = raw
                a, c = tw.tick()
                pa += [(k, int(i)) for i in np.flatnonzero(a)]
                pc += [(k, int(t)) for t in np.flatnonzero(c)]
            counters = {"link_count": sum(1 for _, i in pa if F <= i < F + S),
                        "merged_count": tw.det.merged}
        elif engine == "amaranth":
            pa, pc, counters = _run_network_amaranth(cfg, writes, n)
        else:
            pa, pc, counters = _run_network_cocotb(engine, cfg, writes, n, build_dir)
        aff = [np.array([(k + 1) * dt for k, i in sorted(pa) if i == j]) for j in range(N)]
        cun = [np.array([(k + 1) * dt for k, t in sorted(pc) if t == j]) for j in range(M)]
    return NetworkRun(engine, dt, n, aff, cun, counters, time.perf_counter() - t0)


def _unwrap(ticks, n_ticks: int, width: int):
    """Tick numbers from the stream (modulo ``2**width``) back to absolute ticks, in order."""
    out, base, last = [], 0, -1
    for t in ticks:
        if t < last:
            base += 1 << width
        out.append(base + t)
        last = t
    return out


def _run_network_amaranth(cfg, writes: dict, n_ticks: int):
    from amaranth.sim import Simulator

    from ..hdl.network import AfferentCuneateNetwork
    dut = AfferentCuneateNetwork(cfg)
    stream, out = [], {}

    async def tb(ctx):
        ctx.set(dut.out_ready, 1)

        async def step():
            if ctx.get(dut.out_valid):
                stream.append((ctx.get(dut.out_population), ctx.get(dut.out_tick),
                               ctx.get(dut.out_index)))
            await ctx.tick()
        for k in range(n_ticks):
            while ctx.get(dut.busy):
                await step()
            for i, raw in writes.get(k, []):
                ctx.set(dut.i_wr_en, 1)
                ctx.set(dut.i_wr_addr, i)
                ctx.set(dut.i_wr_data, raw)
                await step()
            ctx.set(dut.i_wr_en, 0)
            ctx.set(dut.tick, 1)
            await step()
            ctx.set(dut.tick, 0)
        while ctx.get(dut.busy) or ctx.get(dut.out_valid):
            await step()
        for _ in range(8):
            await step()
        for k in ("tick_count", "link_count", "merged_count", "cuneate_overflow_count",
                  "afferent_overflow", "overrun_count"):
            out[k] = ctx.get(getattr(dut, k))

    sim = Simulator(dut)
    sim.add_clock(1.0 / cfg.clock_hz)
    sim.add_testbench(tb)
    sim.run()
    return _split_stream(cfg, stream, n_ticks) + (out,)


def _split_stream(cfg, stream, n_ticks):
    pa = [(t, i) for p, t, i in stream if p == 0]
    pc = [(t, i) for p, t, i in stream if p == 1]
    w = cfg.tick_width
    pa = list(zip(_unwrap([t for t, _ in pa], n_ticks, w), [i for _, i in pa]))
    pc = list(zip(_unwrap([t for t, _ in pc], n_ticks, w), [i for _, i in pc]))
    return pa, pc


def _run_network_cocotb(simulator: str, cfg, writes: dict, n_ticks: int,
                        build_dir: Path | None):
    from ..hdl.network import network_verilog
    from .runner import run_cocotb

    def go(bd: Path):
        bd.mkdir(parents=True, exist_ok=True)
        src = bd / "afferent_cuneate_network.v"
        src.write_text(network_verilog(cfg, lowered=simulator == "icarus"))
        rep = run_cocotb(simulator, [src], "afferent_cuneate_network",
                         "cuneate.sim.benches.network_tb", bd,
                         config={"network": cfg.to_kwargs(), "ticks": n_ticks,
                                 "writes": {str(k): v for k, v in writes.items()}},
                         testcase="engine").report
        pa, pc = _split_stream(cfg, [tuple(x) for x in rep["stream"]], n_ticks)
        return pa, pc, rep["counters"]
    if build_dir is not None:
        return go(Path(build_dir))
    with tempfile.TemporaryDirectory(prefix="cuneate-network-") as d:
        return go(Path(d))
