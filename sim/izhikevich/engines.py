"""The Izhikevich block's engines: whole runs (``cuneate simulate izhikevich``) and transports
for the host driver (scenes), one spike convention.

:class:`IzhikevichEngine` is the block's engine interface; each engine implements it and
registers itself (:func:`~cuneate.sim.engines.registry.implements`). All engines run the same
core configuration and report spikes with the golden convention (a spike produced by update k
is at (k+1) dt ms), so their outputs are directly comparable:

``golden``
    The float64 model (forward Euler at the core's dt) with the core's parameter sets.
``fixed``
    The bit-exact NumPy twin.
``amaranth``
    The Amaranth simulator on the core.
``icarus``, ``verilator``
    cocotb on the generated Verilog (bench :mod:`cuneate.sim.izhikevich.bench`).
``verilator-fast``
    The generated Verilog compiled by Verilator with a C++ harness
    (:mod:`cuneate.sim.engines.verilator_fast`): no Python per cycle, same spikes and clamp
    counters.

(``board``, the core behind the UART link, is :mod:`cuneate.sim.engines.board`.)

A core is described by its constructor keywords (``core``, as for
:class:`~cuneate.hdl.izhikevich.IzhikevichConfig`); :func:`engine_core` turns them into the
configuration an engine simulates: the same parameter sets, formats, accepted range and
rounding, at least :data:`~cuneate.hdl.lib.config.MIN_NEURONS` neurons (unused ones idle at
zero current), and an external tick every ``n_neurons`` cycles (one update per clock, no idle
cycles) - results depend only on the update rate (dt), not on the clock. Every engine but
golden also reports the core's clamp counters.

Transports (:meth:`IzhikevichEngine.transport`, :func:`make_transport`; the interface is
:mod:`cuneate.sim.host.transport`) carry a host driver's timed current writes to a core. The
hardware engines share one sweep protocol (:data:`PROTOCOL`): the writes due at tick ``k`` are
driven through the host-write port after sweep ``k - 1`` has left the pipeline and before the
tick of sweep ``k`` (so no write can reach the wrong sweep); the spike FIFO (one entry per
neuron deep) is read out between sweeps and checked against the core's own per-sweep spike
count. Idle cycles between sweeps do not change the arithmetic (external tick). Every transport
refuses a write for a tick already run (``TransportError``) and a schedule longer than its
buffer (``buffer_writes``; a buffer overrun is an error, never a silent drop).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...golden import izhikevich as golden
from ...hdl.izhikevich import (CLAMP_KINDS, IzhikevichConfig, IzhikevichCore,
                               IzhikevichTwin, izhikevich_verilog)
from ...hdl.izhikevich.config import min_neurons
from ...hdl.lib.config import MIN_NEURONS
from ..engines.amaranth import simulate, write_currents
from ..engines.cocotb import run_bench
from ..engines.engine import WAVE_ENGINES, BlockEngine
from ..engines.registry import engine_for, implements
from ..engines.run import EngineRun, TickUnwrap, spike_times
from ..engines.verilator_fast import run_harness
from ..engines.waves import WindowedVcd, write_gtkw
from ..host.transport import SpikeBatch, Transport, TransportError, sweep_count

__all__ = ["IzhikevichEngine", "EngineRun", "engine_core", "run_engine",
           "MIN_NEURONS",
           "TwinTransport", "CocotbTransport", "AmaranthTransport", "VerilatorFastTransport",
           "make_transport", "PROTOCOL", "WAVE_ENGINES"]

PROTOCOL = "writes between sweeps, external tick, FIFO drained between sweeps"
#: Default write-buffer capacity of the batch transports (write calls held until collect).
BUFFER_WRITES = 1 << 20


def engine_core(core: dict, n: int) -> IzhikevichConfig:
    """The configuration an engine simulates for ``n`` neurons of the core ``core``
    (constructor keywords); raises :class:`~cuneate.hdl.izhikevich.ConfigError`."""
    depth = core.get("pipeline_stages")
    N = max(n, MIN_NEURONS, min_neurons(depth) if depth else min_neurons())
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


# ----------------------------------------------------------------------------------------------
# whole runs with constant currents

def _amaranth_window(cfg: IzhikevichConfig, waves):
    """The VCD window of an Amaranth run (``None`` without ``waves``) and what writes its
    GTKWave save file when the run is over."""
    if not waves:
        return None, lambda: None
    path = waves.path("amaranth")
    path.parent.mkdir(parents=True, exist_ok=True)
    window = WindowedVcd(path)
    window.on = waves.covers(0)

    def finish():
        window.close()                        # the simulator leaves a file it did not open
        write_gtkw(path.with_suffix(".gtkw"), path, "amaranth",
                   izhikevich_verilog(cfg, "izhikevich_core"), "izhikevich_core")
    return window, finish


class IzhikevichEngine(BlockEngine):
    """The Izhikevich block on one engine: :meth:`run` a whole run with constant currents,
    :meth:`transport` the host driver's transport (scenes)."""

    block = "izhikevich"

    def build(self, core: dict, n: int) -> IzhikevichConfig:
        """The core this engine simulates for ``n`` neurons of ``core`` (:func:`engine_core`)."""
        return engine_core(core, n)

    def run(self, cfg: IzhikevichConfig, cur, n_sweeps: int, n: int) -> EngineRun:
        """``n_sweeps`` sweeps of ``cfg`` with constant currents ``cur`` (mV/ms, one per neuron
        of the core); the spikes of its first ``n`` neurons."""
        t0 = time.perf_counter()
        spikes, counts, sticky, counters = self.sweeps(cfg, cur, n_sweeps, n)
        return EngineRun(self.name, cfg.dt_ms, n_sweeps, spikes,
                         None if counts is None else dict(counts), sticky,
                         time.perf_counter() - t0, counters)

    def sweeps(self, cfg: IzhikevichConfig, cur, n_sweeps: int, n: int):
        """``(spike times per neuron as lists, clamp counts, sticky flags, counters)``; by
        default through :meth:`transport` (the currents written once, before the first sweep;
        no clamps seen: ``None``)."""
        raw = np.asarray(cfg.I.to_raw(cur), dtype=np.int64)
        got, counters = self.stream(cfg, {0: [(0, raw)]}, n_sweeps)
        return [t.tolist() for t in got.times_ms(cfg.dt_ms, n)], None, None, counters

    #: How the engine runs a scene's cuneate layer: ``"host"`` (its afferents' spikes into
    #: the layer's model or twin, :func:`~cuneate.sim.network.scene.run_layer`), ``"chip"``
    #: (its transport opens the afferent -> cuneate network) or ``None`` (it does not).
    layer: str | None = None


