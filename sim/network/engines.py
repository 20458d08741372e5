"""The engines of the on-chip afferent -> cuneate network: one host current schedule, five
engines, one spike convention for both populations (update of tick ``T`` -> ``(T + 1) dt``).

``golden``
    the float64 afferents (:mod:`cuneate.golden.izhikevich`) feeding their spikes, stamped one
    tick later, to the float64 cuneate model (:mod:`cuneate.golden.coincidence`);
``fixed``
    :class:`cuneate.hdl.network.NetworkTwin`;
``amaranth``
    the Amaranth simulator on :class:`cuneate.hdl.network.AfferentCuneateNetwork`;
``icarus``, ``verilator``
    cocotb on its Verilog (bench :mod:`cuneate.sim.network.bench`, test ``engine``; Icarus runs
    the yosys-lowered netlist);
``board``
    the network behind the UART link (:mod:`cuneate.sim.engines.board`).

:class:`NetworkEngine` is the block's engine interface; each engine implements it and
registers itself (:func:`~cuneate.sim.engines.registry.implements`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...golden import coincidence as gcun
from ...golden import izhikevich as giz
from ...hdl.network import AfferentCuneateNetwork, NetworkTwin, network_verilog
from ..engines.amaranth import simulate
from ..engines.engine import BlockEngine
from ..engines.registry import engine_for, implements
from ..engines.run import EngineRun, times_from_pairs, unwrap_ticks

__all__ = ["NetworkEngine", "run_network", "current_writes", "current_runs"]


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


class NetworkEngine(BlockEngine):
    """The afferent -> cuneate network on one engine: :meth:`run` host currents."""

    block = "network"

    def run(self, cfg, cur: np.ndarray) -> EngineRun:
        """Host currents ``cur`` ``(n_ticks, n_afferents)`` (mV/ms, written before each tick)
        on ``cfg`` (external tick): both populations' spikes."""
        n, N, M = cur.shape[0], cfg.n_afferents, cfg.n_targets
        t0 = time.perf_counter()
        spikes, counters = self.spikes(cfg, cur, n)
        return EngineRun(self.name, cfg.dt_ms, n, spikes, wall_s=time.perf_counter() - t0,
                         counters=counters, populations={"afferent": (0, N), "cuneate": (N, M)})

    def spikes(self, cfg, cur: np.ndarray, n: int):
        """``(spike times of the afferents then the cuneate neurons, counters)``: by default
        from :meth:`pairs` on the host's writes (:func:`current_writes`)."""
        pa, pc, counters = self.pairs(cfg, current_writes(cfg, cur), n)
        dt = cfg.dt_ms
        return times_from_pairs(pa, cfg.n_afferents, dt) + \
            times_from_pairs(pc, cfg.n_targets, dt), counters

    def pairs(self, cfg, writes: dict, n_ticks: int):
        """``(afferent (tick, index) pairs, cuneate pairs, counters)``; by default through
        :meth:`transport` (the changed currents written in lockstep, one write per run of
        consecutive afferents; spike ids ``n_afferents + j`` are cuneate neuron ``j``)."""
        got, counters = self.stream(cfg, {k: current_runs(w) for k, w in writes.items()},
                                    n_ticks)
        N = cfg.n_afferents
        pairs = list(zip(got.tick.tolist(), got.neuron.tolist()))
        return ([(t, i) for t, i in pairs if i < N], [(t, i - N) for t, i in pairs if i >= N],
                counters)


@implements("network", "golden", speed=8e5)
class NetworkGolden(NetworkEngine):
    """The float64 afferents feeding their spikes, stamped one tick later, to the float64
    cuneate model."""

    def spikes(self, cfg, cur, n):
        current_writes(cfg, cur)                    # the same refusals as the other engines
        N, F, S, dt = cfg.n_afferents, cfg.first_source, cfg.n_sources, cfg.dt_ms
        params = [cfg.afferent_param_sets[s] for s in cfg.core.neuron_sets]
        r = giz.simulate(params, cur, n_steps=n, n_neurons=N, dt_ms=dt)
        aff = [np.asarray(s, dtype=np.float64) for s in r.spikes_ms]
        det = cfg.det
        g = gcun.simulate_cuneate([aff[F + s] for s in range(S)], det.delays * dt, n * dt,
                                  dt_ms=dt, J=1.0, weights=det.weights_real,
                                  params=[det.param_sets[s] for s in det.target_sets_],
                                  tau_rise_ms=det.tau_rise_ms, tau_decay_ms=det.tau_decay_ms)
        return aff + [np.asarray(s, dtype=np.float64) for s in g.spikes_ms], {}


