"""cocotb benches for the generated :class:`cuneate.hdl.izhikevich.IzhikevichCore` Verilog.

The bench is configured by the JSON file named in ``CUNEATE_BENCH_CONFIG`` and writes its
figures to ``CUNEATE_BENCH_REPORT``. Two tests:

``scoreboard``
    Watches every cycle. Each update that leaves the pipeline is collected; when a sweep is
    complete it is checked, vectorized, against (a) the bit-exact twin advanced from the DUT's
    own previous state with the current the DUT reports it used - zero mismatches allowed - and
    (b) the float64 golden Euler step from the same state, within the error bound derived from
    the formats. The current used must be the last one the host wrote (or, for a write in the
    cycle of the fetch, the one before). The spike stream and per-sweep counts must agree with
    the updates; nothing may overflow or overrun.
``engine``
    Writes the currents, drives external ticks and records the spike stream: the
    ``icarus``/``verilator`` engines of ``cuneate simulate``.
"""

from __future__ import annotations

import json
import os
import random
import time

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge

from cuneate.golden import izhikevich as golden
from cuneate.hdl.izhikevich import PIPELINE_DEPTH, IzhikevichConfig, IzhikevichTwin


def _load():
    with open(os.environ["CUNEATE_BENCH_CONFIG"]) as f:
        return json.load(f)


def _report(data):
    with open(os.environ["CUNEATE_BENCH_REPORT"], "w") as f:
        json.dump(data, f)


def make_config(core: dict) -> IzhikevichConfig:
    core = dict(core)
    core["param_sets"] = tuple(tuple(p) if isinstance(p, list) else p
                               for p in core.get("param_sets", ("RS",)))
    return IzhikevichConfig(**core)


class TB:
    """Owns the clock, reset, host-write driver and the update/spike monitors."""

    def __init__(self, dut, cfg: IzhikevichConfig):
        self.dut, self.cfg = dut, cfg
        self.cycle = 0
        self.writes: dict[int, list[tuple[int, int]]] = {}    # neuron -> [(cycle, raw)]

    async def start(self):
        cocotb.start_soon(Clock(self.dut.clk, 10, unit="ns").start())
        d = self.dut
        d.rst.value = 1
        for s in (d.i_wr_en, d.sel_wr_en, d.i_wr_addr, d.i_wr_data, d.sel_wr_addr,
                  d.sel_wr_data):
            s.value = 0
        d.spike_ready.value = 1
        if self.cfg.tick_source == "external":
            d.tick.value = 0
        await RisingEdge(d.clk)
        await RisingEdge(d.clk)
        await FallingEdge(d.clk)
        d.rst.value = 0

    async def write_current(self, neuron: int, raw: int):
        """Drive one host write (call at a falling edge; returns at the next falling edge)."""
        d = self.dut
        d.i_wr_addr.value = neuron
        d.i_wr_data.value = int(raw)
        d.i_wr_en.value = 1
        self.writes.setdefault(neuron, []).append((self.cycle, int(raw)))
        await FallingEdge(d.clk)
        d.i_wr_en.value = 0

    def allowed_currents(self, neuron: int, fetch_cycle: int) -> set[int]:
        """Currents the fetch of ``neuron`` at ``fetch_cycle`` may legally have read."""
        hist = self.writes.get(neuron, [])
        before = [raw for c, raw in hist if c < fetch_cycle - 2]
        near = [raw for c, raw in hist if fetch_cycle - 2 <= c <= fetch_cycle + 2]
        base = before[-1] if before else 0
        return {base, *near}


