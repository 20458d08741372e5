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
    the board top :class:`cuneate.hdl.link.LinkedTop` (the network behind the UART link)
    compiled by Verilator behind a simulated serial line, driven by the host stack
    (:class:`cuneate.sim.link.engines.BoardTransport`): the changed currents written in
    lockstep, spikes of both populations back in SPIKES frames (cuneate neuron ``j`` as id
    ``n_afferents + j``), every host and device counter checked.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...golden import coincidence as gcun
from ..engines.amaranth import simulate
from ..engines.registry import check_engine
from ..engines.run import EngineRun, unwrap_ticks

__all__ = ["NetworkRun", "run_network", "current_writes", "current_runs"]

#: A network run is an :class:`~cuneate.sim.engines.run.EngineRun` with the populations
#: ``afferent`` and ``cuneate``.
NetworkRun = EngineRun


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
    from ...golden import izhikevich as giz
    from ...hdl.network import NetworkTwin
    check_engine("network", engine)
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
        elif engine == "board":
            pa, pc, counters = _run_network_board(cfg, writes, n)
        else:
            pa, pc, counters = _run_network_cocotb(engine, cfg, writes, n, build_dir)
        aff = [np.array([(k + 1) * dt for k, i in sorted(pa) if i == j]) for j in range(N)]
        cun = [np.array([(k + 1) * dt for k, t in sorted(pc) if t == j]) for j in range(M)]
    return EngineRun(engine, dt, n, aff + cun, wall_s=time.perf_counter() - t0,
                     counters=counters, populations={"afferent": (0, N), "cuneate": (N, M)})


def _run_network_amaranth(cfg, writes: dict, n_ticks: int):
    from ...hdl.network import AfferentCuneateNetwork
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


def _run_network_board(cfg, writes: dict, n_ticks: int):
    from ..link.engines import BoardTransport
    tr = BoardTransport()
    tr.open(cfg)
    try:
        for k in sorted(writes):
            for first, raw in current_runs(writes[k]):
                tr.write_currents(k, first, raw)
        tr.run(n_ticks)
        got = tr.collect()
        counters = tr.check()
    finally:
        tr.close()
    counters |= {f"board_{k}": v for k, v in tr.figures().items()}
    N = cfg.n_afferents
    pairs = list(zip(got.tick.tolist(), got.neuron.tolist()))
    pa = [(t, i) for t, i in pairs if i < N]
    pc = [(t, i - N) for t, i in pairs if i >= N]
    return pa, pc, counters


def _split_stream(cfg, stream, n_ticks):
    pa = [(t, i) for p, t, i in stream if p == 0]
    pc = [(t, i) for p, t, i in stream if p == 1]
    w = cfg.tick_width
    pa = list(zip(unwrap_ticks([t for t, _ in pa], w), [i for _, i in pa]))
    pc = list(zip(unwrap_ticks([t for t, _ in pc], w), [i for _, i in pc]))
    return pa, pc


def _run_network_cocotb(simulator: str, cfg, writes: dict, n_ticks: int,
                        build_dir: Path | None):
    from ...hdl.network import network_verilog
    from ..engines.cocotb import run_engine_bench
    rep = run_engine_bench(simulator, lambda low: network_verilog(cfg, lowered=low),
                           "afferent_cuneate_network", "network",
                           {"network": cfg.to_kwargs(), "ticks": n_ticks,
                            "writes": {str(k): v for k, v in writes.items()}}, build_dir)
    pa, pc = _split_stream(cfg, [tuple(x) for x in rep["stream"]], n_ticks)
    return pa, pc, rep["counters"]
