"""The Izhikevich block in the accuracy sweep: its batteries, its points and their evaluation
(see :mod:`cuneate.sim.sweep` for the framework).

Each **point** is one way to simulate the battery: the fixed-point core (its bit-exact twin) at
an update rate, multiplier operand width, state fraction bits and rounding; or the float model
(float64 or float32) with an integration scheme at an update rate. Every point is measured
against one **fine-step reference** (float64 RK4 at ``reference_hz``, default 256 kHz), and,
to separate the arithmetic's error from the scheme's, against float64 forward Euler at its own
dt; with ``synth`` the core sized for the clock is synthesized (yosys ``synth_ecp5``) and with
``fmax`` placed and routed (nextpnr-ecp5 on the ULX3S's LFE5U-85F).

A :class:`Battery` is a population of independent Izhikevich neurons, each with a parameter set,
an initial state and a current of time:

* ``yardstick`` (RS, IB, CH, FS x I in {4, 10, 30, 100}: the README's 16 trains), ``wide`` (the
  same presets x 15 currents 3.5..100: 60 trains), ``long`` (6 presets x 8 currents 0..40);
* ``behaviours``: Izhikevich's published panels but (T), each with its own parameters
  (class-1 v-equation, accommodation's u-equation, negative ``a``), initial state and stimulus
  (steps, pulses, ramps), held at its last value after the panel;
* ``scene``, ``scene:NAME`` (an example scene) or ``scene:PATH`` (a scene file): the scene's
  driven Izhikevich neurons (every trial, population and grating) with the currents its front
  end computes from its synthesized traces - per sample, held for the sample period (the
  driver's latency, a pure shift, is left out so every engine sees the same signal).
"""

from __future__ import annotations

import functools
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ...golden import izhikevich as giz
from ...hdl.flow.synth import nextpnr_ecp5, synthesize
from ...hdl.izhikevich import IzhikevichConfig, izhikevich_verilog
from ...hdl.lib.fixed import QFormat
from ..scenes.runner import check_budget
from ..scenes.scene import default_scene, example_names, example_path, load_scene
from ..sweep import (Point, SweepSpec, n_steps, ok_row, point_key, refused, register_battery,
                     same_dt_columns)

__all__ = ["BATTERIES", "Battery", "battery", "scene_battery", "simulate_float", "SweepPoint",
           "grid", "fixed_config", "run_fixed", "reference_trains", "points_from_args",
           "COLUMNS", "current_format", "default_duration_ms", "synth_point", "battery_size",
           "BLOCK"]

#: The block whose engine speeds estimate this module's sweeps.
BLOCK = "izhikevich"

PRESETS = ("RS", "IB", "CH", "FS")
BATTERIES = {
    "yardstick": [(p, i) for p in PRESETS for i in (4.0, 10.0, 30.0, 100.0)],
    "wide": [(p, float(i)) for p in PRESETS
             for i in np.round(np.geomspace(3.5, 100.0, 15), 2)],
    "long": [(p, float(i)) for p in ("RS", "IB", "CH", "FS", "LTS", "RZ")
             for i in (0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0)],
    # Izhikevich's published panels (each with its own parameters, initial state and stimulus)
    "behaviours": "the 20 published behaviours but (T), which diverges at every converged step",
}


@dataclass(frozen=True)
class Battery:
    """The trains a sweep simulates: per train a parameter set (preset name or
    :class:`~cuneate.golden.izhikevich.IzhikevichParams`), an initial state and a current -
    constant (``constant``), a stimulus of time (``stimuli``, the published behaviours, each
    held at its last value after the panel's duration) or per-sample currents (``samples``,
    ``(n_samples, n)`` mV/ms, each held for ``sample_ms``; a scene's front end).
    ``duration_ms``: the battery's natural length (a scene's), if it has one;
    ``current_range`` / ``current_format``: the core's accepted currents, if not its defaults
    (a scene's hardware current format)."""

    name: str
    params: tuple
    labels: tuple
    constant: tuple | None = None
    stimuli: tuple | None = None
    v0: tuple | None = None
    u0: tuple | None = None
    current_range: tuple | None = None
    samples: np.ndarray | None = None
    sample_ms: float | None = None
    duration_ms: float | None = None
    current_format: object = None

    @property
    def n(self) -> int:
        return len(self.params)

    def currents(self, dt_ms: float, n_steps: int) -> np.ndarray:
        """Per-update currents ``(n_steps, n)`` read at ``t = k dt`` (constants as a zero-copy
        broadcast)."""
        if self.constant is not None:
            return np.broadcast_to(np.asarray(self.constant, dtype=np.float64),
                                   (n_steps, self.n))
        t = np.arange(n_steps) * dt_ms
        if self.samples is not None:
            # sample j holds over [j T, (j + 1) T); the last one is held after the scene
            j = np.floor(t / self.sample_ms + 1e-9).astype(np.int64)
            return self.samples[np.minimum(j, self.samples.shape[0] - 1)]
        return np.stack([np.broadcast_to(b.current(np.minimum(t, b.duration_ms)), (n_steps,))
                         for b in self.stimuli], axis=1)