@cocotb.test()
async def scoreboard(dut):
    cfgj = _load()
    cfg = make_config(cfgj["core"])
    N = cfg.n_neurons
    twin = IzhikevichTwin(cfg)
    tb = TB(dut, cfg)
    rng = random.Random(cfgj.get("seed", 1))
    n_sweeps = cfgj["sweeps"]
    lo, hi = cfgj.get("current_range", [0.0, 40.0])
    writes_per_sweep = cfgj.get("writes_per_sweep", 4)
    await tb.start()

    async def driver():
        # initial currents, written while the first sweep is already running, then random
        # rewrites during the sweeps
        for n in range(N):
            await tb.write_current(n, cfg.I.to_raw(rng.uniform(lo, hi)))
        while True:
            if writes_per_sweep > 0 and rng.random() < writes_per_sweep / N:
                await tb.write_current(rng.randrange(N), cfg.I.to_raw(rng.uniform(lo, hi)))
            else:
                await FallingEdge(dut.clk)

    cocotb.start_soon(driver())
    prev_v = np.full(N, cfg.V0.raw, dtype=np.int64)
    prev_u = np.array([cfg.u0[s].raw for s in cfg.neuron_sets], dtype=np.int64)
    sel = np.asarray(cfg.neuron_sets, dtype=np.int64)
    buf = {k: np.zeros(N, dtype=np.int64) for k in ("v", "u", "i", "spike", "cycle")}
    fill = 0
    stats = {"sweeps_checked": 0, "updates_checked": 0, "twin_mismatches": 0,
             "golden_v_max_err": 0.0, "golden_u_max_err": 0.0, "golden_v_max_ratio": 0.0,
             "golden_u_max_ratio": 0.0, "golden_bound_violations": 0,
             "spike_disagreements_near_threshold": 0, "spike_disagreements": 0,
             "spikes": 0, "stream_spikes": 0, "current_violations": 0, "count_mismatches": 0}
    stream: list[tuple[int, int]] = []
    done: list[tuple[int, int]] = []
    expected_done: list[tuple[int, int]] = []
    expected_stream: list[tuple[int, int]] = []
    t0 = time.perf_counter()
    d = dut
    while stats["sweeps_checked"] < n_sweeps:
        await FallingEdge(d.clk)
        tb.cycle += 1
        # sample the outputs registered at the last rising edge
        if int(d.spike_valid.value):
            stream.append((int(d.spike_index.value), int(d.spike_sweep.value)))
        if int(d.sweep_done.value):
            done.append((int(d.sweep_number.value), int(d.sweep_count.value)))
        if not int(d.upd_valid.value):
            continue
        idx = int(d.upd_index.value)
        if idx == 0:
            fill = 0
        if idx != fill:
            raise AssertionError(f"update order broken: expected neuron {fill}, got {idx}")
        buf["v"][idx] = d.upd_v.value.to_signed()
        buf["u"][idx] = d.upd_u.value.to_signed()
        buf["i"][idx] = d.upd_current.value.to_signed()
        buf["spike"][idx] = int(d.upd_spike.value)
        buf["cycle"][idx] = tb.cycle
        fill += 1
        if idx != N - 1:
            continue
        sweep_no = stats["sweeps_checked"]        # sweeps are numbered from 0 after reset
        # ---- whole sweep collected: vectorized checks ----
        out = twin.update(prev_v, prev_u, buf["i"], sel)
        spk = buf["spike"].astype(bool)
        mism = (out["v"] != buf["v"]) | (out["u"] != buf["u"]) | (out["spike"] != spk)
        stats["twin_mismatches"] += int(mism.sum())
        if mism.any():
            k = int(np.flatnonzero(mism)[0])
            dut._log.error(f"sweep {sweep_no} neuron {k}: DUT v={buf['v'][k]} u={buf['u'][k]} "
                           f"spike={spk[k]}, twin v={out['v'][k]} u={out['u'][k]} "
                           f"spike={out['spike'][k]}")
        # golden one-step from the DUT's own previous state
        vf, uf = cfg.V.to_float(prev_v), cfg.U.to_float(prev_u)
        If = cfg.I.to_float(buf["i"])
        a, b, c, dd = (np.array([cfg.sets[s][j] for s in sel]) for j in range(4))
        gv, gu, gspk, gv_pre = golden.step(vf, uf, If, a, b, c, dd, cfg.dt_ms, "euler")
        bv, bu = cfg.one_step_bound(vf, uf, If)
        fv, fu = cfg.V.to_float(buf["v"]), cfg.U.to_float(buf["u"])
        agree = gspk == spk
        ev = np.abs(fv - gv)[agree]
        eu = np.abs(fu - gu)[agree]
        stats["golden_v_max_err"] = max(stats["golden_v_max_err"], float(ev.max(initial=0)))
        stats["golden_u_max_err"] = max(stats["golden_u_max_err"], float(eu.max(initial=0)))
        stats["golden_v_max_ratio"] = max(stats["golden_v_max_ratio"],
                                          float((ev / bv[agree]).max(initial=0)))
        stats["golden_u_max_ratio"] = max(stats["golden_u_max_ratio"],
                                          float((eu / bu[agree]).max(initial=0)))
        stats["golden_bound_violations"] += int((ev > bv[agree]).sum() + (eu > bu[agree]).sum())
        near = np.abs(gv_pre - cfg.v_th) <= bv
        stats["spike_disagreements_near_threshold"] += int((~agree & near).sum())
        stats["spike_disagreements"] += int((~agree & ~near).sum())
        # currents used must be the ones the host wrote
        for n in range(N):
            fetch = int(buf["cycle"][n]) - PIPELINE_DEPTH
            if int(buf["i"][n]) not in tb.allowed_currents(n, fetch):
                stats["current_violations"] += 1
        expected_done.append((sweep_no % (1 << cfg.sweep_number_width), int(spk.sum())))
        expected_stream += [(int(n), sweep_no) for n in np.flatnonzero(spk)]
        stats["spikes"] += int(spk.sum())
        stats["sweeps_checked"] += 1
        stats["updates_checked"] += N
        prev_v, prev_u = buf["v"].copy(), buf["u"].copy()
    # drain the spike stream
    for _ in range(cfg.spike_fifo_depth + 4):
        await FallingEdge(d.clk)
        if int(d.spike_valid.value):
            stream.append((int(d.spike_index.value), int(d.spike_sweep.value)))
        if int(d.sweep_done.value):
            done.append((int(d.sweep_number.value), int(d.sweep_count.value)))
    elapsed = time.perf_counter() - t0
    stats["count_mismatches"] = sum(a != b for a, b in zip(done, expected_done)) + \
        max(0, len(expected_done) - len(done))
    first = expected_stream[0][1] if expected_stream else 0
    stream_checked = [s for s in stream if s[1] >= first][:len(expected_stream)]
    stats["stream_spikes"] = len(stream_checked)
    stats["stream_matches"] = stream_checked == expected_stream
    stats["overrun"] = int(d.overrun.value)
    stats["spike_overflow"] = int(d.spike_overflow.value)
    stats["cycles"] = tb.cycle
    stats["wall_s"] = elapsed
    stats["cycles_per_s"] = tb.cycle / elapsed if elapsed else None
    stats["bound_v_at_rest"] = float(cfg.one_step_bound(-65.0, -13.0, 0.0)[0])
    _report(stats)
    assert stats["twin_mismatches"] == 0, "RTL differs from the twin"
    assert stats["golden_bound_violations"] == 0, "fixed point left the golden error bound"
    assert stats["spike_disagreements"] == 0, "spike decision differs away from threshold"
    assert stats["current_violations"] == 0, "an update used a current the host never wrote"
    assert stats["count_mismatches"] == 0, "sweep_count disagrees with the updates"
    assert stats["stream_matches"], "spike stream differs from the spiking updates"
    assert stats["overrun"] == 0 and stats["spike_overflow"] == 0


