"""cocotb bench for the generated :class:`~cuneate.hdl.plasticity.LearningLayer` Verilog.

Configured by the JSON file named in ``CUNEATE_BENCH_CONFIG``; figures go to
``CUNEATE_BENCH_REPORT``. Test ``scoreboard``: input spike events at random between ticks
(sometimes twice from one source), a tick every ``period`` cycles, a window's end every
``window`` ticks (with the step every other time), a host weight write and read-back once.
Every cycle is watched; every tick's synapse and CN updates and every window's steps are
checked (:class:`~cuneate.sim.plasticity.scoreboard.LearningChecker`: the twin exact, golden
bounded), and at the end the spike stream, the counters (ticks, windows, merged events,
overruns, hazards) and each clamp kind's counter against the twin's.

Test ``engine``: runs a given schedule (events per tick, a window's end after given ticks)
and returns the spike stream and every weight read back through the host port.
"""

from __future__ import annotations

import time

import cocotb
import numpy as np
from cocotb.triggers import FallingEdge

from cuneate.hdl.plasticity import CLAMP_KINDS, OPS, PlasticityConfig
from cuneate.sim.engines.bench import (bench_case, bench_config, bench_progress, bench_report,
                                       bench_verdict, spikes_then_tick, start_in_reset)
from cuneate.sim.plasticity.scoreboard import CN_FIELDS, SYN_FIELDS, LearningChecker

SIGNED_CN = {"v", "u", "e", "i", "inh"}
SIGNED_SYN = {"cd", "cr", "l"}


async def start_bench(dut):
    await start_in_reset(dut, (dut.tick, dut.in_valid, dut.in_source, dut.learn,
                               dut.learn_apply, dut.w_wr_valid, dut.w_wr_addr, dut.w_wr_data,
                               dut.w_rd_valid, dut.w_rd_addr, dut.clamp_clear))


class Monitor:
    """Every cycle's outputs: CN updates, synapse updates, spikes, host read responses."""

    def __init__(self, dut, cfg):
        self.dut, self.cfg = dut, cfg
        M, K = cfg.n_targets, cfg.n_synapses
        self.cn = {f: np.zeros(M, np.int64) for f in CN_FIELDS}
        self.syn = {f: np.zeros((M, K), np.int64) for f in SYN_FIELDS}
        self.syn_seen = {op: 0 for op in OPS.values()}
        self.cn_seen = 0
        self.stream: list = []
        self.upd_spikes: list = []
        self.reads: list = []
        self.cycles = 0

    def sample(self):
        d, K = self.dut, self.cfg.n_synapses
        self.cycles += 1
        if int(d.spike_valid.value):
            self.stream.append((int(d.spike_tick.value), int(d.spike_target.value)))
        if int(d.w_rd_resp_valid.value):
            self.reads.append(int(d.w_rd_resp_data.value))
        if int(d.upd_valid.value):
            j = int(d.upd_target.value)
            for f in CN_FIELDS:
                s = getattr(d, f"upd_{f}").value
                self.cn[f][j] = s.to_signed() if f in SIGNED_CN else int(s)
            if self.cn["spike"][j]:
                self.upd_spikes.append((int(d.upd_tick.value), j))
            self.cn_seen += 1
        if int(d.syn_upd_valid.value):
            op = int(d.syn_upd_op.value)
            j, m = divmod(int(d.syn_upd_addr.value), K)
            for f in SYN_FIELDS:
                s = getattr(d, f"syn_upd_{f}").value
                self.syn[f][j, m] = s.to_signed() if f in SIGNED_SYN else int(s)
            self.syn_seen[op] += 1

    def take(self):
        """The rows gathered since the last take (copies) and their counts."""
        out = ({f: a.copy() for f, a in self.syn.items()},
               {f: a.copy() for f, a in self.cn.items()}, dict(self.syn_seen), self.cn_seen)
        self.syn_seen = {op: 0 for op in OPS.values()}
        self.cn_seen = 0
        return out


async def step(dut, mon, n=1):
    for _ in range(n):
        await FallingEdge(dut.clk)
        mon.sample()


async def settle(dut, mon):
    """Until the layer is idle and the last synapse write-back has left."""
    await step(dut, mon, 2)
    while int(dut.busy.value):
        await step(dut, mon)
    await step(dut, mon, 6)


async def window_end(dut, mon, apply: bool):
    dut.learn.value = 1
    dut.learn_apply.value = int(apply)
    await step(dut, mon)
    dut.learn.value = 0
    await settle(dut, mon)


