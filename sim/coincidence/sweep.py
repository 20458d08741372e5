"""The coincidence block in the accuracy sweep: its word widths swept against golden.

The coincidence-detector counterpart of :mod:`cuneate.sim.lif.sweep` (same
:class:`~cuneate.sim.sweep.SweepSpec`, :func:`~cuneate.sim.sweep.run_sweep` and accuracy
columns). A :class:`CoincidenceSweepPoint` is one way to simulate the afferent battery:

* ``fixed``: the bit-exact twin of the detector (:class:`cuneate.hdl.coincidence.CoincidenceTwin`,
  run through :func:`cuneate.sim.coincidence.engines.run_coincidence`) configured from the point's
  knobs - update rate, weight width, trace fraction bits, the multiplier operand width (the
  trace decays and the targets' Izhikevich arithmetic) and rounding; a configuration
  :class:`~cuneate.hdl.coincidence.config.CoincidenceConfig` refuses is a row with status
  ``refused`` and its one-line reason;
* ``float64`` / ``float32``: the golden model (:mod:`cuneate.golden.coincidence`: the PSP drive
  summed in float64, the targets' forward Euler in that arithmetic) at the point's rate.

The battery ``cuneate-afferents`` (:func:`afferent_battery`): 6 afferents, 10 RS cuneate
targets. Seeded "contact events" (20 per second) make each afferent fire (probability 0.8) at
its own latency (0..6 ms) plus a jitter; each afferent also fires at random (4 Hz). Five
targets have delays that compensate the latencies (their PSPs superimpose), five have random
delays (0..8 ms); weights ``J w`` are seeded in 4..8 mV/ms. Spike times and delays lie on a
0.25 ms grid, so every update rate that is a multiple of 4 kHz holds them exactly.

The reference (:func:`cuneate_reference_trains`) is the float64 golden model with RK4 at
``spec.reference_hz``; as for the Izhikevich sweep, against it a point mostly measures forward
Euler's error at its dt, so the arithmetic's own error is the comparison with float64 forward
Euler at the same dt, reported in the ``vs_float64_*`` columns.
"""

from __future__ import annotations

import sys
import time
from dataclasses import asdict, dataclass, field
from typing import ClassVar
from functools import lru_cache

import numpy as np

from ...golden import coincidence as gcun
from ...golden import izhikevich as giz
from ...hdl.coincidence.config import CYCLES_PER_TARGET_EXTRA, CoincidenceConfig
from ...hdl.lib.fixed import FixedPointError
from ..sweep import (BLOCK_SAME_DT_KEYS, Point, SweepSpec, ok_row, refused, register_battery,
                     same_dt_columns)
from ..sweep import n_steps as n_steps_of
from .engines import run_coincidence

__all__ = ["reference_trains", "COLUMNS", "default_duration_ms", "points_from_args",
           "CUNEATE_BATTERIES", "AfferentBattery", "afferent_battery", "CoincidenceSweepPoint",
           "coincidence_grid", "cuneate_reference_trains", "golden_cuneate_trains",
           "coincidence_config", "coincidence_point_trains", "CUNEATE_COLUMNS",
           "battery_size", "BLOCK"]

#: The block whose engine speeds estimate this module's sweeps.
BLOCK = "coincidence"

CUNEATE_BATTERIES = {
    "cuneate-afferents": "coincidence detector: 6 afferents (events with latencies, background) "
                         "x 10 RS targets (5 tuned delays, 5 random)",
}

#: the columns of a coincidence sweep's CSV, in order
CUNEATE_COLUMNS = ("label", "engine", "update_hz", "weight_bits", "trace_frac_bits",
                   "operand_width", "rounding", "status", "counts_equal", "count_error",
                   "fraction_within_tick", "mean_abs_error_ms", "mean_vp",
                   "vs_float64_fraction_within_tick", "vs_float64_counts_equal",
                   "vs_float64_count_error", "vs_float64_mean_vp", "neurons_per_core",
                   "multipliers", "state_bits", "acc_bits", "trace_format", "weight_format",
                   "clamped_updates", "host_s_per_bio_s", "reason")

