"""The LIF block in the accuracy sweep: its word widths swept against the float64 golden model.

Registered with the framework (:mod:`cuneate.sim.sweep`: same
:class:`~cuneate.sim.sweep.SweepSpec`, same :func:`~cuneate.sim.sweep.run_sweep` with its Dask
pool and per-point cache, same accuracy columns). A :class:`LifSweepPoint` is one way to
simulate a LIF battery:

* ``fixed``: the bit-exact twin of the LIF core (:class:`cuneate.hdl.lif.LifTwin`, run through
  :func:`cuneate.sim.lif.engines.run_lif`) configured from the point's knobs - update rate,
  state fraction bits, multiplier operand width, weight width, decay by multiplier or by shift,
  rounding, accepted decay error; a configuration :class:`~cuneate.hdl.lif.config.LifConfig`
  refuses is a row with status ``refused`` and its one-line reason;
* ``float64`` / ``float32``: the golden model (:mod:`cuneate.golden.lif`) in that arithmetic at
  the point's update rate.

The batteries (:data:`LIF_BATTERIES`, :func:`lif_battery`):

``lif-currents``
    Continuous LIF, three parameter sets (the brief's excitatory cell, tau_m 20 ms; the
    inhibitory cell, 10 ms; a cell resting at -70 mV with tau_m 30 ms) x six constant currents
    (6 mV below to 42 mV above the rheobase) and two seeded random staircases (a new level
    every 50 ms): 24 trains. Every current is a multiple of 1/16 mV (exact in the core's sQ8.8
    current format), accepted range 0..64 mV.
``lif-pow2``
    The same drives on three cells whose tau_m (8, 16, 32 ms) makes ``k = 1 - exp(-dt/tau)``
    a power of two within 1 % at power-of-two rates: the battery on which ``decay="shift"``
    (no multiplier) can be compared with ``"multiply"``.
``lif-inputs``
    Discrete LIF (the brief's quantized networks, as in
    :func:`cuneate.sim.lif.experiments.quantization_table`): 32 neurons, each with 64 seeded
    real-valued weights ``N(0.03, 0.12)``, driven by seeded Bernoulli(0.2) input spike trains;
    two parameter sets (alpha 0.389 / u_th 0.65 from the brief, alpha 0.875 / u_th 1.5). Here
    the weight width matters.

References (:func:`lif_reference_trains`, what the ``fraction_within_tick`` columns are
measured against):

* continuous form: the float64 golden model with exact exponential integration at
  ``spec.reference_hz`` (default 256 kHz) on the same piecewise-constant currents. Exact
  integration is exact for input constant over a step, so the golden model at a point's own dt
  is already the exact solution sampled on that grid: against the fine-step reference a point
  mainly measures **tick quantization** (each threshold crossing reported at the end of its
  tick, the drift that accumulates over the inter-spike intervals) - a cost of the update
  rate, not of the word widths. The figure that isolates the arithmetic is therefore the
  comparison with float64 at the **same dt**, reported in the ``vs_float64_*`` columns
  (fraction of spikes within one tick, counts equal, count error, mean Victor-Purpura
  distance).
* discrete form: there is no finer model - one step is one step - so the reference is the
  float64 discrete model itself and the two comparisons coincide. A step stands for
  ``step_ms`` (1 ms) of biological time whatever the point's update rate, which then only sets
  the neurons per core.
"""

from __future__ import annotations

import sys
import time
from dataclasses import asdict, dataclass, field
from typing import ClassVar
from functools import lru_cache

import numpy as np

from ...golden import lif as golden
from ...golden.izhikevich import spike_ticks, spike_times
from ...hdl.lib.fixed import ROUNDINGS, FixedPointError
from ...hdl.lif.config import DECAYS, FORMS, LifSet
from ..sweep import (BLOCK_SAME_DT_KEYS, Point, SweepSpec, ok_row, refused, register_battery,
                     same_dt_columns)
from ..sweep import n_steps as n_steps_of
from .engines import LifProgram, engine_config, run_lif

__all__ = ["reference_trains", "COLUMNS", "default_duration_ms", "points_from_args",
           "LIF_BATTERIES", "LifBattery", "lif_battery", "LifSweepPoint", "lif_grid",
           "lif_reference_trains", "golden_lif_trains", "lif_core_kwargs", "lif_point_trains",
           "LIF_COLUMNS", "battery_size", "BLOCK"]

#: The block whose engine speeds estimate this module's sweeps.
BLOCK = "lif"