@cocotb.test()
async def scoreboard(dut):
    spec, cfg, rng = bench_case("layer", PlasticityConfig.from_kwargs)
    M, K, S = cfg.n_targets, cfg.n_synapses, cfg.n_sources
    n_ticks, window = spec["ticks"], spec.get("window", 20)
    p_event = spec.get("event_p", 0.3)
    checker = LearningChecker(cfg)
    mon = Monitor(dut, cfg)
    await start_bench(dut)
    merged, problems, t0 = 0, [], time.perf_counter()
    for k in range(n_ticks):
        events = []
        for _ in range(rng.randrange(0, 2 * S)):
            if rng.random() < p_event:
                s = rng.randrange(S)
                merged += s in events
                events.append(s)
        await spikes_then_tick(dut, events, lambda: step(dut, mon), True)
        await settle(dut, mon)
        syn, cn, seen, cn_seen = mon.take()
        if seen[OPS["integrate"]] != M * K or cn_seen != M:
            problems.append(f"tick {k}: {seen[OPS['integrate']]} synapse and {cn_seen} CN "
                            f"updates, expected {M * K} and {M}")
        checker.tick(events, syn, cn)
        if (k + 1) % window == 0:
            apply = ((k + 1) // window) % 2 == 1
            await window_end(dut, mon, apply)
            syn, _, seen, _ = mon.take()
            want = M * K * (2 if apply else 1)
            if seen[OPS["learn"]] + seen[OPS["read"]] != want:
                problems.append(f"window after tick {k}: {seen} synapse operations")
            checker.window(apply, syn)
        if k == n_ticks // 2:                        # a host write, read back
            addr, raw = rng.randrange(M * K), rng.randrange(cfg.w_max_raw + 1)
            dut.w_wr_valid.value, dut.w_wr_addr.value, dut.w_wr_data.value = 1, addr, raw
            await step(dut, mon)
            dut.w_wr_valid.value = 0
            checker.twin.write_weight(addr, raw)
            await settle(dut, mon)
            dut.w_rd_valid.value, dut.w_rd_addr.value = 1, addr
            await step(dut, mon)
            dut.w_rd_valid.value = 0
            await settle(dut, mon)
            mon.take()
            if mon.reads[-1:] != [raw]:
                problems.append(f"host read of synapse {addr}: {mon.reads[-1:]} != {raw}")
        bench_progress(spec, k + 1)
    wall = time.perf_counter() - t0
    tw = checker.twin
    counters = {"tick_count": n_ticks, "learn_count": n_ticks // window,
                "merged_count": merged, "overrun_count": 0, "learn_overrun_count": 0,
                "hazard_count": 0}
    for name, want in counters.items():
        got = int(getattr(dut, name).value)
        if got != want:
            problems.append(f"{name} {got} != {want}")
    for k in CLAMP_KINDS:
        got = int(getattr(dut, f"clamp_count_{k}").value)
        if got != tw.clamp_counts[k]:
            problems.append(f"clamp_count_{k} {got} != the twin's {tw.clamp_counts[k]}")
    if sorted(mon.stream) != sorted(mon.upd_spikes):
        problems.append(f"spike stream {len(mon.stream)} events differs from the updates' "
                        f"{len(mon.upd_spikes)} spikes")
    report = checker.stats | {"izhikevich": checker.iz.stats.to_dict(), "cycles": mon.cycles,
                              "cycles_per_s": mon.cycles / wall, "merged": merged,
                              "clamp_counts": dict(tw.clamp_counts),
                              "weights_changed": int(np.count_nonzero(
                                  tw.w != cfg.weights_raw))}
    bench_verdict(report, checker.failures() + problems)


@cocotb.test()
async def engine(dut):
    spec = bench_config()
    cfg = PlasticityConfig.from_kwargs(spec["layer"])
    n_ticks = spec["ticks"]
    by_tick = {int(k): v for k, v in spec["events"].items()}
    windows = {int(k): bool(a) for k, a in spec["windows"].items()}
    mon = Monitor(dut, cfg)
    await start_bench(dut)
    t0 = time.perf_counter()
    for k in range(n_ticks):
        await spikes_then_tick(dut, by_tick.get(k, []), lambda: step(dut, mon), True)
        await settle(dut, mon)
        if k in windows:
            await window_end(dut, mon, windows[k])
        mon.take()
        bench_progress(spec, k + 1)
    weights = []
    for a in range(cfg.n_targets * cfg.n_synapses):
        dut.w_rd_valid.value, dut.w_rd_addr.value = 1, a       # taken: the layer is idle
        await step(dut, mon)
        dut.w_rd_valid.value = 0
        await step(dut, mon, 4)
        weights.append(mon.reads[-1])
    bench_report({"spikes": mon.stream, "ticks": int(dut.tick_count.value),
                  "windows": int(dut.learn_count.value), "weights": weights,
                  "merged": int(dut.merged_count.value),
                  "hazards": int(dut.hazard_count.value),
                  "clamp_counts": {k: int(getattr(dut, f"clamp_count_{k}").value)
                                   for k in CLAMP_KINDS},
                  "wall_s": time.perf_counter() - t0})
