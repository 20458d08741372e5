"""Engines for a NIR network: one input program, five engines, one spike convention.

The input is ``(steps, n_inputs)``: spikes (0/1) or, when the graph thresholds its input
(``Input -> Threshold``), values the host thresholds into spikes. Every engine reports the last
layer's spikes ``(steps, n_outputs)`` (update ``k`` -> ``(k + 1) dt``) or, for a readout layer
(LI, CubaLI), its membrane after every update.

``golden``
    :func:`cuneate.golden.nir.simulate_layers`: NIR's equations with the NIR parameters in
    float64 on the grid (the mapping's scheme), unquantized.
``fixed``
    :class:`cuneate.hdl.nir.NirNetworkTwin`: the bit-exact chain of LIF twins.
``amaranth``
    The Amaranth simulator on :class:`cuneate.hdl.nir.NirNetwork`.
``icarus``, ``verilator``
    cocotb on the generated Verilog (:mod:`cuneate.sim.nir.bench`, test ``engine``).

The hardware engines run like a host: the biases written once, then per step the input spikes
as events and a tick, the network holding the tick until its cores have settled.

A run is an :class:`~cuneate.sim.engines.run.EngineRun`: the last layer's spike times, or a
readout's membrane in ``values`` (``v``). :class:`NirEngine` is the block's engine interface;
each engine implements it and registers itself
(:func:`~cuneate.sim.engines.registry.implements`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...golden.nir import simulate_layers
from ...hdl.nir import NirNetwork, NirNetworkTwin, nir_network_verilog
from ..engines.amaranth import simulate, spikes_then_tick
from ..engines.cocotb import run_bench
from ..engines.engine import BlockEngine
from ..engines.registry import engine_for, implements
from ..engines.run import EngineRun, TickUnwrap, spike_times
from .graph import NirError
from .mapping import MappedNetwork

__all__ = ["NirEngine", "run_network", "input_spikes", "host_program", "run_dict"]


def run_dict(run: EngineRun, mapped: MappedNetwork) -> dict:
    """A run as ``simulate nir --json`` prints it: times in seconds, spike counts, the
    readout's last membrane."""
    d = {"engine": run.engine, "dt_s": mapped.dt, "steps": run.n_ticks,
         "clamps": run.clamp_counts, "wall_s": run.wall_s}
    if run.spikes_ms is not None:
        d["spike_counts"] = run.counts().tolist()
        d["spikes_s"] = [spike_times(run.spike_ticks(i), mapped.dt).tolist()
                         for i in range(len(run.spikes_ms))]
    if run.values is not None:
        d["v_last"] = run.values[-1].tolist()
    return d


