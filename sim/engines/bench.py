"""The bench side of every cocotb bench (imported inside the simulator): the configuration and
report files the runner (:mod:`cuneate.sim.engines.cocotb`) passes, and :class:`CoreBench`, the
clock, reset, host writes and per-cycle monitor of a time-multiplexed core (the Izhikevich and
LIF cores share their ports, see :mod:`cuneate.hdl.lib.bookkeeping`).
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

from .waves import BENCH_CLOCK_NS

__all__ = ["bench_config", "bench_case", "bench_report", "bench_verdict", "bench_progress",
           "start_in_reset", "spikes_then_tick", "CoreBench"]


def bench_config() -> dict:
    """The configuration the caller gave :func:`~cuneate.sim.engines.cocotb.run_cocotb`."""
    with open(os.environ["CUNEATE_BENCH_CONFIG"]) as f:
        return json.load(f)


def bench_case(key: str, make) -> tuple[dict, object, random.Random]:
    """The bench's configuration (:func:`bench_config`), its block's configuration
    ``make(spec[key])`` and the random source of its stimulus, seeded with ``spec["seed"]``
    (1 when not given)."""
    spec = bench_config()
    return spec, make(spec[key]), random.Random(spec.get("seed", 1))


def bench_report(data: dict) -> None:
    """Hand ``data`` back to the caller as the run's report."""
    with open(os.environ["CUNEATE_BENCH_REPORT"], "w") as f:
        json.dump(data, f, default=float)


def bench_verdict(report: dict, failures: list) -> None:
    """Hand back ``report`` (:func:`bench_report`), then fail the bench naming every failure."""
    bench_report(report)
    assert not failures, "; ".join(failures)


#: the shortest interval between two progress reports of a bench (seconds): a bench may call
#: :func:`bench_progress` every tick, the file is written about twice a second
PROGRESS_INTERVAL_S = 0.4
_last_progress = [0.0]


def bench_progress(config: dict, done: int, force: bool = False) -> None:
    """Tell the caller how far the bench got (the ``progress`` callback of the runner), at
    most every :data:`PROGRESS_INTERVAL_S` unless ``force``."""
    path = config.get("progress_file")
    now = time.monotonic()
    if path and (force or now - _last_progress[0] >= PROGRESS_INTERVAL_S):
        _last_progress[0] = now
        with open(path, "w") as f:
            json.dump({"done": int(done)}, f)


async def start_in_reset(dut, idle=(), ready=()) -> None:
    """Start the bench clock, hold reset for two rising edges with the inputs ``idle`` at 0 and
    ``ready`` at 1, and release it after the next falling edge."""
    cocotb.start_soon(Clock(dut.clk, BENCH_CLOCK_NS, unit="ns").start())
    dut.rst.value = 1
    for s in idle:
        s.value = 0
    for s in ready:
        s.value = 1
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0


async def spikes_then_tick(dut, sources, step, has_inputs: bool) -> None:
    """Present each input spike source on ``in_valid``/``in_source`` for one ``step``, then one
    ``tick`` pulse (the cocotb form of :func:`cuneate.sim.engines.amaranth.spikes_then_tick`)."""
    for s in sources:
        dut.in_valid.value = 1
        dut.in_source.value = int(s)
        await step()
    if has_inputs:
        dut.in_valid.value = 0
    dut.tick.value = 1
    await step()
    dut.tick.value = 0