GRID_MS = 0.25
#: afferents and targets of the battery
BATTERY_SOURCES, BATTERY_TARGETS = 6, 10


@dataclass(frozen=True)
class AfferentBattery:
    """Afferent spike times (ms, per source, on ``GRID_MS``), the targets' delays (ms) and
    weights ``J w`` (mV/ms), both ``(n_targets, n_sources)``."""

    name: str
    spike_times_ms: tuple
    delays_ms: np.ndarray = field(compare=False, repr=False)
    weights: np.ndarray = field(compare=False, repr=False)

    @property
    def n_sources(self) -> int:
        return len(self.spike_times_ms)

    @property
    def n(self) -> int:
        return int(self.delays_ms.shape[0])

    def ticks(self, dt_ms: float) -> tuple[list[np.ndarray], np.ndarray]:
        """Input spike ticks per source and delays in ticks at ``dt_ms``; refuses a dt that
        does not hold the grid."""
        per_grid = GRID_MS / dt_ms
        if abs(per_grid - round(per_grid)) > 1e-9:
            raise ValueError(f"dt {dt_ms:g} ms does not divide the battery's {GRID_MS} ms grid "
                             f"(use an update rate that is a multiple of 4 kHz)")
        return ([np.rint(np.asarray(s) / dt_ms).astype(np.int64) for s in self.spike_times_ms],
                np.rint(self.delays_ms / dt_ms).astype(np.int64))


def battery_size(name: str) -> dict:
    """The size of battery ``name`` (without drawing its spike trains): ``trains`` (targets),
    ``inputs`` (sources) and ``bytes_per_step`` (the per-tick arrays of a run)."""
    if name not in CUNEATE_BATTERIES:
        afferent_battery(name, 0.0)         # refuses, naming the known ones
    return {"trains": BATTERY_TARGETS, "inputs": BATTERY_SOURCES,
            "bytes_per_step": 24.0 * (BATTERY_TARGETS + BATTERY_SOURCES)}


def _on_grid(t):
    return np.round(np.asarray(t) / GRID_MS) * GRID_MS