LIF_BATTERIES = {
    "lif-currents": "continuous LIF, 3 cells (tau_m 20, 10, 30 ms) x 6 constant currents and "
                    "2 random staircases: 24 trains",
    "lif-pow2": "continuous LIF, 3 cells with tau_m 8, 16, 32 ms (decay by shift possible) x "
                "the same 8 drives: 24 trains",
    "lif-inputs": "discrete LIF, 32 neurons x 64 random weights, Bernoulli(0.2) input spikes",
}

#: the columns of a LIF sweep's CSV, in order
LIF_COLUMNS = ("label", "engine", "update_hz", "form", "v_frac_bits", "operand_width",
               "weight_bits", "decay", "rounding", "max_decay_error", "status",
               "counts_equal", "count_error", "fraction_within_tick", "mean_abs_error_ms",
               "mean_vp", "first_spike_latency_error_ms", "vs_float64_fraction_within_tick",
               "vs_float64_counts_equal", "vs_float64_count_error", "vs_float64_mean_vp",
               "neurons_per_core", "multipliers", "state_bits", "acc_bits", "v_format",
               "weight_format", "clamped_updates", "host_s_per_bio_s", "reason")

_GRID_EPS = 1e-9
_CURRENT_STEP_MV = 1.0 / 16.0          # battery currents are multiples of this (exact in sQ8.8)