def battery(name: str) -> Battery:
    """The battery called ``name``: one of :data:`BATTERIES`, or ``scene`` (the default
    scene), ``scene:NAME`` (an example scene) or ``scene:PATH`` (a scene file)."""
    if name == "scene" or name.startswith("scene:"):
        return scene_battery(name.partition(":")[2] or None)
    if name not in BATTERIES:
        raise ValueError(f"unknown battery {name!r}; known: {', '.join(BATTERIES)}, scene, "
                         f"scene:NAME (an example) or scene:PATH (a scene file)")
    if name == "behaviours":
        from ...golden.behaviours import BEHAVIOURS
        bs = [b for k, b in BEHAVIOURS.items() if k != "T"]
        return Battery(name, tuple(b.params for b in bs), tuple(b.key for b in bs),
                       stimuli=tuple(bs), v0=tuple(b.v0 for b in bs),
                       u0=tuple(b.u0 for b in bs),
                       current_range=(min(b.current_range[0] for b in bs),
                                      max(b.current_range[1] for b in bs)))
    b = BATTERIES[name]
    return Battery(name, tuple(p for p, _ in b), tuple(f"{p} I={i:g}" for p, i in b),
                   constant=tuple(float(i) for _, i in b))


@functools.lru_cache(maxsize=4)
def scene_battery(which: str | None = None) -> Battery:
    """A scene's driven Izhikevich neurons (every trial, population and grating; labels
    ``trial/population/grating``) with the float currents its front end computes from its
    synthesized traces, per sensor sample. ``which``: ``None`` (the default scene), an example
    name or a scene file. Refused (``ValueError``, one line): a scene whose neurons are not
    Izhikevich neurons driven by currents (the taxel skin, the ridge network), a grid of
    texture conditions (one condition is a battery)."""
    from ..scenes.afferent import build_izhikevich, build_neurons, front_end, synthesize
    scene = _scene_of(which)
    if scene.kind == "texture":        # a MEMS fingertip's trials and SA afferents
        from ..scenes import texture_trials
        if texture_trials.is_grid(scene):
            raise ValueError(f"scene {which!r} is a grid of conditions; a sweep battery is "
                             f"one condition's neurons")
        synthesize, build_neurons = texture_trials.synthesize, texture_trials.build_neurons
    check_budget(scene, ["golden"])
    _, _, traces, infos, _ = synthesize(scene)
    nn = build_neurons(scene, len(traces))
    cfg, _ = build_izhikevich(scene, nn)
    _, cur, _ = front_end(scene, nn, traces, infos, cfg)
    fs = scene["sensor"]["sample_rate_hz"]
    return Battery(f"scene:{which}" if which else "scene", tuple(nn.preset),
                   tuple(f"{t}/{p}/{g}" for t, p, g in zip(nn.trial, nn.population, nn.grating)),
                   samples=cur, sample_ms=1000.0 / fs, current_format=cfg.I,
                   current_range=cfg.current_range, duration_ms=cur.shape[0] * 1000.0 / fs)