@implements("network", "fixed", speed=8e4)
class NetworkFixed(NetworkEngine):
    """:class:`~cuneate.hdl.network.NetworkTwin`."""

    def pairs(self, cfg, writes, n_ticks):
        F, S = cfg.first_source, cfg.n_sources
        tw = NetworkTwin(cfg)
        pa, pc = [], []
        for k in range(n_ticks):
            for i, raw in writes.get(k, []):
                tw.core.I[i] = raw
            a, c = tw.tick()
            pa += [(k, int(i)) for i in np.flatnonzero(a)]
            pc += [(k, int(t)) for t in np.flatnonzero(c)]
        return pa, pc, {"link_count": sum(1 for _, i in pa if F <= i < F + S),
                        "merged_count": tw.det.merged}


@implements("network", "amaranth", speed=5e3)
class NetworkAmaranth(NetworkEngine):
    """The Amaranth simulator on :class:`~cuneate.hdl.network.AfferentCuneateNetwork`."""

    def pairs(self, cfg, writes, n_ticks):
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

        simulate(dut, tb, cfg.clock_hz)
        return _split_stream(cfg, stream, n_ticks) + (out,)


@implements("network", "icarus", speed=5e3)
@implements("network", "verilator", speed=5e4)
class NetworkCocotb(NetworkEngine):
    """cocotb on the network's Verilog (Icarus: the yosys-lowered netlist)."""

    def pairs(self, cfg, writes, n_ticks):
        rep = self.engine_bench(lambda low: network_verilog(cfg, lowered=low),
                                "afferent_cuneate_network",
                                {"network": cfg.to_kwargs(), "ticks": n_ticks,
                                 "writes": {str(k): v for k, v in writes.items()}})
        pa, pc = _split_stream(cfg, [tuple(x) for x in rep["stream"]], n_ticks)
        return pa, pc, rep["counters"]


def run_network(engine: str, cfg, currents, build_dir: Path | None = None) -> EngineRun:
    """Run the network (:class:`cuneate.hdl.network.NetworkConfig`) with host currents
    ``(n_ticks, n_afferents)`` (mV/ms, written before each tick) on ``engine``: an
    :class:`~cuneate.sim.engines.run.EngineRun` with the populations ``afferent`` and
    ``cuneate``. Spike times use
    the golden convention for both populations (update of tick ``T`` -> ``(T + 1) dt``); the
    golden engine runs the float64 afferents and feeds their spikes, stamped one tick later,
    to the float64 cuneate model."""
    impl = engine_for("network", engine, build_dir=build_dir)
    if cfg.tick_source != "external":               # the engines tick the network themselves
        cfg = type(cfg)(**(cfg.to_kwargs() | {"tick_source": "external"}))
    return impl.run(cfg, np.asarray(currents, dtype=np.float64))


def current_runs(writes: list[tuple[int, int]]) -> list[tuple[int, list[int]]]:
    """One tick's writes ``[(afferent, raw), ...]`` as runs of consecutive afferents
    ``[(first, [raw, ...]), ...]`` (one link write each)."""
    runs: list[tuple[int, list[int]]] = []
    for i, raw in sorted(writes):
        if runs and runs[-1][0] + len(runs[-1][1]) == i:
            runs[-1][1].append(raw)
        else:
            runs.append((i, [raw]))
    return runs


def _split_stream(cfg, stream, n_ticks):
    pa = [(t, i) for p, t, i in stream if p == 0]
    pc = [(t, i) for p, t, i in stream if p == 1]
    w = cfg.tick_width
    pa = list(zip(unwrap_ticks([t for t, _ in pa], w), [i for _, i in pa]))
    pc = list(zip(unwrap_ticks([t for t, _ in pc], w), [i for _, i in pc]))
    return pa, pc