@cocotb.test()
async def engine(dut):
    """Run the core like a host would: set currents, tick, read the spike stream."""
    cfgj = _load()
    cfg = make_config(cfgj["core"])
    N = cfg.n_neurons
    tb = TB(dut, cfg)
    await tb.start()
    currents = cfgj["currents"]
    for n in range(N):
        await tb.write_current(n, cfg.I.to_raw(currents[n] if n < len(currents) else 0.0))
    n_sweeps = cfgj["sweeps"]
    period = cfgj.get("tick_period", N)
    d = dut
    spikes: list[list[int]] = [[] for _ in range(N)]
    width = cfg.sweep_number_width
    base, last_raw = 0, 0
    t0 = time.perf_counter()
    cycles = 0
    total = n_sweeps * period + PIPELINE_DEPTH + cfg.spike_fifo_depth + 4
    for c in range(total):
        d.tick.value = int(c % period == 0 and c // period < n_sweeps)
        await FallingEdge(d.clk)
        cycles += 1
        if int(d.spike_valid.value):
            raw = int(d.spike_sweep.value)
            if raw < last_raw:
                base += 1 << width          # sweep number wrapped
            last_raw = raw
            spikes[int(d.spike_index.value)].append(base + raw)
    elapsed = time.perf_counter() - t0
    _report({"spike_sweeps": spikes, "cycles": cycles, "wall_s": elapsed,
             "overrun": int(d.overrun.value), "spike_overflow": int(d.spike_overflow.value)})
    assert int(d.overrun.value) == 0 and int(d.spike_overflow.value) == 0