def _scene_of(which: str | None):
    """The scene of a ``scene`` battery, refused (``ValueError``) unless it drives independent
    Izhikevich neurons with currents."""
    if which is None:
        scene = default_scene()
    elif example_path(which) is not None:
        scene = load_scene(example_path(which))
    elif Path(which).is_file():
        scene = load_scene(which)
    else:
        raise ValueError(f"scene {which!r} is neither an example "
                         f"({', '.join(Path(n).stem for n in example_names())})"
                         f" nor a scene file")
    kind = scene["stimulus"]["kind"]
    if kind in ("press", "ridges") or any(p["model"] != "izhikevich" for p in scene.populations):
        raise ValueError(f"scene {which or 'default'!r} ({kind}) does not drive independent "
                         f"Izhikevich neurons with currents; a sweep battery needs one that does")
    return scene


def simulate_float(bat: Battery, dt_ms: float, n_steps: int, scheme: str,
                   dtype=np.float64) -> list[np.ndarray]:
    """The battery on the golden model with ``scheme`` and ``dtype`` (float64 or float32)."""
    r = giz.simulate(list(bat.params), bat.currents(dt_ms, n_steps), n_neurons=bat.n,
                     n_steps=n_steps, dt_ms=dt_ms, scheme=scheme, dtype=dtype,
                     v0=None if bat.v0 is None else np.asarray(bat.v0),
                     u0=None if bat.u0 is None else np.asarray(bat.u0))
    return [np.asarray(s) for s in r.spikes_ms]


