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
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...golden.nir import simulate_layers
from ...hdl.nir import NirNetwork, NirNetworkTwin, nir_network_verilog
from ..engines.amaranth import simulate, spikes_then_tick
from ..engines.registry import check_engine
from ..engines.run import TickUnwrap
from .graph import NirError
from .mapping import MappedNetwork

__all__ = ["NirRun", "run_network", "input_spikes", "host_program"]


@dataclass
class NirRun:
    """One engine's run: ``spikes`` (steps, n_out) bool or None, ``v`` (steps, n_out) or None,
    ``clamps`` (counts per kind and layer, hardware engines), wall time."""

    engine: str
    dt_s: float
    steps: int
    spikes: np.ndarray | None
    v: np.ndarray | None
    clamps: dict
    wall_s: float

    def counts(self) -> np.ndarray:
        return self.spikes.sum(axis=0) if self.spikes is not None else np.zeros(0, np.int64)

    def to_dict(self) -> dict:
        d = {"engine": self.engine, "dt_s": self.dt_s, "steps": self.steps,
             "clamps": self.clamps, "wall_s": self.wall_s}
        if self.spikes is not None:
            d["spike_counts"] = self.counts().tolist()
            d["spikes_s"] = [((np.flatnonzero(self.spikes[:, i]) + 1) * self.dt_s).tolist()
                             for i in range(self.spikes.shape[1])]
        if self.v is not None:
            d["v_last"] = self.v[-1].tolist()
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


def run_network(engine: str, mapped: MappedNetwork, inputs, build_dir: Path | None = None,
                scoreboard: bool = False) -> NirRun:
    """Run ``inputs`` on ``engine`` (see the module docstring). ``scoreboard`` (icarus,
    verilator): the per-cycle scoreboard bench instead of the plain engine bench."""
    check_engine("nir", engine)
    x = input_spikes(mapped, inputs)
    t0 = time.perf_counter()
    n = mapped.n_outputs
    readout = mapped.config.readout
    clamps: dict = {}
    if engine == "golden":
        src = x.astype(np.float64)
        res = simulate_layers(mapped.chain.layers, src, mapped.dt, mapped.scheme)[-1]
        spikes, v = res.spikes, (res.v if readout else None)
    elif engine == "fixed":
        run = NirNetworkTwin(mapped.config, mapped.currents_raw).run(x)
        spikes = None if readout else run.spikes[-1][:, :n]
        v = _v_float(mapped, run.v_raw) if readout else None
        clamps = {f"layer{i}": c["counts"] for i, c in enumerate(run.clamps)}
    else:
        prog = host_program(mapped, x)
        if engine == "amaranth":
            rep = _run_amaranth(mapped, prog)
        else:
            from ..engines.cocotb import run_bench
            rep = run_bench(engine, nir_network_verilog(mapped.config), "nir_network", "nir",
                            prog | {"network": mapped.config.to_kwargs()}, build_dir,
                            testcase="scoreboard" if scoreboard else "engine").report
        spikes = np.zeros((x.shape[0], n), dtype=bool)
        for i, k in rep["out_spikes"]:
            if i < n and k < x.shape[0]:
                spikes[k, i] = True
        v = None
        if readout:
            v = _v_float(mapped, np.asarray(rep["out_v"], dtype=np.int64))
            spikes = None
        clamps = rep.get("clamps", {})
        if scoreboard:
            clamps = rep
    return NirRun(engine, mapped.dt, int(x.shape[0]), spikes, v, clamps,
                  time.perf_counter() - t0)


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