def _times(spike_sweeps, n: int, dt_ms: float) -> list[list[float]]:
    return [spike_times(np.sort(spike_sweeps[i]), dt_ms).tolist() for i in range(n)]


@implements("izhikevich", "golden", speed=15e6)
class IzhikevichGolden(IzhikevichEngine):
    """The float64 model at the core's dt (forward Euler), the core's parameter sets."""

    layer = "host"

    def sweeps(self, cfg, cur, n_sweeps, n):
        params = [cfg.params[s] for s in cfg.neuron_sets[:n]]
        cur = np.asarray(cur[:n], dtype=np.float64)
        r = golden.simulate(params, lambda t_ms: cur, n_steps=n_sweeps, n_neurons=n,
                            dt_ms=cfg.dt_ms, scheme="euler", progress=self.progress)
        return [np.asarray(s).tolist() for s in r.spikes_ms], None, None, {}

    def transport(self) -> Transport:
        raise ValueError("engine 'golden' has no transport (it runs the golden model)")


@implements("izhikevich", "fixed", speed=2e6)
class IzhikevichFixed(IzhikevichEngine):
    """The bit-exact twin."""

    layer = "host"

    def sweeps(self, cfg, cur, n_sweeps, n):
        twin = IzhikevichTwin(cfg)
        spikes = [s.tolist() for s in twin.run(cur, n_sweeps, progress=self.progress)[:n]]
        rep = twin.clamp_report()
        return spikes, rep["counts"], rep["sticky"], {}

    def transport(self) -> Transport:
        return TwinTransport(progress=self.progress)