@dataclass(frozen=True)
class LifBattery:
    """The trains a LIF sweep simulates: one core's worth of neurons.

    Parameters
    ----------
    name, form
        Battery name and LIF form (``"continuous"`` or ``"discrete"``).
    param_sets, neuron_sets, labels
        Parameter sets (dicts, see :class:`cuneate.hdl.lif.config.LifSet`), the set of every
        train and its label.
    drives
        Continuous form, per train: ``("constant", I_mV)`` or ``("staircase", lo, hi,
        hold_ms, seed)`` (a seeded uniform level in ``[lo, hi]`` every ``hold_ms``, rounded to
        1/16 mV).
    weights, input_rate, input_seed
        Discrete form: ``(n, n_inputs)`` real weights and the Bernoulli rate (per step) and
        seed of the input spike trains.
    step_ms
        Discrete form: biological time of one step.
    current_format, current_range
        The core's host current format and accepted range.
    """

    name: str
    form: str
    param_sets: tuple
    neuron_sets: tuple
    labels: tuple
    drives: tuple | None = None
    weights: np.ndarray | None = field(default=None, compare=False, repr=False)
    input_rate: float = 0.0
    input_seed: int = 0
    step_ms: float = 1.0
    current_format: tuple = (8, 8)
    current_range: tuple | None = None

    @property
    def n(self) -> int:
        return len(self.neuron_sets)

    @property
    def n_inputs(self) -> int:
        return 0 if self.weights is None else int(self.weights.shape[1])

    def dt_ms(self, update_hz: float) -> float:
        """The tick of a point at ``update_hz``: ``1000 / update_hz`` (continuous) or one step
        (discrete)."""
        return 1000.0 / update_hz if self.form == "continuous" else self.step_ms

    def currents(self, dt_ms: float, n_steps: int) -> np.ndarray:
        """Host currents ``(n_steps, n)`` in mV read at ``t = k dt`` (zero in the discrete
        form)."""
        if self.form == "discrete":
            return np.zeros((n_steps, self.n))
        t = np.arange(n_steps) * dt_ms + _GRID_EPS
        cols = []
        for d in self.drives:
            if d[0] == "constant":
                cols.append(np.full(n_steps, d[1]))
                continue
            _, lo, hi, hold, seed = d
            n_levels = int(t[-1] // hold) + 1 if n_steps else 0
            levels = np.random.default_rng(seed).uniform(lo, hi, n_levels)
            levels = np.round(levels / _CURRENT_STEP_MV) * _CURRENT_STEP_MV
            cols.append(levels[(t // hold).astype(np.int64)])
        return np.stack(cols, axis=1)

    def inputs(self, n_steps: int) -> np.ndarray | None:
        """Input spikes ``(n_steps, n_inputs)`` (a longer run extends a shorter one)."""
        if not self.n_inputs:
            return None
        rng = np.random.default_rng(self.input_seed)
        return rng.random((n_steps, self.n_inputs)) < self.input_rate


def _drives(rheobase: float, seed: int) -> list:
    offsets = (-6.0, 0.5, 2.0, 7.0, 17.0, 42.0)
    return ([("constant", rheobase + o) for o in offsets]
            + [("staircase", rheobase - 6.0, rheobase + 30.0, 50.0, seed + j) for j in (0, 1)])


def _continuous_battery(name: str, sets: list[dict]) -> LifBattery:
    drives, ns, labels = [], [], []
    for i, s in enumerate(sets):
        full = LifSet.make(s, "continuous")
        rheobase = full.v_th - full.v_rest
        for d in _drives(rheobase, seed=100 * i):
            drives.append(d)
            ns.append(i)
            what = f"I={d[1]:g}" if d[0] == "constant" else f"staircase seed {d[4]}"
            labels.append(f"tau_m {full.tau_m_ms:g} {what}")
    return LifBattery(name, "continuous", tuple(sets), tuple(ns), tuple(labels), tuple(drives),
                      current_range=(0.0, 64.0))


def lif_battery(name: str) -> LifBattery:
    """The battery ``name`` (one of :data:`LIF_BATTERIES`)."""
    if name == "lif-currents":
        return _continuous_battery(name, [
            {}, {"tau_m_ms": golden.TAU_M_INH_MS, "t_ref_ms": golden.T_REF_INH_MS},
            {"tau_m_ms": 30.0, "v_th": -50.0, "v_reset": -65.0, "v_rest": -70.0,
             "t_ref_ms": 3.0}])
    if name == "lif-pow2":
        return _continuous_battery(name, [{"tau_m_ms": t} for t in (8.0, 16.0, 32.0)])
    if name == "lif-inputs":
        n, f = 32, 64
        w = np.random.default_rng(7).normal(0.25 * 0.12, 0.12, (n, f))
        sets = ({"alpha": golden.DISCRETE_ALPHA, "u_th": golden.DISCRETE_U_TH},
                {"alpha": 0.875, "u_th": 1.5})
        return LifBattery(name, "discrete", sets, tuple(i % 2 for i in range(n)),
                          tuple(f"neuron {i} alpha {sets[i % 2]['alpha']:g}" for i in range(n)),
                          weights=w, input_rate=0.2, input_seed=8, current_format=(1, 1))
    raise ValueError(f"unknown LIF battery {name!r}; known: {', '.join(LIF_BATTERIES)}")


def battery_size(name: str) -> dict:
    """The size of battery ``name``: ``trains``, ``inputs`` and ``bytes_per_step`` (the
    per-step currents and input spikes a run holds)."""
    bat = lif_battery(name)
    return {"trains": bat.n, "inputs": bat.n_inputs,
            "bytes_per_step": 24.0 * bat.n + 2.0 * bat.n_inputs}


def golden_lif_trains(bat: LifBattery, dt_ms: float, n_steps: int,
                      dtype=np.float64) -> list[np.ndarray]:
    """The battery on the golden model in ``dtype`` at ``dt_ms``: spike times (ms) per train."""
    sets = [LifSet.make(s, bat.form) for s in bat.param_sets]
    sel = np.asarray(bat.neuron_sets)
    if bat.form == "continuous":
        res = golden.simulate_lif(
            bat.currents(dt_ms, n_steps), dt_ms, n_neurons=bat.n, record=False, dtype=dtype,
            **{k: np.array([getattr(sets[i], k) for i in sel])
               for k in ("tau_m_ms", "v_th", "v_reset", "v_rest", "t_ref_ms")})
        return [np.asarray(s, dtype=np.float64) for s in res.spikes_ms]
    x = bat.inputs(n_steps)
    trains: list[np.ndarray] = [np.zeros(0)] * bat.n
    for i, s in enumerate(sets):
        idx = np.flatnonzero(sel == i)
        res = golden.simulate_discrete_lif(x, bat.weights[idx].T, alpha=s.alpha, u_th=s.v_th,
                                           u_rest=s.v_reset,
                                           refractory_steps=s.refractory_steps, dtype=dtype)
        for j, n in enumerate(idx):
            trains[n] = spike_times(np.flatnonzero(res.spikes[:, j]), dt_ms)
    return trains


@lru_cache(maxsize=8)
def _float64_trains(battery: str, dt_ms: float, n_steps: int) -> tuple:
    """Float64 golden at a point's dt (shared by the points of one rate in a process)."""
    return tuple(golden_lif_trains(lif_battery(battery), dt_ms, n_steps))


def lif_reference_trains(spec: SweepSpec) -> list[np.ndarray]:
    """The accuracy reference of a LIF battery: the float64 golden model, at
    ``spec.reference_hz`` in the continuous form, per step in the discrete form (see the module
    docstring)."""
    bat = lif_battery(spec.battery)
    dt = bat.dt_ms(spec.reference_hz)
    return golden_lif_trains(bat, dt, n_steps_of(spec.duration_ms, dt))


@dataclass(frozen=True)
class LifSweepPoint(Point):
    """One way to simulate a LIF battery: ``engine`` is ``fixed``, ``float64`` or ``float32``.

    The fixed-point knobs (ignored by the float engines): ``v_frac_bits`` (state fraction
    bits), ``operand_width`` (the leak multiplier's operands; unused with ``decay="shift"``),
    ``weight_bits``, ``decay`` (``"multiply"`` or ``"shift"``), ``rounding`` (``"nearest"`` or
    ``"truncate"``) and ``max_decay_error`` (largest accepted relative error of the
    represented decay). ``form`` must be the battery's.
    """

    form: str = "continuous"
    """the battery's form: ``continuous`` or ``discrete``"""
    v_frac_bits: int = 16
    weight_bits: int = 8
    decay: str = "multiply"
    """``multiply`` (one multiplier) or ``shift`` (none)"""
    max_decay_error: float = 1e-2

    BLOCK: ClassVar[str] = "lif"

    def label(self) -> str:
        rate = f"{self.update_hz / 1e3:g} kHz"
        if self.engine != "fixed":
            return f"{self.engine} {self.form} {rate}"
        op = f"op{self.operand_width} " if self.decay == "multiply" else ""
        err = f" err{self.max_decay_error:g}" if self.max_decay_error != 1e-2 else ""
        return (f"fixed {self.form} {rate} v.{self.v_frac_bits} {op}w{self.weight_bits} "
                f"{self.decay} {self.rounding}{err}")

    def evaluate(self, spec: SweepSpec, ref: list) -> dict:
        """Simulate the battery of ``spec`` at this point and measure it against ``ref`` (the
        reference of :func:`lif_reference_trains`) and against float64 at the same dt. Returns
        a row shaped like :func:`cuneate.sim.sweep.evaluate`'s."""
        bat = lif_battery(spec.battery)
        if self.form != bat.form:
            raise ValueError(f"point {self.label()!r} is {self.form}-form, battery "
                             f"{bat.name!r} is {bat.form}-form")
        dt = bat.dt_ms(self.update_hz)
        n_steps = n_steps_of(spec.duration_ms, dt)
        row: dict = {"key": self.key(spec), "label": self.label(), **asdict(self), "dt_ms": dt}
        t0 = time.perf_counter()
        if self.engine == "fixed":
            try:
                cfg = engine_config(lif_core_kwargs(self, bat), bat.n)
            except FixedPointError as exc:     # the configuration refuses these widths
                return refused(row, exc)
            trains, clamps = _run_twin(cfg, bat, dt, n_steps)
            row.update(state_bits=cfg.V.width + cfg.ref_bits, weight_bits=cfg.W.width,
                       acc_bits=cfg.acc_bits,
                       multipliers=(1 if cfg.decay == "multiply" else 0) + len(cfg.traces),
                       neurons_per_core=int(spec.clock_hz // self.update_hz),
                       clamped_updates=int(sum(clamps.values())), v_format=str(cfg.V),
                       weight_format=str(cfg.W) if bat.n_inputs else None)
        elif self.engine in ("float64", "float32"):
            dtype = np.float64 if self.engine == "float64" else np.float32
            trains = golden_lif_trains(bat, dt, n_steps, dtype)
            bits = np.dtype(dtype).itemsize * 8
            row.update(state_bits=bits, weight_bits=bits if bat.n_inputs else None,
                       acc_bits=None, multipliers=None, neurons_per_core=None)
        else:
            raise ValueError(f"unknown engine {self.engine!r}; known: fixed, float64, float32")
        row.update(ok_row(ref, trains, dt, spec, t0))
        f64 = _float64_trains(bat.name, dt, n_steps)
        row.update(same_dt_columns("vs_float64_", list(f64), trains, dt, BLOCK_SAME_DT_KEYS))
        return row


def lif_core_kwargs(p: LifSweepPoint, bat: LifBattery) -> dict:
    """Constructor keywords of the LIF core for point ``p`` on battery ``bat`` (for
    :func:`cuneate.sim.lif.engines.engine_config`)."""
    kw = dict(update_hz=float(p.update_hz), form=bat.form,
              param_sets=[dict(s) for s in bat.param_sets], neuron_sets=list(bat.neuron_sets),
              decay=p.decay, v_frac_bits=int(p.v_frac_bits),
              operand_width=int(p.operand_width), weight_bits=int(p.weight_bits),
              rounding=p.rounding, max_decay_error=float(p.max_decay_error),
              current_format=list(bat.current_format), current_range=bat.current_range)
    if bat.weights is not None:
        kw["weights"] = bat.weights
    return kw


def _run_twin(cfg, bat: LifBattery, dt_ms: float, n_steps: int):
    """The battery on the twin of ``cfg``: spike times (in the battery's ms) and clamp
    counts."""
    run = run_lif("fixed", cfg, LifProgram(bat.currents(dt_ms, n_steps), bat.inputs(n_steps)),
                  n=bat.n)
    trains = [np.asarray(s, dtype=np.float64) for s in run.spikes_ms]
    if bat.form == "discrete":          # the twin counts ticks of 1 / update_hz: use steps
        trains = [spike_times(spike_ticks(s, cfg.dt_ms), dt_ms) for s in trains]
    return trains, run.clamp_counts


def lif_point_trains(p: LifSweepPoint, spec: SweepSpec) -> list[np.ndarray]:
    """The spike trains (ms) point ``p`` produces on the battery of ``spec`` (what
    :meth:`LifSweepPoint.evaluate` measures). Raises the configuration's error when the core
    refuses the point."""
    bat = lif_battery(spec.battery)
    dt = bat.dt_ms(p.update_hz)
    n_steps = n_steps_of(spec.duration_ms, dt)
    if p.engine == "fixed":
        return _run_twin(engine_config(lif_core_kwargs(p, bat), bat.n), bat, dt, n_steps)[0]
    return golden_lif_trains(bat, dt, n_steps,
                             np.float32 if p.engine == "float32" else np.float64)


def lif_grid(update_hz=(16e3,), form: str = "continuous", v_frac_bits=(16,),
             operand_width=(18,), weight_bits=(8,), decay=("multiply",),
             rounding=("nearest",), floats=("float64", "float32"),
             max_decay_error=(1e-2,)) -> list[LifSweepPoint]:
    """The points of a LIF sweep: every fixed-point combination of the knobs (with
    ``decay="shift"`` the operand width is unused, so only the first is kept), then the float
    engines at each update rate. ``form`` is the battery's
    (``lif_battery(name).form``). Raises :class:`ValueError` for an unknown form, decay,
    rounding or float engine."""
    for what, given, known in (("form", (form,), FORMS), ("decay", decay, DECAYS),
                               ("rounding", rounding, ROUNDINGS),
                               ("float engine", floats, ("float64", "float32"))):
        bad = [x for x in given if x not in known]
        if bad:
            raise ValueError(f"unknown {what} {bad[0]!r}; known: {', '.join(known)}")
    pts = [LifSweepPoint("fixed", float(h),
                         int(w) if d == "multiply" else int(operand_width[0]), r, form=form, v_frac_bits=int(fv), weight_bits=int(wb), decay=d,
                         max_decay_error=float(e))
           for h in update_hz for fv in v_frac_bits for w in operand_width
           for wb in weight_bits for d in decay for r in rounding for e in max_decay_error]
    pts += [LifSweepPoint(f, float(h), form=form) for f in floats for h in update_hz]
    return list(dict.fromkeys(pts))


# ----------------------------------------------------------------------------------------------
# the framework's interface

reference_trains = lif_reference_trains
COLUMNS = LIF_COLUMNS


def default_duration_ms(name: str) -> float | None:
    """LIF batteries have no natural length (the sweep's default applies)."""
    lif_battery(name)
    return None


def points_from_args(args, rates, widths, rounding, floats, parse):
    """The points of ``cuneate sweep`` for a LIF battery and the report's columns."""
    wbits = parse(args.weight_bits, int, "--weight-bits") if args.weight_bits else [8]
    return lif_grid(rates, lif_battery(args.battery).form,
                    parse(args.v_frac_bits, int, "--v-frac-bits"), widths, wbits,
                    parse(args.decay, str, "--decay"), rounding, floats,
                    parse(args.max_decay_error, float, "--max-decay-error")), LIF_COLUMNS


for _name in LIF_BATTERIES:
    register_battery(_name, sys.modules[__name__])