class CoreBench:
    """Clock, reset, host current writes and the per-cycle monitor of a core.

    ``fields``: name -> ``f(dut)`` reading one value of the update on ``upd_*`` (besides the
    current, spike, clamp bits and the cycle, which every core reports). After each falling
    edge :meth:`sample` records the spike stream, every ``sweep_done`` (number, count and
    clamp counters) and the update on ``upd_*`` into a per-neuron buffer (checking the update
    order), and says when a whole sweep is in :attr:`buf`; :meth:`expect_sweep` records what
    the core's counters, stream and sticky flags must then show, :meth:`mismatches` compares.
    """

    def __init__(self, dut, cfg, clamp_kinds, fields: dict):
        self.dut, self.cfg, self.kinds, self.fields = dut, cfg, tuple(clamp_kinds), fields
        N = cfg.n_neurons
        self.cycle = 0
        self.writes: dict[int, list[tuple[int, int]]] = {}    # neuron -> [(cycle, raw)]
        self.buf = {k: np.zeros(N, dtype=np.int64)
                    for k in (*fields, "i", "spike", "clamp", "cycle")}
        self.fill = 0
        self.stream: list[tuple[int, int]] = []
        self.done: list[tuple] = []
        self.expected_done: list[tuple] = []
        self.expected_stream: list[tuple[int, int]] = []
        self.sticky_seen, self.sticky_due, self.sticky_mismatches = 0, False, 0
        self.counters = [getattr(dut, f"sweep_clamps_{k}") for k in clamp_kinds]

    async def start(self, idle=()):
        """Start the clock and reset with every host input idle (``idle``: more of them)."""
        cocotb.start_soon(Clock(self.dut.clk, BENCH_CLOCK_NS, unit="ns").start())
        d = self.dut
        d.rst.value = 1
        for s in (d.i_wr_en, d.sel_wr_en, d.i_wr_addr, d.i_wr_data, d.sel_wr_addr,
                  d.sel_wr_data, d.clamp_clear, *idle):
            s.value = 0
        d.spike_ready.value = 1
        if self.cfg.tick_source == "external":
            d.tick.value = 0
        await RisingEdge(d.clk)
        await RisingEdge(d.clk)
        await FallingEdge(d.clk)
        d.rst.value = 0

    def drive_write(self, neuron: int, raw: int) -> None:
        """Put one host write on the port for the coming cycle, and remember it."""
        d = self.dut
        d.i_wr_addr.value = neuron
        d.i_wr_data.value = int(raw)
        d.i_wr_en.value = 1
        self.writes.setdefault(neuron, []).append((self.cycle, int(raw)))

    async def write_current(self, neuron: int, raw: int, count: bool = False):
        """One host write (call at a falling edge; returns at the next); ``count``: this
        coroutine also counts the cycle (when no monitor loop does)."""
        self.drive_write(neuron, raw)
        await FallingEdge(self.dut.clk)
        if count:
            self.cycle += 1
        self.dut.i_wr_en.value = 0

    def allowed_currents(self, neuron: int, fetch_cycle: int) -> set[int]:
        """Currents the fetch of ``neuron`` at ``fetch_cycle`` may legally have read."""
        hist = self.writes.get(neuron, [])
        before = [raw for c, raw in hist if c < fetch_cycle - 2]
        near = [raw for c, raw in hist if fetch_cycle - 2 <= c <= fetch_cycle + 2]
        return {before[-1] if before else 0, *near}

    def sample_outputs(self) -> None:
        """The spike stream and ``sweep_done`` registered at the last rising edge."""
        d = self.dut
        if int(d.spike_valid.value):
            self.stream.append((int(d.spike_index.value), int(d.spike_sweep.value)))
        if int(d.sweep_done.value):
            self.done.append((int(d.sweep_number.value), int(d.sweep_count.value),
                              *(int(c.value) for c in self.counters)))

    def sample(self) -> bool:
        """Everything of this cycle (call after a falling edge, the cycle counted); True when
        the last neuron's update completed a sweep in :attr:`buf`."""
        d = self.dut
        if self.sticky_due:
            # one cycle after a sweep's last update the sticky flags hold every clamp so far
            self.sticky_due = False
            self.sticky_mismatches += int(int(d.clamp_flags.value) != self.sticky_seen)
        self.sample_outputs()
        if not int(d.upd_valid.value):
            return False
        idx = int(d.upd_index.value)
        if idx == 0:
            self.fill = 0
        if idx != self.fill:
            raise AssertionError(f"update order broken: expected neuron {self.fill}, got {idx}")
        b = self.buf
        for k, read in self.fields.items():
            b[k][idx] = read(d)
        b["i"][idx] = d.upd_current.value.to_signed()
        b["spike"][idx] = int(d.upd_spike.value)
        b["clamp"][idx] = int(d.upd_clamp.value)
        b["cycle"][idx] = self.cycle
        self.fill += 1
        return idx == self.cfg.n_neurons - 1

    def current_violations(self, pipeline_depth: int) -> int:
        """Updates of the sweep in :attr:`buf` that used a current the host never wrote."""
        b = self.buf
        return sum(int(b["i"][n]) not in self.allowed_currents(n, int(b["cycle"][n])
                                                               - pipeline_depth)
                   for n in range(self.cfg.n_neurons))

    def expect_sweep(self, sweep: int, sticky: int) -> None:
        """What the core must report for the sweep in :attr:`buf`: its counters, its spikes on
        the stream and, a cycle later, the sticky flags ``sticky``."""
        spk = self.buf["spike"].astype(bool)
        clamp = self.buf["clamp"]
        sums = [int(((clamp >> i) & 1).sum()) for i in range(len(self.kinds))]
        self.expected_done.append((sweep % (1 << self.cfg.sweep_number_width), int(spk.sum()),
                                   *sums))
        self.expected_stream += [(int(n), sweep) for n in np.flatnonzero(spk)]
        self.sticky_seen |= sticky
        self.sticky_due = True

    async def drain(self) -> None:
        """Let the spike FIFO and the last ``sweep_done`` come out."""
        for _ in range(self.cfg.spike_fifo_depth + 4):
            await FallingEdge(self.dut.clk)
            self.sample_outputs()

    def mismatches(self) -> dict:
        """Counter, clamp-counter and sticky mismatches against what was expected."""
        done, exp = self.done, self.expected_done
        return {"count_mismatches": sum(a[:2] != b[:2] for a, b in zip(done, exp))
                + max(0, len(exp) - len(done)),
                "clamp_counter_mismatches": sum(a[2:] != b[2:] for a, b in zip(done, exp)),
                "sticky_mismatches": self.sticky_mismatches}
