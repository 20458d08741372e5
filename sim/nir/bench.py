"""cocotb benches for the generated :class:`cuneate.hdl.nir.NirNetwork` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG`` (``network``: the configuration's
keywords; ``currents``: the raw biases per layer; ``inputs``: per step the input sources); the
report goes to ``CUNEATE_BENCH_REPORT``. Both tests run the network like a host: the biases
written once, then per step the input events and a tick (taken by the network once its cores
have settled), the output stream read every cycle.

``engine``
    Records the output stream (spikes with their sweep, or the readout layer's membrane).
``scoreboard``
    Also watches every layer's update probe (``layer<l>.upd_*``) every cycle. Every whole sweep
    of every layer is checked by :class:`~cuneate.sim.lif.scoreboard.LifSweepChecker`: the
    bit-exact twin from the DUT's own previous state (v, refractory counter, spike, accumulated
    input, synaptic trace, clamp flags: zero mismatches), with as input the spikes the layer
    received - the host's events of that step for layer 0, the spikes of layer ``l - 1``'s
    previous sweep as the DUT produced them for layer ``l`` - and the float64 golden step within
    its derived bound. The output stream must hold exactly the last layer's spikes.
"""

from __future__ import annotations

import time

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge

from cuneate.hdl.nir import NirNetworkConfig
from cuneate.sim.engines.bench import bench_config, bench_progress, bench_report, spikes_then_tick
from cuneate.sim.engines.run import TickUnwrap
from cuneate.sim.lif.scoreboard import LifSweepChecker


class _Layer:
    """The per-cycle monitor of one layer's update probe."""

    def __init__(self, probe, cfg):
        self.p, self.cfg, self.fill = probe, cfg, 0
        N = cfg.n_neurons
        self.buf = {k: np.zeros(N, dtype=np.int64) for k in ("v", "ref", "i", "acc", "spike",
                                                             "clamp")}
        self.tr = np.zeros((len(cfg.traces), N), dtype=np.int64)
        self.order_errors = 0

    def sample(self) -> bool:
        p = self.p
        if not int(p.upd_valid.value):
            return False
        idx = int(p.upd_index.value)
        if idx != self.fill:
            self.order_errors += 1
        b = self.buf
        b["v"][idx] = p.upd_v.value.to_signed()
        b["ref"][idx] = int(p.upd_ref.value) if self.cfg.ref_bits else 0
        b["i"][idx] = p.upd_current.value.to_signed()
        b["acc"][idx] = p.upd_acc.value.to_signed() if self.cfg.n_inputs else 0
        b["spike"][idx] = int(p.upd_spike.value)
        b["clamp"][idx] = int(p.upd_clamp.value)
        for j, t in enumerate(self.cfg.traces):
            self.tr[j, idx] = getattr(p, f"upd_{t.name}").value.to_signed()
        self.fill = idx + 1
        if idx == self.cfg.n_neurons - 1:
            self.fill = 0
            return True
        return False


async def _run(dut, check: bool):
    spec = bench_config()
    cfg = NirNetworkConfig.from_kwargs(spec["network"])
    T = len(spec["inputs"])
    last = cfg.layers[-1]
    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.rst.value = 1
    for s in (dut.tick, dut.i_wr_en, dut.i_wr_layer, dut.i_wr_addr, dut.i_wr_data):
        s.value = 0
    if cfg.n_inputs:
        dut.in_valid.value = 0
        dut.in_source.value = 0
    dut.out_ready.value = 1
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
    layers = [_Layer(getattr(dut, f"layer{i}"), c) for i, c in enumerate(cfg.layers)]
    checkers = [LifSweepChecker(c) for c in cfg.layers] if check else []
    # x[l][k]: the input vector layer l's sweep k uses (before its input delays)
    out_spikes, out_v = [], []
    vrow = np.zeros(last.n_neurons, dtype=np.int64)
    unwrap = TickUnwrap(last.sweep_number_width)
    swept = [0] * cfg.n_layers
    host_x = [np.zeros(cfg.n_inputs, dtype=bool) for _ in range(T)]
    for k, srcs in enumerate(spec["inputs"]):
        host_x[k][srcs] = True
    produced = [[] for _ in cfg.layers]
    t0 = time.perf_counter()

    def sample():
        if int(dut.out_valid.value):
            out_spikes.append((int(dut.out_index.value), unwrap(int(dut.out_sweep.value))))
        if int(dut.out_v_valid.value):
            idx = int(dut.out_v_index.value)
            vrow[idx] = dut.out_v.value.to_signed()
            if idx == last.n_neurons - 1:
                out_v.append(vrow.tolist())
        for li, lay in enumerate(layers):
            if lay.sample():
                k = swept[li]
                spk = lay.buf["spike"].astype(bool)
                produced[li].append(spk.copy())
                if check:
                    if li == 0:
                        x = host_x[k] if k < T else np.zeros(cfg.n_inputs, dtype=bool)
                    else:
                        x = produced[li - 1][k - 1] if k >= 1 else \
                            np.zeros(cfg.layers[li - 1].n_neurons, dtype=bool)
                    b = lay.buf
                    checkers[li].check(b["v"], b["ref"], b["i"], b["acc"], spk, b["clamp"],
                                       x if cfg.layers[li].n_inputs else None,
                                       lay.tr if cfg.layers[li].traces else None)
                swept[li] += 1

    async def step():
        await FallingEdge(dut.clk)
        sample()

    for li, cur in enumerate(spec["currents"]):
        dut.i_wr_en.value = 1
        dut.i_wr_layer.value = li
        for i, raw in enumerate(cur):
            dut.i_wr_addr.value = i
            dut.i_wr_data.value = int(raw)
            await step()
    dut.i_wr_en.value = 0
    for k, srcs in enumerate(spec["inputs"]):
        while int(dut.busy.value):
            await step()
        await spikes_then_tick(dut, srcs, step, bool(cfg.n_inputs))
        bench_progress(spec, k + 1)
    for _ in range(cfg.settle_cycles + last.spike_fifo_depth + 8):
        await step()
    rep = {"out_spikes": out_spikes, "out_v": out_v, "sweeps": swept,
           "wall_s": time.perf_counter() - t0,
           "overrun": int(dut.tick_overrun.value),
           "spike_overflow": int(dut.spike_overflow.value),
           "order_errors": sum(lay.order_errors for lay in layers)}
    if check:
        rep["layers"] = [c.stats for c in checkers]
        rep["failures"] = [f"layer {i}: {f}" for i, c in enumerate(checkers)
                           for f in c.failures()]
        expect = sorted((int(n), k) for k, row in enumerate(produced[-1]) for n in
                        np.flatnonzero(row))
        rep["stream_matches"] = sorted(out_spikes) == expect
    bench_report(rep)
    assert rep["overrun"] == 0 and rep["spike_overflow"] == 0 and rep["order_errors"] == 0
    assert all(s == T for s in swept), swept
    if check:
        assert not rep["failures"], rep["failures"]
        assert rep["stream_matches"]


@cocotb.test()
async def engine(dut):
    await _run(dut, check=False)


@cocotb.test()
async def scoreboard(dut):
    await _run(dut, check=True)