@lru_cache(maxsize=8)
def afferent_battery(name: str, duration_ms: float) -> AfferentBattery:
    """The battery ``name`` (one of :data:`CUNEATE_BATTERIES`) for a run of ``duration_ms``."""
    if name not in CUNEATE_BATTERIES:
        raise ValueError(f"unknown coincidence battery {name!r}; known: "
                         f"{', '.join(CUNEATE_BATTERIES)}")
    rng = np.random.default_rng(11)
    S, M = BATTERY_SOURCES, BATTERY_TARGETS
    latency = _on_grid(rng.uniform(0.0, 6.0, S))
    events = np.sort(rng.uniform(0.0, duration_ms, rng.poisson(20.0 * duration_ms / 1000.0)))
    trains = []
    for s in range(S):
        fire = events[rng.random(events.size) < 0.8]
        t = fire + latency[s] + rng.normal(0.0, 0.25, fire.size)
        bg = rng.uniform(0.0, duration_ms, rng.poisson(4.0 * duration_ms / 1000.0))
        t = np.unique(_on_grid(np.concatenate([t, bg])))
        trains.append(tuple(float(x) for x in t[(t >= 0) & (t < duration_ms)]))
    tuned = _on_grid(latency.max() - latency[None, :] + rng.uniform(0.0, 2.0, (M // 2, 1)))
    delays = np.vstack([tuned, _on_grid(rng.uniform(0.0, 8.0, (M - M // 2, S)))])
    weights = rng.uniform(4.0, 8.0, (M, S))
    return AfferentBattery(name, tuple(trains), delays, weights)


def golden_cuneate_trains(bat: AfferentBattery, dt_ms: float, n_steps: int,
                          scheme: str = "euler", dtype=np.float64) -> list[np.ndarray]:
    """The battery on the golden model: the PSP drive of :func:`cuneate.golden.coincidence
    .psp_drive` (float64) into RS targets integrated by ``scheme`` in ``dtype`` - what
    :func:`cuneate.golden.coincidence.simulate_cuneate` does, with the arithmetic selectable."""
    drive = gcun.psp_drive([np.asarray(s) for s in bat.spike_times_ms], bat.delays_ms,
                           np.arange(n_steps) * dt_ms, J=1.0, weights=bat.weights)
    r = giz.simulate("RS", drive, n_steps=n_steps, n_neurons=bat.n, dt_ms=dt_ms, scheme=scheme,
                     dtype=dtype)
    return [np.asarray(s, dtype=np.float64) for s in r.spikes_ms]


@lru_cache(maxsize=8)
def _float64_trains(battery: str, duration_ms: float, dt_ms: float, n_steps: int) -> tuple:
    """Float64 Euler at a point's dt (shared by the points of one rate in a process)."""
    return tuple(golden_cuneate_trains(afferent_battery(battery, duration_ms), dt_ms, n_steps))


def cuneate_reference_trains(spec: SweepSpec) -> list[np.ndarray]:
    """Float64 golden, RK4 at ``spec.reference_hz`` (see the module docstring)."""
    bat = afferent_battery(spec.battery, float(spec.duration_ms))
    dt = 1000.0 / spec.reference_hz
    return golden_cuneate_trains(bat, dt, n_steps_of(spec.duration_ms, dt), "rk4")


@dataclass(frozen=True)
class CoincidenceSweepPoint(Point):
    """One way to simulate the afferent battery: ``engine`` is ``fixed``, ``float64`` or
    ``float32``; the knobs of :class:`~cuneate.hdl.coincidence.config.CoincidenceConfig` apply to
    ``fixed`` only."""

    weight_bits: int = 12
    """width of the ``J w`` weights"""
    trace_frac_bits: int = 16
    """fraction bits of the PSP traces"""

    BLOCK: ClassVar[str] = "coincidence"

    def label(self) -> str:
        rate = f"{self.update_hz / 1e3:g} kHz"
        if self.engine != "fixed":
            return f"{self.engine} coincidence {rate}"
        return (f"fixed coincidence {rate} w{self.weight_bits} tr.{self.trace_frac_bits} "
                f"op{self.operand_width} {self.rounding}")

    def evaluate(self, spec: SweepSpec, ref: list) -> dict:
        """Simulate the battery at this point, measured against ``ref`` and against float64
        Euler at the same dt; a row shaped like :func:`cuneate.sim.sweep.evaluate`'s."""
        bat = afferent_battery(spec.battery, float(spec.duration_ms))
        dt = 1000.0 / self.update_hz
        n_steps = n_steps_of(spec.duration_ms, dt)
        row: dict = {"key": self.key(spec), "label": self.label(), **asdict(self), "dt_ms": dt}
        t0 = time.perf_counter()
        if self.engine == "fixed":
            try:
                cfg = coincidence_config(self, bat)
            except FixedPointError as exc:     # the configuration refuses these widths
                return refused(row, exc)
            run = run_coincidence("fixed", cfg, bat.ticks(dt)[0], n_steps)
            trains = [np.asarray(s, dtype=np.float64) for s in run.spikes_ms]
            per_target = bat.n_sources + CYCLES_PER_TARGET_EXTRA
            row.update(state_bits=cfg.iz.V.width + cfg.iz.U.width + 2 * cfg.TV.width,
                       weight_bits=cfg.W.width, acc_bits=cfg.acc_bits,
                       multipliers=2 + (4 if cfg.iz.dt_shift is not None else 5),
                       neurons_per_core=int((spec.clock_hz // self.update_hz - 2)
                                            // per_target),
                       clamped_updates=int(sum(run.clamp_counts.values())),
                       trace_format=str(cfg.TV), weight_format=str(cfg.W))
        elif self.engine in ("float64", "float32"):
            dtype = np.float64 if self.engine == "float64" else np.float32
            trains = golden_cuneate_trains(bat, dt, n_steps, dtype=dtype)
            bits = np.dtype(dtype).itemsize * 8
            row.update(state_bits=2 * bits, weight_bits=64, acc_bits=None, multipliers=None,
                       neurons_per_core=None)
        else:
            raise ValueError(f"unknown engine {self.engine!r}; known: fixed, float64, float32")
        row.update(ok_row(ref, trains, dt, spec, t0))
        f64 = _float64_trains(bat.name, float(spec.duration_ms), dt, n_steps)
        row.update(same_dt_columns("vs_float64_", list(f64), trains, dt, BLOCK_SAME_DT_KEYS))
        return row


def coincidence_config(p: CoincidenceSweepPoint, bat: AfferentBattery) -> CoincidenceConfig:
    """The detector of point ``p`` for battery ``bat``: a clock of exactly the cycles a tick
    needs, a history just deep enough for the longest delay. Raises the configuration's
    error."""
    dt = 1000.0 / p.update_hz
    _, delays = bat.ticks(dt)
    cycles = bat.n * (bat.n_sources + CYCLES_PER_TARGET_EXTRA) + 2
    return CoincidenceConfig(n_sources=bat.n_sources, n_targets=bat.n, delays_ticks=delays,
                             weights=bat.weights, max_delay_ticks=int(delays.max()) + 1,
                             clock_hz=p.update_hz * cycles, update_hz=float(p.update_hz),
                             weight_bits=int(p.weight_bits),
                             trace_frac_bits=int(p.trace_frac_bits),
                             operand_width=int(p.operand_width), rounding=p.rounding)


def coincidence_point_trains(p: CoincidenceSweepPoint, spec: SweepSpec) -> list[np.ndarray]:
    """The spike trains (ms) point ``p`` produces on the battery of ``spec`` (what
    :meth:`CoincidenceSweepPoint.evaluate` measures). Raises the configuration's error when
    the detector refuses the point."""
    bat = afferent_battery(spec.battery, float(spec.duration_ms))
    dt = 1000.0 / p.update_hz
    n_steps = n_steps_of(spec.duration_ms, dt)
    if p.engine == "fixed":
        run = run_coincidence("fixed", coincidence_config(p, bat), bat.ticks(dt)[0], n_steps)
        return [np.asarray(s, dtype=np.float64) for s in run.spikes_ms]
    return golden_cuneate_trains(bat, dt, n_steps,
                                 dtype=np.float32 if p.engine == "float32" else np.float64)


def coincidence_grid(update_hz=(16e3,), weight_bits=(12,), trace_frac_bits=(16,),
                     operand_width=(18,), rounding=("nearest",),
                     floats=("float64", "float32")) -> list[CoincidenceSweepPoint]:
    """Every fixed-point combination of the knobs, then the float engines at each rate.
    Raises :class:`ValueError` for a rate whose tick does not hold the battery's 0.25 ms grid
    (rates must be multiples of 4 kHz)."""
    for h in update_hz:
        if float(h) <= 0 or abs(float(h) / 4e3 - round(float(h) / 4e3)) > 1e-9:
            raise ValueError(f"update rate {float(h):g} Hz: the coincidence battery needs a "
                             f"multiple of 4000 Hz (its spike times and delays lie on a "
                             f"{GRID_MS} ms grid)")
    pts = [CoincidenceSweepPoint("fixed", float(h), int(ow), r, weight_bits=int(wb),
                                 trace_frac_bits=int(tf))
           for h in update_hz for wb in weight_bits for tf in trace_frac_bits
           for ow in operand_width for r in rounding]
    pts += [CoincidenceSweepPoint(f, float(h)) for f in floats for h in update_hz]
    return pts


# ----------------------------------------------------------------------------------------------
# the framework's interface

reference_trains = cuneate_reference_trains
COLUMNS = CUNEATE_COLUMNS


def default_duration_ms(name: str) -> float | None:
    """The afferent battery has no natural length (the sweep's default applies)."""
    return None


def points_from_args(args, rates, widths, rounding, floats, parse):
    """The points of ``cuneate sweep`` for the coincidence battery and the report's columns."""
    wbits = parse(args.weight_bits, int, "--weight-bits") if args.weight_bits else [12]
    return coincidence_grid(rates, wbits, parse(args.trace_frac_bits, int, "--trace-frac-bits"),
                            widths, rounding, floats), CUNEATE_COLUMNS


for _name in CUNEATE_BATTERIES:
    register_battery(_name, sys.modules[__name__])