def input_spikes(mapped: MappedNetwork, inputs) -> np.ndarray:
    """The spikes the first layer receives: the input thresholded by the graph's Threshold, or
    the input itself, which must then be 0/1."""
    x = np.asarray(inputs, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != mapped.n_inputs:
        raise NirError(f"the input must have shape (steps, {mapped.n_inputs}), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise NirError("the input holds values that are not finite")
    thr = mapped.chain.input_threshold
    if thr is not None:
        return x > thr[None, :]
    if not np.all((x == 0) | (x == 1)):
        raise NirError("the input holds values other than 0 and 1; the LIF cores take spikes "
                       "(threshold it in the graph: Input -> Threshold)")
    return x.astype(bool)


class NirEngine(BlockEngine):
    """A NIR network on one engine: :meth:`run` the first layer's input spikes."""

    block = "nir"

    def run(self, mapped: MappedNetwork, x: np.ndarray, scoreboard: bool = False) -> EngineRun:
        """Input spikes ``x`` ``(steps, n_inputs)``: the last layer's spikes, or a readout's
        membrane."""
        t0 = time.perf_counter()
        raster, v, clamps = self.outputs(mapped, x, scoreboard)
        dt_ms = mapped.dt * 1e3
        spikes = None if raster is None else \
            [spike_times(np.flatnonzero(raster[:, i]), dt_ms) for i in range(raster.shape[1])]
        return EngineRun(self.name, dt_ms, int(x.shape[0]), spikes, clamps, {},
                         time.perf_counter() - t0, values=v)

    def outputs(self, mapped: MappedNetwork, x: np.ndarray, scoreboard: bool):
        """``(spike raster (steps, n_out) or None, readout membrane or None, clamps)``."""
        raise NotImplementedError


@implements("nir", "golden", speed=2e6)
class NirGolden(NirEngine):
    """NIR's equations in float64 on the grid, unquantized."""

    def outputs(self, mapped, x, scoreboard):
        res = simulate_layers(mapped.chain.layers, x.astype(np.float64), mapped.dt,
                              mapped.scheme)[-1]
        return res.spikes, (res.v if mapped.config.readout else None), {}


@implements("nir", "fixed", speed=2e5)
class NirFixed(NirEngine):
    """The bit-exact chain of LIF twins."""

    def outputs(self, mapped, x, scoreboard):
        run = NirNetworkTwin(mapped.config, mapped.currents_raw).run(x)
        readout = mapped.config.readout
        return (None if readout else run.spikes[-1][:, :mapped.n_outputs],
                _v_float(mapped, run.v_raw) if readout else None,
                {f"layer{i}": c["counts"] for i, c in enumerate(run.clamps)})


class _NirHost(NirEngine):
    """The hardware engines: a host program (:func:`host_program`) on the network."""

    def outputs(self, mapped, x, scoreboard):
        n = mapped.n_outputs
        rep = self.report(mapped, host_program(mapped, x), scoreboard)
        if mapped.config.readout:
            v, spikes = _v_float(mapped, np.asarray(rep["out_v"], dtype=np.int64)), None
        else:
            v, spikes = None, np.zeros((x.shape[0], n), dtype=bool)
            for i, k in rep["out_spikes"]:
                if i < n and k < x.shape[0]:
                    spikes[k, i] = True
        return spikes, v, (rep if scoreboard else rep.get("clamps", {}))

    def report(self, mapped, prog: dict, scoreboard: bool) -> dict:
        raise NotImplementedError


@implements("nir", "amaranth", speed=3e3)
class NirAmaranth(_NirHost):
    """The Amaranth simulator on :class:`~cuneate.hdl.nir.NirNetwork`."""

    def report(self, mapped, prog, scoreboard):
        return _run_amaranth(mapped, prog)


@implements("nir", "icarus", speed=3e3)
@implements("nir", "verilator", speed=3e4)
class NirCocotb(_NirHost):
    """cocotb on the generated Verilog; ``scoreboard``: the per-cycle scoreboard bench."""

    def report(self, mapped, prog, scoreboard):
        return run_bench(self.name, nir_network_verilog(mapped.config), "nir_network", "nir",
                         prog | {"network": mapped.config.to_kwargs()}, self.build_dir,
                         testcase="scoreboard" if scoreboard else "engine").report


def run_network(engine: str, mapped: MappedNetwork, inputs, build_dir: Path | None = None,
                scoreboard: bool = False) -> EngineRun:
    """Run ``inputs`` on ``engine`` (see the module docstring). ``scoreboard`` (icarus,
    verilator): the per-cycle scoreboard bench instead of the plain engine bench."""
    impl = engine_for("nir", engine, build_dir=build_dir)
    return impl.run(mapped, input_spikes(mapped, inputs), scoreboard)


def _v_float(mapped: MappedNetwork, v_raw) -> np.ndarray:
    cfg = mapped.config.layers[-1]
    n = mapped.n_outputs
    leak = mapped.chain.layers[-1].v_leak
    leak = np.zeros(n) if leak is None else np.asarray(leak)
    sc = mapped.report[-1].get("state_scale", 1.0)
    return cfg.V.to_float(np.asarray(v_raw)[:, :n]) / sc + leak[None, :]


def host_program(mapped: MappedNetwork, x: np.ndarray) -> dict:
    """What a host sends: the biases (raw, per layer) and per step the input sources."""
    return {"currents": [c.tolist() for c in mapped.currents_raw],
            "inputs": [np.flatnonzero(row).tolist() for row in x]}


def _run_amaranth(mapped: MappedNetwork, prog: dict) -> dict:
    cfg = mapped.config
    dut = NirNetwork(cfg)
    last = cfg.layers[-1]
    out_spikes, out_v = [], []
    unwrap = TickUnwrap(last.sweep_number_width)
    T = len(prog["inputs"])
    vrow = np.zeros(last.n_neurons, dtype=np.int64)
    state = {"sweep": -1}

    async def bench(ctx):
        ctx.set(dut.out_ready, 1)

        async def step():
            await ctx.tick()
            if ctx.get(dut.out_valid):
                out_spikes.append((ctx.get(dut.out_index), unwrap(ctx.get(dut.out_sweep))))
            if ctx.get(dut.out_v_valid):
                idx = ctx.get(dut.out_v_index)
                vrow[idx] = ctx.get(dut.out_v)
                if idx == last.n_neurons - 1:
                    out_v.append(vrow.copy())

        for li, cur in enumerate(prog["currents"]):
            ctx.set(dut.i_wr_en, 1)
            ctx.set(dut.i_wr_layer, li)
            for i, raw in enumerate(cur):
                ctx.set(dut.i_wr_addr, i)
                ctx.set(dut.i_wr_data, int(raw))
                await step()
        ctx.set(dut.i_wr_en, 0)
        for k in range(T):
            while ctx.get(dut.busy):
                await step()
            await spikes_then_tick(ctx, dut, prog["inputs"][k], step, bool(cfg.n_inputs))
        for _ in range(cfg.settle_cycles + last.spike_fifo_depth + 8):
            await step()
        state["overflow"] = ctx.get(dut.spike_overflow)
        state["overrun"] = ctx.get(dut.tick_overrun)

    simulate(dut, bench)
    if state["overflow"] or state["overrun"]:
        raise RuntimeError("the network dropped a spike or a tick (spike_overflow / "
                           "tick_overrun)")
    return {"out_spikes": out_spikes, "out_v": [r.tolist() for r in out_v]}