@dataclass(frozen=True)
class SweepPoint(Point):
    """One configuration: ``engine`` is ``fixed``, ``float64`` or ``float32``;
    ``current_frac_bits``: fraction bits of the core's current format (``None``: the
    battery's, by default sQ10.8)."""

    v_frac_bits: int = 18
    u_frac_bits: int = 20
    """state fraction bits of v and u"""
    scheme: str = "euler"
    """the float models' integration scheme: ``euler``, ``izhikevich`` or ``rk4``"""
    current_frac_bits: int | None = None

    def key(self, spec: "SweepSpec") -> str:
        fields = {k: v for k, v in asdict(self).items() if v is not None}
        return point_key(fields, spec.battery, spec.duration_ms, spec.reference_hz,
                         spec.clock_hz, spec.synth or spec.fmax, spec.fmax,
                         *(() if spec.pipeline_stages == 5 and tuple(spec.seeds) == (1,) else
                           (spec.pipeline_stages, tuple(spec.seeds))),
                         *(("pack_registers",) if spec.pack_registers and spec.fmax else ()))

    def label(self) -> str:
        if self.engine == "fixed":
            cur = "" if self.current_frac_bits is None else f" i.{self.current_frac_bits}"
            return (f"fixed {self.update_hz / 1e3:g} kHz w{self.operand_width} "
                    f"v.{self.v_frac_bits} u.{self.u_frac_bits}{cur} {self.rounding}")
        return f"{self.engine} {self.scheme} {self.update_hz / 1e3:g} kHz"

    def evaluate(self, spec: SweepSpec, ref: list) -> dict:
        """Simulate the battery at this point and measure it against ``ref``."""
        bat = battery(spec.battery)
        dt = 1000.0 / self.update_hz
        steps = n_steps(spec.duration_ms, dt)
        row: dict = {"key": self.key(spec), "label": self.label(), **asdict(self), "dt_ms": dt}
        t0 = time.perf_counter()
        try:
            if self.engine == "fixed":
                from ...hdl.izhikevich import IzhikevichTwin
                cfg = fixed_config(self, bat)
                twin = IzhikevichTwin(cfg)
                trains = run_fixed(twin, bat, dt, steps)
                row.update(multipliers=4 if cfg.dt_shift is not None else 5,
                           state_bits=cfg.V.width + cfg.U.width, current_bits=cfg.I.width,
                           neurons_per_core=int(spec.clock_hz // self.update_hz),
                           clamped_updates=int(sum(twin.clamp_counts.values())))
            else:
                dtype = np.float32 if self.engine == "float32" else np.float64
                trains = simulate_float(bat, dt, steps, self.scheme, dtype)
                row.update(multipliers=None, state_bits=64 if dtype == np.float32 else 128,
                           neurons_per_core=None)
        except Exception as exc:              # a configuration the core refuses, a divergence
            return refused(row, exc)
        row.update(ok_row(ref, trains, dt, spec, t0))
        if self.engine == "fixed" or self.engine == "float32" or self.scheme != "euler":
            # the error of the arithmetic alone: against float64 forward Euler at the same dt
            row.update(same_dt_columns("vs_euler_", simulate_float(bat, dt, steps, "euler"),
                                       trains, dt))
        if (spec.synth or spec.fmax) and self.engine == "fixed":
            row.update(synth_point(self, spec))
        return row


def grid(update_hz=(16e3,), operand_width=(18,), frac_bits=((18, 20),),
         rounding=("nearest",), schemes=("euler",), floats=("float64", "float32"),
         current_frac_bits=(None,)) -> list[SweepPoint]:
    """The points of a sweep: every fixed-point combination, and the float models at each
    scheme and update rate."""
    pts = [SweepPoint("fixed", float(h), int(w), r, v_frac_bits=int(fv), u_frac_bits=int(fu),
                      current_frac_bits=None if c is None else int(c))
           for h in update_hz for w in operand_width for fv, fu in frac_bits
           for c in current_frac_bits for r in rounding]
    pts += [SweepPoint(f, float(h), scheme=s) for f in floats for s in schemes
            for h in update_hz]
    return pts


def fixed_config(p: SweepPoint, bat: Battery):
    """The core configuration of point ``p`` for battery ``bat`` (at least 5 neurons, external
    tick, the battery's initial states and current format)."""
    n = bat.n
    N = max(n, 5)
    sets = tuple(dict.fromkeys(bat.params))
    pad = N - n
    kw = {}
    if bat.v0 is not None:
        kw["v_init"] = list(bat.v0) + [bat.v0[0]] * pad
        kw["u_init"] = list(bat.u0) + [bat.u0[0]] * pad
    if bat.current_range is not None:
        kw["current_range"] = bat.current_range
    if bat.current_format is not None:
        kw["current_format"] = bat.current_format
    if p.current_frac_bits is not None:
        kw["current_format"] = current_format(p, bat.current_format)
    return IzhikevichConfig(n_neurons=N, clock_hz=p.update_hz * N, update_hz=p.update_hz,
                            param_sets=sets,
                            neuron_sets=[sets.index(x) for x in bat.params] + [0] * pad,
                            operand_width=p.operand_width, v_frac_bits=p.v_frac_bits,
                            u_frac_bits=p.u_frac_bits, rounding=p.rounding,
                            tick_source="external", **kw)


def current_format(p: SweepPoint, base=None):
    """The core's current format at point ``p``: ``base`` (default sQ10.8) with the point's
    fraction bits."""
    base = base or IzhikevichConfig.current_format
    if p.current_frac_bits is None:
        return base
    return QFormat(base.int_bits, p.current_frac_bits)


def run_fixed(twin, bat: Battery, dt_ms: float, n_steps: int) -> list[np.ndarray]:
    """The battery's trains on a core twin built by :func:`fixed_config` (the neurons that pad
    the core to its minimum size get no current)."""
    n, pad = bat.n, twin.cfg.n_neurons - bat.n
    if bat.constant is not None:
        return twin.run(np.concatenate([bat.constant, np.zeros(pad)]), n_steps)[:n]
    sched = np.concatenate([bat.currents(dt_ms, n_steps), np.zeros((n_steps, pad))], axis=1)
    return twin.run(lambda t: sched[int(round(t / dt_ms))], n_steps)[:n]


def synth_point(p: SweepPoint, spec: SweepSpec) -> dict:
    """yosys synth_ecp5 of the core with as many neurons as the clock allows at this rate;
    with ``spec.fmax`` also nextpnr-ecp5 place and route of the bare core on the ULX3S's
    LFE5U-85F (CABGA381, speed grade 6, ports on free pins) at each of ``spec.seeds``:
    ``fmax_mhz`` (the lowest) and ``fmax_mhz_per_seed``; the core has
    ``spec.pipeline_stages`` stages; with ``spec.pack_registers`` the flip-flops around its
    multipliers and after its block RAMs are packed into their registers first."""

    n = int(spec.clock_hz // p.update_hz)
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=n * p.update_hz, update_hz=p.update_hz,
                           operand_width=p.operand_width, v_frac_bits=p.v_frac_bits,
                           u_frac_bits=p.u_frac_bits, rounding=p.rounding,
                           current_format=current_format(p),
                           pipeline_stages=spec.pipeline_stages)
    out = {}
    with tempfile.TemporaryDirectory(prefix="cuneate-sweep-") as d:
        r = synthesize(izhikevich_verilog(cfg, "izhikevich_core"), "izhikevich_core", "ecp5",
                       Path(d), netlist=spec.fmax,
                       pack_registers=spec.fmax and spec.pack_registers)
        if spec.fmax:
            per_seed = [nextpnr_ecp5(Path(d), r["netlist"], device="85k", package="CABGA381",
                                     speed=6, seed=s, freq_mhz=spec.clock_hz / 1e6,
                                     out_of_context=False, timeout=3600)["min_fmax_mhz"]
                        for s in spec.seeds]
            out["fmax_mhz"] = min(per_seed)
            out["fmax_mhz_per_seed"] = per_seed
    for cell in ("LUT4", "CCU2C", "TRELLIS_FF", "DP16KD", "MULT18X18D"):
        out[cell] = int(r["cells"].get(cell, 0))
    return out


def reference_trains(spec: SweepSpec) -> list[np.ndarray]:
    """Float64 RK4 at ``reference_hz`` on the battery (the accuracy reference)."""
    dt = 1000.0 / spec.reference_hz
    return simulate_float(battery(spec.battery), dt, n_steps(spec.duration_ms, dt), "rk4")


def battery_size(name: str) -> dict:
    """The size of battery ``name`` without building it: ``trains``, ``inputs`` (none) and
    ``bytes_per_step`` (the per-update currents a run holds: none for constant currents, a
    broadcast; a scene's from its file: every trial, population and grating)."""
    if name == "scene" or name.startswith("scene:"):
        from ..scenes.afferent import n_driven
        n = n_driven(_scene_of(name.partition(":")[2] or None))[1]
        return {"trains": n, "inputs": 0, "bytes_per_step": 24.0 * n}
    if name == "behaviours":
        from ...golden.behaviours import BEHAVIOURS
        n = len(BEHAVIOURS) - 1
        return {"trains": n, "inputs": 0, "bytes_per_step": 24.0 * n}
    if name not in BATTERIES:
        battery(name)                       # refuses, naming the known ones
    return {"trains": len(BATTERIES[name]), "inputs": 0, "bytes_per_step": 0.0}


def default_duration_ms(name: str) -> float | None:
    """The battery's natural length (a scene's), if it has one; refuses an unknown or unusable
    battery (``ValueError``, one line)."""
    return battery(name).duration_ms


def points_from_args(args, rates, widths, rounding, floats, parse):
    """The points of ``cuneate sweep`` for an Izhikevich battery and the report's columns
    (``parse(text, conv, option)``: the command line's list parser); ``ValueError`` names the
    option that is out of range."""
    def frac(text):
        v, _, u = text.partition(":")
        return int(v), int(u or v)
    fracs = parse(args.frac_bits, frac, "--frac-bits")
    cfb = parse(args.current_frac_bits, int, "--current-frac-bits") \
        if args.current_frac_bits else [None]
    if any(c is not None and not 0 <= c <= 24 for c in cfb):
        raise ValueError("--current-frac-bits: fraction bits must lie in 0..24")
    schemes = parse(args.schemes, str, "--schemes")
    if set(schemes) - {"euler", "izhikevich", "rk4"}:
        raise ValueError("--schemes: euler, izhikevich and/or rk4")
    return grid(rates, widths, fracs, rounding, schemes, floats, cfb), COLUMNS


COLUMNS = ("label", "engine", "update_hz", "operand_width", "v_frac_bits", "u_frac_bits",
           "current_frac_bits", "rounding", "scheme", "status", "counts_equal", "count_error",
           "fraction_within_tick", "mean_abs_error_ms", "mean_vp",
           "first_spike_latency_error_ms", "vs_euler_fraction_within_tick",
           "vs_euler_counts_equal", "vs_euler_mean_vp", "neurons_per_core", "multipliers",
           "state_bits", "current_bits", "host_s_per_bio_s", "LUT4", "CCU2C", "TRELLIS_FF",
           "DP16KD", "MULT18X18D",
           "fmax_mhz", "reason")


_THIS = sys.modules[__name__]
for _name in BATTERIES:
    register_battery(_name, _THIS)
register_battery("scene", _THIS)
register_battery("scene:", _THIS, prefix=True)
