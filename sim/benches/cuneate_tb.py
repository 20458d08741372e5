"""cocotb bench for the generated :class:`cuneate.hdl.coincidence.CoincidenceDetector` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG``; figures go to
``CUNEATE_BENCH_REPORT``. Test ``scoreboard``: external ticks every ``period`` cycles; between
ticks input spike events arrive at random (one per cycle, sometimes twice from one source).
Every cycle is watched; every target update is checked when its tick is complete:

* the input sum the DUT used (``upd_a``) equals the twin's from the events driven before that
  tick and the delays and weights;
* traces, PSP current, ``v``, ``u``, spike and clamp flags equal the bit-exact twin advanced from
  the DUT's own previous state (zero mismatches);
* the float64 golden steps from the same state stay within their derived one-step bounds:
  the traces (:func:`~cuneate.hdl.lib.synapses.trace_golden_check`) and the Izhikevich update
  (:class:`~cuneate.sim.scoreboard.SweepChecker`, flagged clamps expected, unflagged fail);
* the spike stream equals the updates' spikes, ``merged_count`` the duplicate events and
  ``tick_count`` the ticks.

``engine``: runs a given input schedule (events per tick) and records the spike stream; the
``icarus``/``verilator`` engines of ``cuneate simulate coincidence``.
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

from cuneate.hdl.coincidence import CoincidenceConfig, CoincidenceTwin
from cuneate.hdl.lib.synapses import trace_golden_check
from cuneate.sim.scoreboard import SweepChecker


def _load():
    with open(os.environ["CUNEATE_BENCH_CONFIG"]) as f:
        return json.load(f)


def _report(data):
    with open(os.environ["CUNEATE_BENCH_REPORT"], "w") as f:
        json.dump(data, f, default=float)


class CoincidenceChecker:
    """Checks the updates of whole ticks against the twin (exact) and golden (bounded)."""

    def __init__(self, cfg: CoincidenceConfig):
        self.cfg = cfg
        M = cfg.n_targets
        self.ref = CoincidenceTwin(cfg)         # history and inputs; state from the DUT
        self.iz = SweepChecker(cfg.iz)
        self.iz.prev_v, self.iz.prev_u = self.iz.prev_v[:M], self.iz.prev_u[:M]
        self.sel = np.asarray(cfg.target_sets_, dtype=np.int64)
        self.prev_xd = np.zeros(M, dtype=np.int64)
        self.prev_xr = np.zeros(M, dtype=np.int64)
        self.stats = {"ticks_checked": 0, "updates_checked": 0, "input_mismatches": 0,
                      "trace_mismatches": 0, "current_mismatches": 0,
                      "trace_golden_violations": 0, "trace_golden_max_ratio": 0.0,
                      "first_mismatch": None}

    def check(self, events, rows) -> None:
        """``events``: sources driven before this tick; ``rows``: dict of arrays by target."""
        st = self.stats
        self.ref.spike_in(events)
        a = self.ref.stamp()
        out = self.ref.update(self.iz.prev_v, self.iz.prev_u, self.prev_xd, self.prev_xr, a,
                              self.sel)
        bad_a = rows["a"] != a
        bad_t = (rows["xd"] != out["xd"]) | (rows["xr"] != out["xr"])
        bad_i = rows["i"] != out["i"]
        st["input_mismatches"] += int(bad_a.sum())
        st["trace_mismatches"] += int(bad_t.sum())
        st["current_mismatches"] += int(bad_i.sum())
        if (bad_a | bad_t | bad_i).any() and st["first_mismatch"] is None:
            k = int(np.flatnonzero(bad_a | bad_t | bad_i)[0])
            st["first_mismatch"] = (f"tick {st['ticks_checked']} target {k}: DUT a={rows['a'][k]}"
                                    f" xd={rows['xd'][k]} xr={rows['xr'][k]} i={rows['i'][k]};"
                                    f" twin a={a[k]} xd={out['xd'][k]} xr={out['xr'][k]} "
                                    f"i={out['i'][k]}")
        errs, bounds = trace_golden_check(self.cfg.tview, out["ys"], [rows["xd"], rows["xr"]])
        st["trace_golden_violations"] += int((errs > bounds).sum())
        st["trace_golden_max_ratio"] = max(st["trace_golden_max_ratio"],
                                           float((errs / bounds).max()))
        self.iz.check(rows["v"], rows["u"], rows["i"], rows["spike"], rows["clamp"], self.sel)
        self.prev_xd, self.prev_xr = rows["xd"].copy(), rows["xr"].copy()
        self.ref.ticks += 1
        st["ticks_checked"] += 1
        st["updates_checked"] += self.cfg.n_targets

    def failures(self) -> list[str]:
        st, out = self.stats, list(self.iz.failures())
        for k in ("input_mismatches", "trace_mismatches", "current_mismatches",
                  "trace_golden_violations"):
            if st[k]:
                out.append(f"{st[k]} {k.replace('_', ' ')} ({st['first_mismatch']})")
        return out


async def _start(dut):
    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.rst.value = 1
    for s in (dut.tick, dut.in_valid, dut.in_source, dut.clamp_clear):
        s.value = 0
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0


_FIELDS = ("v", "u", "xd", "xr", "a", "i", "spike", "clamp")


def _row(dut) -> dict:
    sig = {"v": dut.upd_v, "u": dut.upd_u, "xd": dut.upd_xd, "xr": dut.upd_xr, "a": dut.upd_a,
           "i": dut.upd_i, "spike": dut.upd_spike, "clamp": dut.upd_clamp}
    signed = {"v", "u", "xd", "xr", "i"}
    return {k: (s.value.to_signed() if k in signed else int(s.value)) for k, s in sig.items()}


@cocotb.test()
async def scoreboard(dut):
    spec = _load()
    cfg = CoincidenceConfig(**spec["detector"])
    M, S = cfg.n_targets, cfg.n_sources
    rng = random.Random(spec.get("seed", 1))
    n_ticks = spec["ticks"]
    period = spec.get("period", cfg.cycles_needed + 2 * S + 4)
    p_event = spec.get("event_p", 0.3)
    checker = CoincidenceChecker(cfg)
    await _start(dut)
    pending, events_of = [], {}
    rows: dict = {}
    stream, upd_spikes = [], []
    tick_no, phase, cycles = 0, 1, 0
    merged = 0
    t0 = time.perf_counter()
    while checker.stats["ticks_checked"] < n_ticks:
        tick = phase == 0 and tick_no < n_ticks
        dut.tick.value = int(tick)
        dut.in_valid.value = 0
        if tick:
            events_of[tick_no] = pending
            pending = []
            tick_no += 1
        elif tick_no < n_ticks and rng.random() < p_event:
            s = rng.randrange(S)
            dut.in_valid.value = 1
            dut.in_source.value = s
            merged += s in pending
            pending.append(s)
        await FallingEdge(dut.clk)
        cycles += 1
        phase = (phase + 1) % period
        if int(dut.spike_valid.value):
            stream.append((int(dut.spike_tick.value), int(dut.spike_target.value)))
        if not int(dut.upd_valid.value):
            continue
        k, t = int(dut.upd_tick.value), int(dut.upd_target.value)
        r = _row(dut)
        rows.setdefault(k, {f: np.zeros(M, dtype=np.int64) for f in _FIELDS})
        for f in _FIELDS:
            rows[k][f][t] = r[f]
        if r["spike"]:
            upd_spikes.append((k, t))
        if t == M - 1:
            checker.check(events_of[k], rows.pop(k))
    wall = time.perf_counter() - t0
    extra = []
    if sorted(stream) != sorted(upd_spikes):
        extra.append(f"spike stream {len(stream)} events differs from the updates' "
                     f"{len(upd_spikes)} spikes")
    if int(dut.merged_count.value) != merged:
        extra.append(f"merged_count {int(dut.merged_count.value)} != {merged} duplicate events")
    if int(dut.tick_count.value) != n_ticks:
        extra.append(f"tick_count {int(dut.tick_count.value)} != {n_ticks}")
    if int(dut.overrun_count.value):
        extra.append(f"{int(dut.overrun_count.value)} ticks overran (period too short)")
    report = checker.stats | {"izhikevich": checker.iz.stats.to_dict(), "cycles": cycles,
                              "cycles_per_s": cycles / wall, "spikes": len(stream),
                              "merged": merged, "events": sum(map(len, events_of.values()))}
    _report(report)
    fails = checker.failures() + extra
    assert not fails, "; ".join(fails)


@cocotb.test()
async def engine(dut):
    spec = _load()
    cfg = CoincidenceConfig(**spec["detector"])
    n_ticks = spec["ticks"]
    by_tick = {int(k): v for k, v in spec["events"].items()}
    await _start(dut)
    stream, clamp_words = [], []
    t0 = time.perf_counter()
    for k in range(n_ticks):
        for s in by_tick.get(k, []):
            dut.in_valid.value = 1
            dut.in_source.value = int(s)
            await FallingEdge(dut.clk)
        dut.in_valid.value = 0
        dut.tick.value = 1
        await FallingEdge(dut.clk)
        dut.tick.value = 0
        while True:
            await FallingEdge(dut.clk)
            if int(dut.spike_valid.value):
                stream.append((int(dut.spike_tick.value), int(dut.spike_target.value)))
            if int(dut.upd_valid.value) and int(dut.upd_clamp.value):
                clamp_words.append(int(dut.upd_clamp.value))
            if not int(dut.busy.value) and not int(dut.upd_valid.value):
                break
    _report({"spikes": stream, "ticks": int(dut.tick_count.value),
             "merged": int(dut.merged_count.value), "wall_s": time.perf_counter() - t0,
             "clamp_flags": int(dut.clamp_flags.value), "clamp_words": clamp_words})
