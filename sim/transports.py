"""Transports of the simulation engines (see :mod:`cuneate.sim.transport`).

``fixed`` (:class:`TwinTransport`)
    The bit-exact twin, stepped sweep by sweep; writes take effect at their tick.
``amaranth`` (:class:`AmaranthTransport`)
    The Amaranth simulator on :class:`~cuneate.hdl.izhikevich.IzhikevichCore`: the buffered
    write schedule is played through the core's host-write port at :meth:`collect`.
``icarus`` / ``verilator`` (:class:`CocotbTransport`)
    cocotb on the generated Verilog (bench ``cuneate.sim.benches.driver_tb``), the same
    schedule played at :meth:`collect`.

The hardware engines share one sweep protocol (:data:`PROTOCOL`): the writes due at tick ``k``
are driven through the host-write port after sweep ``k - 1`` has left the pipeline and before
the tick of sweep ``k`` (so no write can reach the wrong sweep); the spike FIFO (one entry per
neuron deep) is read out between sweeps and checked against the core's own per-sweep spike
count. Idle cycles between sweeps do not change the arithmetic (external tick).

Every transport refuses a write for a tick already run (``TransportError``) and a schedule
longer than its buffer (``buffer_writes``; a buffer overrun is an error, never a silent drop).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from ..hdl.izhikevich import CLAMP_KINDS, PIPELINE_DEPTH, IzhikevichConfig, IzhikevichTwin
from .transport import SpikeBatch, Transport, TransportError

__all__ = ["TwinTransport", "CocotbTransport", "AmaranthTransport", "TRANSPORTS",
           "make_transport", "PROTOCOL"]

PROTOCOL = "writes between sweeps, external tick, FIFO drained between sweeps"
#: Default write-buffer capacity of the batch transports (write calls held until collect).
BUFFER_WRITES = 1 << 20


class _Buffered(Transport):
    """Common bookkeeping: tick, write schedule, counters."""

    def __init__(self, buffer_writes: int = BUFFER_WRITES):
        self.buffer_writes = int(buffer_writes)
        self.cfg: IzhikevichConfig | None = None
        self.tick = 0
        self.writes: list[tuple[int, int, list[int]]] = []
        self.cnt = {"writes": 0, "words": 0, "spikes": 0, "spikes_counted": 0, "overflow": 0,
                    "overrun": 0, "late_writes": 0, "sweeps": 0}
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
        for _ in range(int(n_ticks)):
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
                 progress=None):
        super().__init__(buffer_writes)
        self.build_dir = Path(build_dir) if build_dir is not None else None
        self.progress = progress
        self.ran_ticks = 0

    def write_currents(self, tick: int, first: int, raw) -> None:
        raw = self._check_write(tick, first, raw)
        if len(self.writes) >= self.buffer_writes:
            raise TransportError(f"{self.name}: write buffer overrun ({self.buffer_writes} "
                                 f"writes buffered before collect)")
        self.writes.append((int(tick), int(first), raw))

    def run(self, n_ticks: int) -> None:
        self.tick += int(n_ticks)

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
        self.cnt["writes"] += rep["writes"]
        self.cnt["words"] += rep["words"]
        self.cnt["spikes_counted"] += rep["spikes_counted"]
        self.cnt["overflow"] += rep["overflow"]
        self.cnt["overrun"] += rep["overrun"]
        self.cnt["sweeps"] += rep["sweeps"]
        self.clamps = {k: int(rep["clamp_counts"][k]) for k in CLAMP_KINDS}
        #: wall time of the simulation proper (the rest of wall_s is generation and build)
        self.sim_s = float(rep.get("wall_s", self.wall_s))
        b = SpikeBatch(rep["spike_tick"], rep["spike_neuron"])
        self.cnt["spikes"] += len(b)
        return b

    def _execute(self, n_ticks, writes) -> dict:
        raise NotImplementedError


class CocotbTransport(_Batch):
    """cocotb on Icarus or Verilator (bench :mod:`cuneate.sim.benches.driver_tb`)."""

    def __init__(self, simulator: str, build_dir: Path | None = None,
                 buffer_writes: int = BUFFER_WRITES, progress=None):
        super().__init__(build_dir, buffer_writes, progress)
        self.name = simulator

    def _execute(self, n_ticks, writes) -> dict:
        from ..hdl.izhikevich import izhikevich_verilog
        from .runner import run_cocotb
        cfg = self.cfg
        config = {"core": cfg.to_kwargs(), "ticks": n_ticks,
                  "writes": [[t, f, r] for t, f, r in writes]}

        def go(d: Path):
            d.mkdir(parents=True, exist_ok=True)
            src = d / "izhikevich_core.v"
            src.write_text(izhikevich_verilog(cfg))
            return run_cocotb(self.name, [src], "izhikevich_core",
                              "cuneate.sim.benches.driver_tb", d, config=config,
                              testcase="play", progress=self.progress).report
        if self.build_dir is not None:
            return go(self.build_dir)
        with tempfile.TemporaryDirectory(prefix=f"cuneate-{self.name}-") as tmp:
            return go(Path(tmp))


class AmaranthTransport(_Batch):
    """The Amaranth simulator on the core, same protocol as the cocotb bench."""

    name = "amaranth"

    def _execute(self, n_ticks, writes) -> dict:
        from amaranth.sim import Simulator
        from ..hdl.izhikevich import IzhikevichCore
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

        async def bench(ctx):
            ctx.set(dut.spike_ready, 0)
            for k in range(n_ticks):
                for f, r in by_tick.pop(k, []):
                    for i, x in enumerate(r):
                        ctx.set(dut.i_wr_en, 1)
                        ctx.set(dut.i_wr_addr, f + i)
                        ctx.set(dut.i_wr_data, x)
                        await ctx.tick()
                    rep["writes"] += 1
                    rep["words"] += len(r)
                ctx.set(dut.i_wr_en, 0)
                ctx.set(dut.tick, 1)
                await ctx.tick()
                ctx.set(dut.tick, 0)
                await ctx.tick().repeat(N + PIPELINE_DEPTH + 4)
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

        sim = Simulator(dut)
        sim.add_clock(1e-6)
        sim.add_testbench(bench)
        t0 = time.perf_counter()
        sim.run()
        rep["wall_s"] = time.perf_counter() - t0
        return rep


#: Engine name -> transport factory (``build_dir`` and ``progress`` keywords).
TRANSPORTS = {
    "fixed": lambda **kw: TwinTransport(progress=kw.get("progress")),
    "amaranth": lambda **kw: AmaranthTransport(**kw),
    "icarus": lambda **kw: CocotbTransport("icarus", **kw),
    "verilator": lambda **kw: CocotbTransport("verilator", **kw),
}


def make_transport(engine: str, **kw) -> Transport:
    if engine not in TRANSPORTS:
        raise ValueError(f"unknown engine {engine!r}; known: {', '.join(TRANSPORTS)}")
    return TRANSPORTS[engine](**kw)