@implements("izhikevich", "amaranth", speed=4e3)
class IzhikevichAmaranth(IzhikevichEngine):
    """The Amaranth simulator on the core."""

    writes_waves = True

    def sweeps(self, cfg, cur, n_sweeps, n):
        """The core with constant currents ``cur``, a tick every ``n_neurons`` cycles: the
        spikes, clamp counts per kind and sticky flags it reports."""
        dut = IzhikevichCore(cfg)
        window, finish = _amaranth_window(cfg, self.waves)
        N, waves, progress = cfg.n_neurons, self.waves, self.progress
        raw = cfg.I.to_raw(cur)
        spikes = [[] for _ in range(N)]
        counts = {k: 0 for k in CLAMP_KINDS}
        out = {}

        async def bench(ctx):
            ctx.set(dut.spike_ready, 1)
            await write_currents(ctx, dut, raw[:N])
            unwrap = TickUnwrap(cfg.sweep_number_width)
            for c in range(n_sweeps * N + cfg.pipeline_stages + cfg.spike_fifo_depth + 4):
                ctx.set(dut.tick, int(c % N == 0 and c // N < n_sweeps))
                await ctx.tick()
                if ctx.get(dut.sweep_done):
                    for k in CLAMP_KINDS:
                        counts[k] += ctx.get(getattr(dut, f"sweep_clamps_{k}"))
                    done_sweeps = c // N + 1
                    if window is not None:
                        window.on = waves.covers(done_sweeps)
                    if progress is not None and done_sweeps % 1000 == 0:
                        progress(done_sweeps)
                if ctx.get(dut.spike_valid):
                    spikes[ctx.get(dut.spike_index)].append(unwrap(ctx.get(dut.spike_sweep)))
            assert not ctx.get(dut.overrun) and not ctx.get(dut.spike_overflow)
            out["sticky"] = ctx.get(dut.clamp_flags)

        simulate(dut, bench, vcd=window)
        finish()
        sticky = {k: bool(out["sticky"] >> i & 1) for i, k in enumerate(CLAMP_KINDS)}
        return _times(spikes, n, cfg.dt_ms), counts, sticky, {}

    def transport(self) -> Transport:
        return AmaranthTransport(self.build_dir, progress=self.progress, waves=self.waves)


@implements("izhikevich", "icarus", speed=2.5e3)
@implements("izhikevich", "verilator", speed=4e4)
class IzhikevichCocotb(IzhikevichEngine):
    """cocotb on the generated Verilog (the bench's ``engine`` and ``play`` tests)."""

    writes_waves = True

    def sweeps(self, cfg, cur, n_sweeps, n):
        rep = run_bench(self.name, izhikevich_verilog(cfg), "izhikevich_core", "izhikevich",
                        {"core": cfg.to_kwargs(), "currents": list(map(float, cur)),
                         "sweeps": n_sweeps}, self.build_dir, testcase="engine",
                        progress=self.progress, waves=self.waves).report
        return (_times(rep["spike_sweeps"], n, cfg.dt_ms), rep["clamp_counts"],
                rep["clamp_sticky"], {"cycles": rep["cycles"], "wall_s": rep["wall_s"]})

    def transport(self) -> Transport:
        return CocotbTransport(self.name, self.build_dir, progress=self.progress,
                               waves=self.waves)


@implements("izhikevich", "verilator-fast", speed=1e6)
class IzhikevichVerilatorFast(IzhikevichEngine):
    """The core compiled by Verilator with the C++ harness."""

    def sweeps(self, cfg, cur, n_sweeps, n):
        run = run_harness(cfg, cur, n_sweeps, build_root=self.build_dir)
        if self.progress is not None:
            self.progress(n_sweeps)
        ks = run.spikes_per_neuron(n)
        return ([spike_times(k, cfg.dt_ms).tolist() for k in ks],
                dict(run.summary["clamp_counts"]), run.clamp_sticky(), {})

    def transport(self) -> Transport:
        return VerilatorFastTransport(self.build_dir, progress=self.progress)


def run_engine(engine: str, core: dict, currents, duration_ms: float,
               build_dir: Path | None = None, progress=None, waves=None) -> EngineRun:
    """Run ``engine`` on ``len(currents)`` neurons of ``core`` with constant currents (mV/ms).

    ``progress``, if given, is called with the number of sweeps done (the twin and the Amaranth
    simulator report as they go; cocotb runs report from the simulator's progress file).
    ``waves``: a :class:`~cuneate.sim.engines.waves.Waves` window, dumped by the RTL engines
    (``amaranth``, ``icarus``, ``verilator``; refused for the others).
    """
    impl = engine_for("izhikevich", engine, build_dir=build_dir, progress=progress,
                      waves=waves)
    n = len(currents)
    cfg = impl.build(core, n)
    n_sweeps = int(round(duration_ms / cfg.dt_ms))
    cur = np.zeros(cfg.n_neurons)
    cur[:n] = currents
    for x in currents:
        if not cfg.I.contains(x):
            raise ValueError(f"current {x:g} is outside the core's input format {cfg.I} "
                             f"[{cfg.I.min_value:g}, {cfg.I.max_value:g}]")
    return impl.run(cfg, cur, n_sweeps, n)


def make_transport(engine: str, **kw) -> Transport:
    """The transport of ``engine`` for the host driver (``build_dir``, ``progress``, ``waves``
    and the engine's own keywords)."""
    return engine_for("izhikevich", engine, **kw).transport()


# ----------------------------------------------------------------------------------------------
# transports for the host driver

class _Buffered(Transport):
    """Common bookkeeping: tick, write schedule, counters."""

    def __init__(self, buffer_writes: int = BUFFER_WRITES):
        self.buffer_writes = int(buffer_writes)
        self.cfg: IzhikevichConfig | None = None
        self.tick = 0
        self.writes: list[tuple[int, int, list[int]]] = []
        self.cnt = {"writes": 0, "words": 0, "spikes": 0, "spikes_counted": 0, "overflow": 0,
                    "overrun": 0, "late_writes": 0, "sweeps": 0, "frames_lost": 0}
        self.clamps = {k: 0 for k in CLAMP_KINDS}
        self.wall_s = 0.0

    def open(self, config) -> None:
        self.cfg = config

    def _check_write(self, tick: int, first: int, raw) -> list[int]:
        if self.cfg is None:
            raise TransportError(f"{self.name}: write before open")
        if tick < self.tick:
            self.cnt["late_writes"] += 1
            raise TransportError(f"{self.name}: write for tick {tick} arrived after tick "
                                 f"{self.tick - 1} ran (late write refused)")
        raw = [int(x) for x in np.asarray(raw).ravel()]
        if first < 0 or first + len(raw) > self.cfg.n_neurons:
            raise TransportError(f"{self.name}: write to neurons {first}..{first + len(raw) - 1} "
                                 f"outside the core (0..{self.cfg.n_neurons - 1})")
        lo, hi = self.cfg.I.min_raw, self.cfg.I.max_raw
        if raw and (min(raw) < lo or max(raw) > hi):
            raise TransportError(f"{self.name}: raw current outside {self.cfg.I}")
        return raw

    def counters(self) -> dict[str, int]:
        return dict(self.cnt) | {f"clamp_{k}": v for k, v in self.clamps.items()}


class TwinTransport(_Buffered):
    """The bit-exact twin behind the transport interface."""

    name = "fixed"

    def __init__(self, buffer_writes: int = BUFFER_WRITES, progress=None):
        super().__init__(buffer_writes)
        self.progress = progress

    def open(self, config) -> None:
        super().open(config)
        self.twin = IzhikevichTwin(config)
        self.pending: dict[int, list[tuple[int, list[int]]]] = {}
        self.hits_k: list[np.ndarray] = []
        self.hits_n: list[np.ndarray] = []

    def write_currents(self, tick: int, first: int, raw) -> None:
        raw = self._check_write(tick, first, raw)
        if sum(len(w) for w in self.pending.values()) >= self.buffer_writes:
            raise TransportError(f"fixed: write buffer overrun ({self.buffer_writes} writes "
                                 f"pending)")
        self.pending.setdefault(int(tick), []).append((int(first), raw))

    def run(self, n_ticks: int) -> None:
        t0 = time.perf_counter()
        tw = self.twin
        for _ in range(sweep_count(n_ticks, self.name)):
            for first, raw in self.pending.pop(self.tick, []):
                tw.I[first:first + len(raw)] = raw
                self.cnt["writes"] += 1
                self.cnt["words"] += len(raw)
            spk = tw.sweep()
            if spk.any():
                idx = np.flatnonzero(spk)
                self.hits_n.append(idx)
                self.hits_k.append(np.full(idx.size, self.tick, dtype=np.int64))
                self.cnt["spikes_counted"] += idx.size
            self.tick += 1
            self.cnt["sweeps"] += 1
            if self.progress is not None and self.tick % 1000 == 0:
                self.progress(self.tick)
        self.clamps = dict(tw.clamp_counts)
        self.wall_s += time.perf_counter() - t0

    def collect(self) -> SpikeBatch:
        if not self.hits_k:
            return SpikeBatch()
        b = SpikeBatch(np.concatenate(self.hits_k), np.concatenate(self.hits_n))
        self.hits_k, self.hits_n = [], []
        self.cnt["spikes"] += len(b)
        return b


class _Batch(_Buffered):
    """Writes and ticks are buffered; the schedule runs on the engine at :meth:`collect`."""

    def __init__(self, build_dir: Path | None = None, buffer_writes: int = BUFFER_WRITES,
                 progress=None, waves=None):
        super().__init__(buffer_writes)
        self.build_dir = Path(build_dir) if build_dir is not None else None
        self.progress = progress
        self.waves = waves
        self.ran_ticks = 0

    def write_currents(self, tick: int, first: int, raw) -> None:
        raw = self._check_write(tick, first, raw)
        if len(self.writes) >= self.buffer_writes:
            raise TransportError(f"{self.name}: write buffer overrun ({self.buffer_writes} "
                                 f"writes buffered before collect)")
        self.writes.append((int(tick), int(first), raw))

    def run(self, n_ticks: int) -> None:
        self.tick += sweep_count(n_ticks, self.name)

    def collect(self) -> SpikeBatch:
        if self.tick == self.ran_ticks:
            return SpikeBatch()
        if self.ran_ticks:
            raise TransportError(f"{self.name}: a batch engine runs its schedule once; "
                                 f"collect after the last run")
        t0 = time.perf_counter()
        rep = self._execute(self.tick, self.writes)
        self.wall_s += time.perf_counter() - t0
        self.ran_ticks = self.tick
        for k in ("writes", "words", "spikes_counted", "overflow", "overrun", "sweeps"):
            self.cnt[k] += rep[k]
        self.clamps = {k: int(rep["clamp_counts"][k]) for k in CLAMP_KINDS}
        #: wall time of the simulation proper (the rest of wall_s is generation and build)
        self.sim_s = float(rep.get("wall_s", self.wall_s))
        b = SpikeBatch(rep["spike_tick"], rep["spike_neuron"])
        self.cnt["spikes"] += len(b)
        return b

    def _execute(self, n_ticks, writes) -> dict:
        raise NotImplementedError


class CocotbTransport(_Batch):
    """cocotb on Icarus or Verilator (test ``play`` of :mod:`cuneate.sim.izhikevich.bench`)."""

    def __init__(self, simulator: str, build_dir: Path | None = None,
                 buffer_writes: int = BUFFER_WRITES, progress=None, waves=None):
        super().__init__(build_dir, buffer_writes, progress, waves)
        self.name = simulator

    def _execute(self, n_ticks, writes) -> dict:
        cfg = self.cfg
        config = {"core": cfg.to_kwargs(), "ticks": n_ticks,
                  "writes": [[t, f, r] for t, f, r in writes]}
        return run_bench(self.name, izhikevich_verilog(cfg), "izhikevich_core", "izhikevich",
                         config, self.build_dir, testcase="play",
                         progress=self.progress, waves=self.waves).report


class AmaranthTransport(_Batch):
    """The Amaranth simulator on the core, same protocol as the cocotb bench."""

    name = "amaranth"

    def _execute(self, n_ticks, writes) -> dict:
        cfg = self.cfg
        dut = IzhikevichCore(cfg)
        N = cfg.n_neurons
        by_tick: dict[int, list] = {}
        for t, f, r in writes:
            by_tick.setdefault(t, []).append((f, r))
        rep = {"writes": 0, "words": 0, "spikes_counted": 0, "overflow": 0, "overrun": 0,
               "sweeps": 0, "clamp_counts": {k: 0 for k in CLAMP_KINDS}, "spike_tick": [],
               "spike_neuron": []}
        width = cfg.sweep_number_width
        waves = self.waves
        window, finish = _amaranth_window(cfg, waves)

        async def bench(ctx):
            ctx.set(dut.spike_ready, 0)
            for k in range(n_ticks):
                if window is not None:
                    window.on = waves.covers(k)
                for f, r in by_tick.pop(k, []):
                    await write_currents(ctx, dut, r, f)
                    rep["writes"] += 1
                    rep["words"] += len(r)
                ctx.set(dut.tick, 1)
                await ctx.tick()
                ctx.set(dut.tick, 0)
                await ctx.tick().repeat(N + cfg.pipeline_stages + 4)
                rep["sweeps"] += 1
                counted = ctx.get(dut.sweep_count)
                if ctx.get(dut.sweep_number) != k % (1 << width):
                    rep["overrun"] += 1
                rep["spikes_counted"] += counted
                for kk in CLAMP_KINDS:
                    rep["clamp_counts"][kk] += ctx.get(getattr(dut, f"sweep_clamps_{kk}"))
                ctx.set(dut.spike_ready, 1)
                while ctx.get(dut.spike_valid):
                    rep["spike_neuron"].append(ctx.get(dut.spike_index))
                    rep["spike_tick"].append(k)
                    await ctx.tick()
                ctx.set(dut.spike_ready, 0)
                if self.progress is not None and (k + 1) % 1000 == 0:
                    self.progress(k + 1)
            rep["overflow"] = int(ctx.get(dut.spike_overflow))
            rep["overrun"] += int(ctx.get(dut.overrun))

        t0 = time.perf_counter()
        simulate(dut, bench, vcd=window)
        rep["wall_s"] = time.perf_counter() - t0
        finish()
        return rep


class VerilatorFastTransport(_Batch):
    """The core compiled by Verilator with the C++ harness
    (:mod:`cuneate.sim.engines.verilator_fast`): the buffered writes become the harness's
    current schedule (one segment per tick that has writes, each the whole current vector as
    the writes leave it), run in one call with no Python per cycle. The harness drives the
    host port between sweeps like the other engines, so its spikes equal the twin's."""

    name = "verilator-fast"

    def __init__(self, build_dir: Path | None = None, buffer_writes: int = BUFFER_WRITES,
                 progress=None, waves=None):
        if waves:
            raise ValueError("engine 'verilator-fast' writes no waveforms (those that do: "
                             f"{', '.join(WAVE_ENGINES)})")
        super().__init__(build_dir, buffer_writes, progress)

    def _execute(self, n_ticks, writes) -> dict:
        cfg = self.cfg
        cur = np.zeros(cfg.n_neurons, dtype=np.int64)
        segments, words = [], 0
        for t, f, r in writes:
            cur[f:f + len(r)] = r
            words += len(r)
            if segments and segments[-1][0] == t:
                segments[-1] = (t, cur.copy())
            else:
                segments.append((t, cur.copy()))
        run = run_harness(cfg, segments, n_ticks, build_root=self.build_dir)
        if self.progress is not None:
            self.progress(n_ticks)
        s = run.summary
        return {"writes": len(writes), "words": words,
                "spikes_counted": int(s["stream_spikes"]), "overflow":
                int(s["spike_overflow"]), "overrun": int(s["overrun"]), "sweeps": n_ticks,
                "clamp_counts": dict(s["clamp_counts"]), "spike_tick": run.spike_sweeps,
                "spike_neuron": run.spike_neurons, "wall_s": float(s.get("wall_s", 0.0))}
