"""Float64 synthesis of FBG wavelength-shift traces from the physics of a touch.

Nothing here is recorded data: every trace is computed from a stated mechanical model, the Bragg
relation of :mod:`cuneate.golden.fbg`, and only the sensor effects a caller asks for.

Grasp (design brief, section 3)
-------------------------------
A finger closes at constant velocity ``v`` on a cylinder. From contact (``t0``) its travel is
``x(t) = v (t - t0)``; the soft finger pad (a compressed slab, stiffness ``k_pad = E_pad A /
h``) is in series with the object's contact stiffness. For a cylinder of diameter ``D`` pressed
along a contact length ``L`` by a flat pad, the line-contact stiffness is taken as
``k_obj = (pi / 4) E* L`` with ``E* = E / (1 - nu^2)`` (Johnson, *Contact Mechanics*, ch. 4:
the load per length of a cylinder grows almost linearly with approach; the logarithmic
correction is neglected). The contact force is ``F = k_eff x`` with
``1 / k_eff = 1 / k_pad + 1 / k_obj``. Grating ``g`` is strained ``eps_g = c_g F`` (``c_g``:
coupling in microstrain per newton, set by where the fibre runs in the pad) and shifts
``d_lambda_g = lambda_B (1 - p_e) eps_g`` (:func:`~cuneate.golden.fbg.bragg_shift_nm`,
1.209 pm per microstrain at 1550 nm). The finger stops when the first grating reaches the stop
shift (0.01 nm published); the force, and so the shift, is then held. Soft objects load slowly,
stiff ones fast: the slope of ``d_lambda`` carries stiffness. ABS and aluminium are both far
stiffer than the pad, so their traces differ only by the pad's share (the hard pair).

Trials vary: each physical parameter is drawn ``value * (1 + spread * N(0, 1))`` (clipped to
stay positive) from the scene's seeded generator, spreads stated per parameter.

Slide
-----
A sinusoidal grating texture (period ``lambda_tex``, depth) slides at speed ``s`` under a pad
pressed with a ramped normal force: the normal load gives a sustained shift (what slowly adapting
afferents encode), the texture a vibration at ``s / lambda_tex`` (what fast adapting afferents
encode). Gratings sit ``spacing`` apart along the sliding direction, so each sees the texture
delayed by ``spacing / s``.

Effects
-------
:data:`EFFECTS` maps each effect name to the function that applies it. :func:`apply_effects`
calls only the functions of the effects listed, in the order of :data:`EFFECT_ORDER`; an effect
not listed is never computed. ``strain`` is the mechanical term itself and is always required.
Each applied effect returns counts for the run report (samples clipped, dropped, ...).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .validate import number
from .fbg import bragg_shift_nm, strain_sensitivity_pm_per_microstrain

__all__ = ["Material", "MATERIALS", "Pad", "contact_stiffness", "series_stiffness",
           "GraspSpec", "SlideSpec", "PulseSpec", "synthesize_grasp", "synthesize_slide",
           "synthesize_pulse", "EFFECTS",
           "EFFECT_ORDER", "EFFECT_UNITS", "apply_effects", "sensor_effects", "Trace"]


@dataclass(frozen=True)
class Material:
    """An object's contact material: Young's modulus (Pa), Poisson ratio, cylinder geometry."""

    name: str
    young_Pa: float
    poisson: float = 0.4
    diameter_m: float = 0.030
    height_m: float = 0.150

    def __post_init__(self):
        number(self.young_Pa, f"{self.name}: young_Pa", positive=True)
        if not 0.0 <= float(self.poisson) < 0.5:
            raise ValueError(f"{self.name}: poisson must lie in [0, 0.5), got {self.poisson!r}")
        number(self.diameter_m, f"{self.name}: diameter_m", positive=True)
        number(self.height_m, f"{self.name}: height_m", positive=True)


#: The four cylinders of the grasp experiment (30 mm diameter, 150 mm high), brief section 3.
MATERIALS = {
    "dragon_skin": Material("dragon_skin", 0.34e6, 0.49),
    "vytaflex": Material("vytaflex", 2.0e6, 0.49),
    "abs": Material("abs", 2.2e9, 0.35),
    "aluminium": Material("aluminium", 70e9, 0.33),
}


@dataclass(frozen=True)
class Pad:
    """Soft finger pad: a slab of modulus ``young_Pa``, area ``area_m2``, thickness
    ``thickness_m``; ``contact_length_m`` is the length of the line contact on a cylinder."""

    young_Pa: float = 1.0e6
    area_m2: float = 15e-3 * 15e-3
    thickness_m: float = 3e-3
    contact_length_m: float = 15e-3

    @property
    def stiffness_N_per_m(self) -> float:
        return self.young_Pa * self.area_m2 / self.thickness_m


def contact_stiffness(material: Material, contact_length_m: float) -> float:
    """Line-contact stiffness ``(pi/4) E/(1 - nu^2) L`` of a cylinder, N/m."""
    e_star = material.young_Pa / (1.0 - material.poisson ** 2)
    return float(np.pi / 4.0 * e_star * contact_length_m)


def series_stiffness(*k) -> float:
    """Stiffness of springs in series, ``1 / sum(1 / k_i)``."""
    return float(1.0 / sum(1.0 / float(x) for x in k))


@dataclass
class Trace:
    """A synthesized (or loaded) multi-grating trace: ``d_lambda_nm`` of shape
    ``(n_samples, n_gratings)`` at ``fs_hz``, plus what was computed to get it."""

    d_lambda_nm: np.ndarray
    fs_hz: float
    info: dict = field(default_factory=dict)
    effect_counts: dict = field(default_factory=dict)


@dataclass(frozen=True)
class GraspSpec:
    """A grasp: finger velocity, pad, per-grating coupling, stop shift, timing, spreads."""

    velocity_m_per_s: float = 1.5e-3
    pad: Pad = Pad()
    coupling_microstrain_per_N: tuple = (2.0, 1.6)
    stop_nm: float = 0.01
    contact_ms: float = 50.0
    duration_ms: float = 700.0
    fs_hz: float = 1000.0
    spread_velocity: float = 0.05
    spread_pad: float = 0.05
    spread_young: float = 0.10
    spread_coupling: float = 0.03


def _draw(rng, value, spread):
    if spread <= 0:
        return float(value)
    return float(value) * max(0.2, 1.0 + spread * rng.standard_normal())


def synthesize_grasp(material: Material, spec: GraspSpec, rng: np.random.Generator,
                     lambda_B_nm: float = 1550.0) -> tuple[np.ndarray, dict]:
    """Strain-only shift ``(n_samples, n_gratings)`` in nm of one grasp, and its parameters.

    Sample ``j`` is at ``t = j / fs``. The finger touches at ``contact_ms`` and closes until the
    first grating reaches ``stop_nm``, then holds.
    """
    n = int(round(spec.duration_ms * spec.fs_hz / 1000.0))
    t_s = np.arange(n) / spec.fs_hz
    v = _draw(rng, spec.velocity_m_per_s, spec.spread_velocity)
    pad = Pad(_draw(rng, spec.pad.young_Pa, spec.spread_pad), spec.pad.area_m2,
              spec.pad.thickness_m, spec.pad.contact_length_m)
    mat = Material(material.name, _draw(rng, material.young_Pa, spec.spread_young),
                   material.poisson, material.diameter_m, material.height_m)
    k_obj = contact_stiffness(mat, pad.contact_length_m)
    k_eff = series_stiffness(pad.stiffness_N_per_m, k_obj)
    c = np.array([_draw(rng, x, spec.spread_coupling) for x in spec.coupling_microstrain_per_N])
    sens_nm_per_N = c * 1e-6 * float(bragg_shift_nm(1.0, 0.0, lambda_B_nm))   # nm per newton
    f_stop = spec.stop_nm / sens_nm_per_N.max()
    x_stop = f_stop / k_eff
    t_stop = spec.contact_ms / 1000.0 + x_stop / v
    travel = np.clip(v * (t_s - spec.contact_ms / 1000.0), 0.0, x_stop)
    force = k_eff * travel
    strain = force[:, None] * c[None, :] * 1e-6
    info = {"material": material.name, "velocity_m_per_s": v, "pad_young_Pa": pad.young_Pa,
            "object_young_Pa": mat.young_Pa, "k_pad_N_per_m": pad.stiffness_N_per_m,
            "k_object_N_per_m": k_obj, "k_eff_N_per_m": k_eff, "stop_force_N": f_stop,
            "loading_ms": 1000.0 * x_stop / v, "stop_ms": 1000.0 * t_stop,
            "coupling_microstrain_per_N": c.tolist(),
            "sensitivity_pm_per_microstrain": strain_sensitivity_pm_per_microstrain(lambda_B_nm)}
    return strain, info


@dataclass(frozen=True)
class SlideSpec:
    """A texture sliding under the pad (see the module docstring)."""

    speed_m_per_s: float = 0.02
    period_m: float = 2e-3
    depth_microstrain: float = 3.0
    normal_force_N: float = 0.5
    ramp_ms: float = 100.0
    coupling_microstrain_per_N: float = 10.0
    spacing_m: float = 2e-3
    n_gratings: int = 2
    duration_ms: float = 600.0
    fs_hz: float = 1000.0
    spread_speed: float = 0.05
    spread_force: float = 0.05


def synthesize_slide(spec: SlideSpec, rng: np.random.Generator,
                     period_m: float | None = None) -> tuple[np.ndarray, dict]:
    """Strain ``(n_samples, n_gratings)`` of a texture of ``period_m`` sliding under the pad."""
    n = int(round(spec.duration_ms * spec.fs_hz / 1000.0))
    t = np.arange(n) / spec.fs_hz
    s = _draw(rng, spec.speed_m_per_s, spec.spread_speed)
    fn = _draw(rng, spec.normal_force_N, spec.spread_force)
    per = float(period_m if period_m is not None else spec.period_m)
    load = fn * np.clip(t / (spec.ramp_ms / 1000.0), 0.0, 1.0)
    out = np.empty((n, spec.n_gratings))
    phase0 = rng.uniform(0, 2 * np.pi)
    for g in range(spec.n_gratings):
        pos = s * t - g * spec.spacing_m
        tex = 0.5 * (1 + np.sin(2 * np.pi * pos / per + phase0)) * (pos > 0)
        out[:, g] = (load * spec.coupling_microstrain_per_N
                     + spec.depth_microstrain * tex * (load / fn)) * 1e-6
    return out, {"speed_m_per_s": s, "normal_force_N": fn, "period_m": per,
                 "vibration_hz": s / per}


@dataclass(frozen=True)
class PulseSpec:
    """A rectangular normal-force pulse on the pad (linear rise and fall of ``edge_ms``),
    ``amplitude_N`` for ``width_ms`` from ``start_ms``; one coupling per grating."""

    start_ms: float = 50.0
    width_ms: float = 200.0
    edge_ms: float = 5.0
    coupling_microstrain_per_N: tuple = (2.0, 1.6)
    duration_ms: float = 400.0
    fs_hz: float = 1000.0
    spread_force: float = 0.05


def synthesize_pulse(spec: PulseSpec, rng: np.random.Generator,
                     amplitude_N: float) -> tuple[np.ndarray, dict]:
    """Strain ``(n_samples, n_gratings)`` of one force pulse of nominal ``amplitude_N``."""
    n = int(round(spec.duration_ms * spec.fs_hz / 1000.0))
    t = np.arange(n) * 1000.0 / spec.fs_hz
    amp = _draw(rng, amplitude_N, spec.spread_force)
    e = max(spec.edge_ms, 1e-9)
    rise = np.clip((t - spec.start_ms) / e, 0.0, 1.0)
    fall = np.clip((spec.start_ms + spec.width_ms - t) / e, 0.0, 1.0)
    force = amp * np.minimum(rise, fall)
    c = np.asarray(spec.coupling_microstrain_per_N, dtype=np.float64)
    return force[:, None] * c[None, :] * 1e-6, {"amplitude_N": amp}


# ------------------------------------------------------------------------------ effects
# Each effect: f(x (n, channels), p, rng, fs_hz, context) -> (new array, counts dict), its
# parameters ``p`` in the trace's own unit (nm for a grating's shift, V for a MEMS tether's
# output): :func:`sensor_effects` converts a scene's parameters (pm, mV, ...) with the sensor's
# table of units (:data:`EFFECT_UNITS`).

def _eff_temperature(x, p, rng, fs, ctx):
    t = np.arange(x.shape[0]) / fs
    dT = p["offset_K"] + p["drift_K_per_s"] * t
    shift = bragg_shift_nm(0.0, dT, ctx.get("lambda_B_nm", 1550.0))
    return x + shift[:, None], {"max_shift_nm": float(np.max(np.abs(shift)))}


def _eff_crosstalk(x, p, rng, fs, ctx):
    f = p["fraction"]
    if x.shape[1] < 2:
        return x, {}
    others = x.sum(axis=1, keepdims=True) - x
    return x + f * others / (x.shape[1] - 1), {}


def _eff_noise(x, p, rng, fs, ctx):
    return x + p["sigma"] * rng.standard_normal(x.shape), {}


def _eff_saturation(x, p, rng, fs, ctx):
    lo, hi = p["lo"], p["hi"]
    n = int(np.count_nonzero((x < lo) | (x > hi)))
    return np.clip(x, lo, hi), {"samples_clipped": n}


def _eff_resolution(x, p, rng, fs, ctx):
    return np.round(x / p["step"]) * p["step"], {}


def _eff_dropped(x, p, rng, fs, ctx):
    """The interrogator misses samples: they come back as NaN, for the loader/driver to see."""
    drop = rng.random(x.shape[0]) < p["probability"]
    drop[0] = False
    y = x.copy()
    y[drop, :] = np.nan
    return y, {"samples_dropped": int(drop.sum()),
               "first_dropped": int(np.flatnonzero(drop)[0]) if drop.any() else None}


#: Effect name -> function. Only the effects a scene lists are looked up here and called.
EFFECTS = {
    "temperature": _eff_temperature,
    "crosstalk": _eff_crosstalk,
    "noise": _eff_noise,
    "saturation": _eff_saturation,
    "resolution": _eff_resolution,
    "dropped_samples": _eff_dropped,
}
#: Physical order: optics (temperature, cross-talk), then the interrogator (noise, range,
#: resolution, dropped samples). ``strain`` is the mechanical term computed by the synthesizers.
EFFECT_ORDER = ("strain", "temperature", "crosstalk", "noise", "saturation", "resolution",
                "dropped_samples")
#: A grating's effect parameters as a scene gives them -> the effect functions' (in nm):
#: ``{effect: {parameter: (scene key, scale, default)}}``.
EFFECT_UNITS = {
    "temperature": {"offset_K": ("offset_K", 1.0, 0.0),
                    "drift_K_per_s": ("drift_K_per_s", 1.0, 0.0)},
    "crosstalk": {"fraction": ("fraction", 1.0, 0.02)},
    "noise": {"sigma": ("sigma_pm", 1e-3, 0.5)},
    "saturation": {"lo": ("min_nm", 1.0, -2.0), "hi": ("max_nm", 1.0, 2.0)},
    "resolution": {"step": ("step_pm", 1e-3, 1.0)},
    "dropped_samples": {"probability": ("probability", 1.0, 0.001)},
}


def apply_effects(strain, effects, params: dict, rng: np.random.Generator, fs_hz: float,
                  lambda_B_nm: float = 1550.0) -> Trace:
    """Turn strain into ``d_lambda`` (nm) and apply exactly the listed ``effects``.

    ``effects`` must contain ``"strain"``; every other name must be a key of :data:`EFFECTS`.
    ``params[name]`` holds the effect's parameters. The returned trace's ``effect_counts`` has
    one entry per effect applied, in the order applied.
    """
    effects = list(effects)
    if "strain" not in effects:
        raise ValueError("effects must include 'strain' (the mechanical term)")
    for e in effects:
        if e not in EFFECT_ORDER:
            raise ValueError(f"unknown effect {e!r}; known: {', '.join(EFFECT_ORDER)}")
    x = bragg_shift_nm(np.asarray(strain, dtype=np.float64), 0.0, lambda_B_nm)
    if x.ndim == 1:
        x = x[:, None]
    counts = {"strain": {"max_nm": float(np.max(np.abs(x)))}}
    x, more = sensor_effects(x, effects, params, rng, fs_hz, lambda_B_nm)
    return Trace(x, fs_hz, {}, counts | more)


def sensor_effects(d_lambda_nm, effects, params: dict, rng: np.random.Generator, fs_hz: float,
                   lambda_B_nm: float = 1550.0, units: dict = EFFECT_UNITS
                   ) -> tuple[np.ndarray, dict]:
    """Apply exactly the listed ``effects`` other than ``strain`` to a trace ``(n, channels)``
    that already holds the mechanical term (synthesized or recorded): a grating's shifts (nm)
    by default, or another sensor's outputs with that sensor's table of ``units`` (scene
    parameters -> the trace's unit, :data:`EFFECT_UNITS`). Returns the trace and one count
    entry per effect applied, in the order applied: the parameters as the scene gave them
    and what the effect counted."""
    for e in effects:
        if e not in EFFECT_ORDER:
            raise ValueError(f"unknown effect {e!r}; known: {', '.join(EFFECT_ORDER)}")
    x = np.asarray(d_lambda_nm, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    counts = {}
    ctx = {"lambda_B_nm": lambda_B_nm}
    for name in EFFECT_ORDER[1:]:
        if name in effects:
            given = params.get(name, {})
            scene = {key: float(given.get(key, default))
                     for key, _, default in units[name].values()}
            p = {k: scale * scene[key] for k, (key, scale, _) in units[name].items()}
            x, c = EFFECTS[name](x, p, rng, fs_hz, ctx)
            counts[name] = scene | c
    return x, counts
