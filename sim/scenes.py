"""Scene files: what a run simulates, in TOML (read with :mod:`tomllib`).

A scene names the sensor and the physical effects to model, the stimulus, the host front end,
the neuron populations and their projections, the decoder, the hardware configuration, the
engines to run, and the trials and seeds. :func:`load_scene` validates a file against
:data:`SCHEMA` and returns a :class:`Scene` (plain dictionaries with every default filled in);
any problem raises :class:`SceneError` naming the file, the dotted key and the reason (unknown
key, wrong type, missing unit, out of range, not available in this build).

Quantities carry their unit in the key name (``duration_ms``, ``velocity_mm_per_s``,
``young_MPa``); a key given without its unit (``duration = 700``) is refused with the keys that
would be accepted. The embedded default scene (:data:`DEFAULT_SCENE_TOML`) is the four-material
grasp; more scenes ship in ``cuneate.sim.examples`` (:func:`example_path`).
See docs/scenes.md for the full reference.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

__all__ = ["SceneError", "Scene", "load_scene", "parse_scene", "default_scene", "SCHEMA",
           "DEFAULT_SCENE_TOML", "EFFECT_NAMES", "ENGINE_NAMES", "MODELS", "AVAILABLE_MODELS",
           "example_path", "example_names"]

EFFECT_NAMES = ("strain", "temperature", "noise", "resolution", "saturation",
                "dropped_samples", "crosstalk")
ENGINE_NAMES = ("golden", "fixed", "amaranth", "icarus", "verilator")
#: Neuron models a scene may name, and those this build can simulate.
MODELS = ("izhikevich", "lif", "cuneate")
AVAILABLE_MODELS = ("izhikevich", "lif", "cuneate")
STIMULUS_KINDS = ("grasp", "slide", "pulses", "recorded", "press", "ridges")
AVAILABLE_STIMULI = STIMULUS_KINDS


class SceneError(ValueError):
    """A scene is invalid; the message is one line: ``file: key: reason``."""


@dataclass(frozen=True)
class F:
    """One key of the schema: type, default, bounds, choices."""

    type: type | tuple
    default: object = None
    required: bool = False
    lo: float | None = None
    hi: float | None = None
    choices: tuple | None = None
    items: type | tuple | None = None       # element type of lists
    doc: str = ""


NUM = (int, float)
_EFFECT_PARAMS = {
    "temperature": {"offset_K": F(NUM, 0.0), "drift_K_per_s": F(NUM, 0.0, lo=-100, hi=100)},
    "noise": {"sigma_pm": F(NUM, 0.5, lo=0, hi=1e4)},
    "resolution": {"step_pm": F(NUM, 1.0, lo=1e-6, hi=1e4)},
    "saturation": {"min_nm": F(NUM, -2.0), "max_nm": F(NUM, 2.0)},
    "dropped_samples": {"probability": F(NUM, 0.001, lo=0, hi=0.5)},
    "crosstalk": {"fraction": F(NUM, 0.02, lo=0, hi=1)},
}

SCHEMA: dict = {
    "scene": {"name": F(str, "scene"), "description": F(str, ""),
              "duration_ms": F(NUM, 700.0, lo=1, hi=600_000),
              "trials": F(int, 10, lo=1, hi=10_000), "seed": F(int, 1, lo=0)},
    "sensor": {"kind": F(str, "fbg", choices=("fbg", "taxels")),
               "channels": F(int, 2, lo=1, hi=1024),
               "grid": F(list, None, items=int),
               "sample_rate_hz": F(NUM, 1000.0, lo=1, hi=1e6),
               "lambda_B_nm": F(NUM, 1550.0, lo=100, hi=5000),
               "effects": F(list, ["strain"], items=str),
               **{e: F(dict, {}) for e in _EFFECT_PARAMS}},
    "stimulus": {"kind": F(str, "grasp", choices=STIMULUS_KINDS),
                 # grasp
                 "velocity_mm_per_s": F(NUM, 1.5, lo=1e-3, hi=1e3),
                 "stop_nm": F(NUM, 0.01, lo=1e-6, hi=10),
                 "contact_ms": F(NUM, 50.0, lo=0),
                 "coupling_microstrain_per_N": F(list, [2.0, 1.6], items=NUM),
                 "pad_young_MPa": F(NUM, 1.0, lo=1e-4, hi=1e6),
                 "pad_area_mm2": F(NUM, 225.0, lo=1e-3, hi=1e6),
                 "pad_thickness_mm": F(NUM, 3.0, lo=1e-3, hi=1e3),
                 "contact_length_mm": F(NUM, 15.0, lo=1e-3, hi=1e3),
                 "materials": F(list, ["dragon_skin", "vytaflex", "abs", "aluminium"],
                                items=(str, dict)),
                 "spread_velocity": F(NUM, 0.05, lo=0, hi=1),
                 "spread_pad": F(NUM, 0.05, lo=0, hi=1),
                 "spread_young": F(NUM, 0.10, lo=0, hi=1),
                 "spread_coupling": F(NUM, 0.03, lo=0, hi=1),
                 # slide
                 "speed_mm_per_s": F(NUM, 20.0, lo=1e-3, hi=1e4),
                 "periods_mm": F(list, [1.0, 2.0, 4.0], items=NUM),
                 "depth_microstrain": F(NUM, 3.0, lo=0, hi=1e4),
                 "normal_force_N": F(NUM, 0.5, lo=1e-6, hi=1e4),
                 "ramp_ms": F(NUM, 100.0, lo=1e-3),
                 "slide_coupling_microstrain_per_N": F(NUM, 10.0, lo=0, hi=1e6),
                 "spacing_mm": F(NUM, 2.0, lo=0, hi=1e3),
                 "spread_speed": F(NUM, 0.05, lo=0, hi=1),
                 "spread_force": F(NUM, 0.05, lo=0, hi=1),
                 # pulses (classes: amplitudes)
                 "pulse_amplitudes_N": F(list, [0.5, 1.0, 2.0], items=NUM),
                 "pulse_start_ms": F(NUM, 50.0, lo=0), "pulse_width_ms": F(NUM, 200.0, lo=1e-3),
                 "pulse_edge_ms": F(NUM, 5.0, lo=0),
                 # recorded
                 "file": F(str, ""), "time_key": F(str, "Time"),
                 "data_key": F(str, "DeltaBraggW"), "struct": F(str, ""),
                 "time_unit": F(str, "s", choices=("s", "ms")),
                 "shift_unit": F(str, "nm", choices=("nm", "pm")),
                 "label": F(str, "recorded"),
                 # press (taxel skin): pulses of growing width, then of growing amplitude
                 "press_taxel": F(int, 4, lo=0),
                 "press_widths_ms": F(list, [20.0, 40.0, 80.0], items=NUM),
                 "press_amplitudes_N": F(list, [1.0, 1.5, 2.0], items=NUM),
                 "press_base_amplitude_N": F(NUM, 1.0, lo=1e-6, hi=1e4),
                 "press_base_width_ms": F(NUM, 40.0, lo=1e-3, hi=1e5),
                 "press_gap_ms": F(NUM, 60.0, lo=1e-3, hi=1e5),
                 "press_spread": F(list, [0.5, 0.25], items=NUM),
                 # ridges (two stacked sensors, cuneate neurons)
                 "ridge_angles_deg": F(list, [-45.0, 0.0, 45.0], items=NUM),
                 "ridge_width_mm": F(NUM, 0.2, lo=1e-3, hi=100),
                 "sensor_spacing_mm": F(NUM, 0.25, lo=1e-3, hi=100),
                 "jitter_ms": F(NUM, 0.3, lo=0, hi=100),
                 "trial_ms": F(NUM, 120.0, lo=1, hi=1e4),
                 "onset_ms": F(NUM, 30.0, lo=0, hi=1e4)},
    "frontend": {"filter_low_hz": F(NUM, 1.0, lo=1e-6), "filter_high_hz": F(NUM, 16.0, lo=1e-6),
                 "filter_order": F(int, 1, lo=1, hi=8),
                 "filter_kind": F(str, "butter",
                                  choices=("butter", "bessel", "cheby1", "cheby2", "ellip")),
                 "filter_b": F(list, None, items=NUM), "filter_a": F(list, None, items=NUM),
                 "gain_S": F(NUM, 180.0, lo=-1e9, hi=1e9),
                 "delta_lambda_unit_pm": F(NUM, 10.0, lo=1e-6, hi=1e9),
                 "sa_gain": F(NUM, 12500.0, lo=-1e12, hi=1e12),
                 "sa_threshold_pm": F(NUM, 0.0),
                 "sa_unit_pm": F(NUM, 1000.0, lo=1e-6, hi=1e9),
                 "fa_rectify": F(str, "positive", choices=("positive", "abs", "none")),
                 "latency_ticks": F(int, 0, lo=0, hi=1_000_000),
                 "window": F(str, "none", choices=("none", "loading")),
                 # force encoding of a taxel skin: I = offset + gain * force
                 "force_offset_mV": F(NUM, 5.0, lo=-1e4, hi=1e4),
                 "force_gain_mV_per_N": F(NUM, 20.0, lo=-1e4, hi=1e4)},
    "hardware": {"clock_hz": F(NUM, 40e6, lo=1e3, hi=1e9),
                 "update_hz": F(NUM, 16000.0, lo=1, hi=1e7),
                 "current_int_bits": F(int, 10, lo=1, hi=30),
                 "current_frac_bits": F(int, 8, lo=0, hi=30),
                 "rounding": F(str, "nearest", choices=("nearest", "truncate"))},
    "decoder": {"kind": F(str, "tree", choices=("tree", "knn", "winner", "pattern", "none")),
                "target": F(str, "material"),
                "features": F(str, "isi", choices=("isi", "trial")),
                "cv_folds": F(int, 50, lo=2, hi=10_000), "max_depth": F(int, 3, lo=1, hi=64),
                "neighbours": F(int, 3, lo=1, hi=1000),
                "window_ms": F(list, None, items=NUM),
                "tolerance": F(NUM, 0.10, lo=0, hi=1)},
    "run": {"engines": F(list, ["golden", "fixed", "verilator"], items=str)},
}
POPULATION = {"name": F(str, required=True), "model": F(str, "izhikevich", choices=MODELS),
              "preset": F(str, None), "size": F(int, None, lo=1, hi=1_000_000),
              "encoding": F(str, None, choices=("FA", "SA", "force", "spikes")),
              "gratings": F(list, None, items=int),
              "inputs": F(list, [], items=str),
              "gain": F(NUM, None)}
PROJECTION = {"source": F(str, required=True), "target": F(str, required=True),
              "delays_ms": F(list, [0.0], items=NUM), "weight": F(NUM, 1.0),
              "psp": F(str, "biexp", choices=("biexp", "exp", "delta"))}

_UNIT_KEYS = {}
for _sec, _keys in SCHEMA.items():
    for _k in _keys:
        for suffix in ("_ms", "_hz", "_nm", "_pm", "_mm", "_mm2", "_MPa", "_N", "_K",
                       "_mm_per_s", "_microstrain_per_N", "_microstrain", "_K_per_s",
                       "_ticks", "_mV", "_mV_per_N"):
            if _k.endswith(suffix):
                _UNIT_KEYS.setdefault((_sec, _k[: -len(suffix)]), []).append(_k)


DEFAULT_SCENE_TOML = """\
# The four-material grasp: a two-grating finger closes on cylinders of Dragon Skin, Vytaflex,
# ABS and aluminium until the first grating shifts by 0.01 nm; fast-adapting Izhikevich RS
# neurons on the 40 MHz / 16 kHz core encode the filtered shift; stiffness (the material) is
# decoded from inter-spike intervals with a coarse decision tree and cross-validation.
[scene]
name = "four-material grasp"
duration_ms = 700
trials = 10
seed = 1

[sensor]
kind = "fbg"
channels = 2
sample_rate_hz = 1000
effects = ["strain"]

[stimulus]
kind = "grasp"
materials = ["dragon_skin", "vytaflex", "abs", "aluminium"]
velocity_mm_per_s = 1.5
stop_nm = 0.01

[frontend]
filter_low_hz = 1
filter_high_hz = 16
gain_S = 180
delta_lambda_unit_pm = 10
window = "loading"

[[population]]
name = "fa"
model = "izhikevich"
preset = "RS"
encoding = "FA"

[hardware]
clock_hz = 40e6
update_hz = 16000

[decoder]
kind = "tree"
features = "isi"
cv_folds = 50
max_depth = 3

[run]
engines = ["golden", "fixed", "verilator"]
"""


@dataclass
class Scene:
    """A validated scene: one dictionary per section (defaults filled), populations and
    projections as lists of dictionaries, and where it came from."""

    source: str
    sections: dict
    populations: list
    projections: list
    base_dir: Path | None = None

    def __getitem__(self, key):
        return self.sections[key]

    @property
    def name(self) -> str:
        return self.sections["scene"]["name"]

    @property
    def engines(self) -> list[str]:
        return list(self.sections["run"]["engines"])

    @property
    def effects(self) -> list[str]:
        return list(self.sections["sensor"]["effects"])

    def classes(self) -> list[str]:
        st = self.sections["stimulus"]
        if st["kind"] == "grasp":
            return [m if isinstance(m, str) else m["name"] for m in st["materials"]]
        if st["kind"] == "slide":
            return [f"{p:g} mm" for p in st["periods_mm"]]
        if st["kind"] == "pulses":
            return [f"{a:g} N" for a in st["pulse_amplitudes_N"]]
        if st["kind"] == "ridges":
            return [f"{a:+g} deg" for a in st["ridge_angles_deg"]]
        if st["kind"] == "press":
            return [f"taxel {st['press_taxel']}"]
        return [st["label"]]

    def to_dict(self) -> dict:
        return copy.deepcopy(self.sections) | {"population": copy.deepcopy(self.populations),
                                                "projection": copy.deepcopy(self.projections)}


def _tname(t) -> str:
    if isinstance(t, tuple):
        return " or ".join(_tname(x) for x in t)
    return {int: "integer", float: "number", str: "string", list: "array", dict: "table",
            bool: "boolean"}.get(t, t.__name__)


def _type_ok(value, t) -> bool:
    ts = t if isinstance(t, tuple) else (t,)
    if isinstance(value, bool):
        return bool in ts
    if float in ts and isinstance(value, int):
        return True
    return isinstance(value, ts)


class _V:
    def __init__(self, src: str):
        self.src = src

    def err(self, key: str, reason: str):
        raise SceneError(f"{self.src}: {key}: {reason}")

    def value(self, key: str, v, f: F):
        if not _type_ok(v, f.type):
            self.err(key, f"wrong type: expected {_tname(f.type)}, got {_tname(type(v))} "
                          f"({v!r})")
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            if v != v or v in (float("inf"), float("-inf")):
                self.err(key, f"must be finite, got {v!r}")
            if f.lo is not None and v < f.lo:
                self.err(key, f"out of range: {v!r} < {f.lo:g}")
            if f.hi is not None and v > f.hi:
                self.err(key, f"out of range: {v!r} > {f.hi:g}")
            if f.type is float or f.type == NUM:
                v = float(v)
        if f.choices is not None and v not in f.choices:
            self.err(key, f"must be one of {', '.join(map(str, f.choices))}, got {v!r}")
        if isinstance(v, list) and f.items is not None:
            if not v and f.required:
                self.err(key, "must not be empty")
            for i, x in enumerate(v):
                if not _type_ok(x, f.items):
                    self.err(f"{key}[{i}]", f"wrong type: expected {_tname(f.items)}, got "
                                            f"{_tname(type(x))} ({x!r})")
                if isinstance(x, float) and (x != x or abs(x) == float("inf")):
                    self.err(f"{key}[{i}]", f"must be finite, got {x!r}")
        return v

    def table(self, prefix: str, data: dict, schema: dict, section: str | None = None) -> dict:
        if not isinstance(data, dict):
            self.err(prefix, f"wrong type: expected a table, got {_tname(type(data))}")
        out = {}
        for k, v in data.items():
            key = f"{prefix}.{k}"
            if k not in schema:
                cand = _UNIT_KEYS.get((section, k)) if section else None
                if cand:
                    self.err(key, f"missing unit: write {' or '.join(cand)}")
                close = [s for s in schema if s.lower().startswith(k.lower()[:4])]
                hint = f" (did you mean {', '.join(close[:3])}?)" if close else ""
                self.err(key, f"unknown key{hint}")
            out[k] = self.value(key, v, schema[k])
        for k, f in schema.items():
            if k not in out:
                if f.required:
                    self.err(f"{prefix}.{k}", "missing required key")
                out[k] = copy.deepcopy(f.default)
        return out


def parse_scene(text: str, source: str = "<scene>", base_dir: Path | None = None) -> Scene:
    """Validate TOML ``text``; errors name ``source``."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: not valid TOML: {exc}") from None
    V = _V(source)
    sections = {}
    for k in raw:
        if k not in SCHEMA and k not in ("population", "projection"):
            V.err(k, f"unknown section (known: {', '.join([*SCHEMA, 'population', 'projection'])})")
    for sec, schema in SCHEMA.items():
        sections[sec] = V.table(sec, raw.get(sec, {}), schema, sec)
    sensor = sections["sensor"]
    taxels = sensor["kind"] == "taxels"
    if taxels:
        # a taxel skin reads force directly: none of the optical effects of a grating apply
        if raw.get("sensor", {}).get("effects"):
            V.err("sensor.effects", "FBG effects do not apply to a taxel sensor (leave the list "
                                    "empty or out)")
        sensor["effects"] = []
    elif sensor["grid"] is not None:
        V.err("sensor.grid", "a grid needs sensor.kind = \"taxels\"")
    for i, e in enumerate(sensor["effects"]):
        if e not in EFFECT_NAMES:
            V.err(f"sensor.effects[{i}]", f"unknown effect {e!r} (known: "
                                          f"{', '.join(EFFECT_NAMES)})")
    if not taxels and "strain" not in sensor["effects"]:
        V.err("sensor.effects", "must include 'strain' (the mechanical term every trace has)")
    if len(set(sensor["effects"])) != len(sensor["effects"]):
        V.err("sensor.effects", "lists an effect twice")
    for e, params in _EFFECT_PARAMS.items():
        given = raw.get("sensor", {}).get(e)
        if given is not None and e not in sensor["effects"]:
            V.err(f"sensor.{e}", f"parameters given for effect {e!r}, which sensor.effects "
                                 f"does not list (it would not be computed)")
        sensor[e] = V.table(f"sensor.{e}", given or {}, params) if e in sensor["effects"] \
            else {}
    st = sections["stimulus"]
    if st["kind"] not in AVAILABLE_STIMULI:
        V.err("stimulus.kind", f"{st['kind']!r} stimuli are not available in this build "
                               f"(available: {', '.join(AVAILABLE_STIMULI)})")
    if st["kind"] == "grasp":
        from ..golden.tactile import MATERIALS
        if not st["materials"]:
            V.err("stimulus.materials", "must not be empty")
        mats = []
        for i, m in enumerate(st["materials"]):
            if isinstance(m, str):
                if m not in MATERIALS:
                    V.err(f"stimulus.materials[{i}]", f"unknown material {m!r} (known: "
                          f"{', '.join(MATERIALS)}; or give a table with name, young_MPa)")
                mats.append(m)
            else:
                mats.append(V.table(f"stimulus.materials[{i}]", m, {
                    "name": F(str, required=True), "young_MPa": F(NUM, required=True, lo=1e-6,
                                                                  hi=1e7),
                    "poisson": F(NUM, 0.4, lo=0, hi=0.499),
                    "diameter_mm": F(NUM, 30.0, lo=1e-3, hi=1e4),
                    "height_mm": F(NUM, 150.0, lo=1e-3, hi=1e5)}))
        names = [m if isinstance(m, str) else m["name"] for m in mats]
        if len(set(names)) != len(names):
            V.err("stimulus.materials", "names a material twice")
        st["materials"] = mats
        if len(st["coupling_microstrain_per_N"]) != sensor["channels"]:
            V.err("stimulus.coupling_microstrain_per_N",
                  f"needs one value per channel ({sensor['channels']}), got "
                  f"{len(st['coupling_microstrain_per_N'])}")
        if any(c <= 0 for c in st["coupling_microstrain_per_N"]):
            V.err("stimulus.coupling_microstrain_per_N", "out of range: values must be > 0")
    if sections["frontend"]["window"] == "loading" and st["kind"] != "grasp":
        V.err("frontend.window", "'loading' needs a grasp stimulus (it has a loading phase)")
    if st["kind"] == "pulses":
        if not st["pulse_amplitudes_N"] or any(a <= 0 for a in st["pulse_amplitudes_N"]):
            V.err("stimulus.pulse_amplitudes_N", "must list amplitudes > 0")
        if len(st["coupling_microstrain_per_N"]) != sensor["channels"]:
            V.err("stimulus.coupling_microstrain_per_N",
                  f"needs one value per channel ({sensor['channels']}), got "
                  f"{len(st['coupling_microstrain_per_N'])}")
    if st["kind"] == "slide" and (not st["periods_mm"] or any(p <= 0 for p in st["periods_mm"])):
        V.err("stimulus.periods_mm", "must list periods > 0")
    if st["kind"] == "recorded":
        if not st["file"]:
            V.err("stimulus.file", "missing required key for a recorded stimulus")
        p = Path(st["file"])
        if not p.is_absolute() and base_dir is not None:
            p = base_dir / p
        st["file"] = str(p)
    fe = sections["frontend"]
    if (fe["filter_b"] is None) != (fe["filter_a"] is None):
        V.err("frontend.filter_a" if fe["filter_a"] is None else "frontend.filter_b",
              "filter coefficients need both filter_b and filter_a")
    if fe["filter_b"] is not None:
        from ..golden.fbg import IIRFilter
        try:
            rep = IIRFilter(b=fe["filter_b"], a=fe["filter_a"]).check()
        except ValueError as exc:
            V.err("frontend.filter_a", str(exc))
        if not rep.stable:
            V.err("frontend.filter_a", f"unstable filter: {rep.message}")
    fs = sensor["sample_rate_hz"]
    if not taxels and fe["filter_b"] is None and \
            not 0 < fe["filter_low_hz"] < fe["filter_high_hz"] < fs / 2:
        V.err("frontend.filter_high_hz", f"band edges must satisfy 0 < filter_low_hz < "
                                         f"filter_high_hz < sample_rate_hz/2 = {fs / 2:g}")
    hw = sections["hardware"]
    ratio = hw["update_hz"] / fs
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        V.err("hardware.update_hz", f"must be a whole multiple of sensor.sample_rate_hz "
                                    f"({fs:g}): each sample is held for a whole number of "
                                    f"ticks, got ratio {ratio:g}")
    if hw["clock_hz"] / hw["update_hz"] < 1:
        V.err("hardware.clock_hz", "must be >= update_hz")
    for i, e in enumerate(sections["run"]["engines"]):
        if e not in ENGINE_NAMES:
            V.err(f"run.engines[{i}]", f"unknown engine {e!r} (known: {', '.join(ENGINE_NAMES)})")
    if not sections["run"]["engines"]:
        V.err("run.engines", "must name at least one engine")
    if len(set(sections["run"]["engines"])) != len(sections["run"]["engines"]):
        V.err("run.engines", "names an engine twice")
    dec = sections["decoder"]
    if dec["window_ms"] is not None and (len(dec["window_ms"]) != 2
                                         or not dec["window_ms"][0] < dec["window_ms"][1]):
        V.err("decoder.window_ms", "must be [start, end] with start < end")
    # populations and projections
    pops_raw = raw.get("population", [])
    for key in ("population", "projection"):
        if isinstance(raw.get(key), dict):
            V.err(key, f"wrong type: write [[{key}]] (an array of tables), not [{key}]")
    if not isinstance(pops_raw, list) or not pops_raw:
        V.err("population", "at least one [[population]] table is required")
    pops = []
    for i, p in enumerate(pops_raw):
        pops.append(V.table(f"population[{i}]", p, POPULATION))
        if pops[-1]["preset"] is None and pops[-1]["model"] == "izhikevich":
            pops[-1]["preset"] = "RS"
    ridges = st["kind"] == "ridges"
    projs = []
    if ridges:
        from .scene_ridge import validate_ridge
        projs = _projections(V, raw, [p["name"] for p in pops])
        validate_ridge(V, raw, sections, pops, projs)
    elif taxels or st["kind"] == "press":
        from .scene_skin import validate_skin
        validate_skin(V, raw, sections, pops)
    for i, p in enumerate(pops):
        if p["encoding"] is None:
            p["encoding"] = "FA"
        if not taxels and p["model"] == "lif":
            V.err(f"population[{i}].model", "LIF populations run on a taxel skin in this build "
                                            "(sensor.kind = \"taxels\", stimulus.kind = "
                                            "\"press\")")
        if not taxels and p["encoding"] == "force":
            V.err(f"population[{i}].encoding", "force encoding needs sensor.kind = \"taxels\"")
    names = [p["name"] for p in pops]
    for i, p in enumerate(pops):
        key = f"population[{i}]"
        if names.count(p["name"]) > 1:
            V.err(f"{key}.name", f"duplicate population name {p['name']!r}")
        for j, src in enumerate(p["inputs"]):
            if src not in names or src == p["name"]:
                V.err(f"{key}.inputs[{j}]", f"unknown source population {src!r}")
        if p["model"] == "izhikevich":
            from ..golden.izhikevich import to_params
            try:
                to_params(p["preset"])
            except ValueError as exc:
                V.err(f"{key}.preset", str(exc))
        if p["encoding"] == "spikes" and not p["inputs"]:
            V.err(f"{key}.inputs", "a population driven by spikes needs inputs")
        if p["encoding"] != "spikes":
            g = p["gratings"] if p["gratings"] is not None else list(range(sensor["channels"]))
            for j, x in enumerate(g):
                if not 0 <= x < sensor["channels"]:
                    V.err(f"{key}.gratings[{j}]", f"out of range: grating {x} (the sensor has "
                                                  f"{sensor['channels']} channels)")
            p["gratings"] = g
            if p["size"] is not None and p["size"] != len(g):
                V.err(f"{key}.size", f"a sensor-driven population has one neuron per grating "
                                     f"({len(g)}), got {p['size']}")
            p["size"] = len(g)
        elif p["size"] is None:
            V.err(f"{key}.size", "missing required key for a spike-driven population")
    if not ridges:
        projs = _projections(V, raw, names)
    # only what this build can simulate
    for i, p in enumerate(pops):
        if p["model"] == "cuneate" and not ridges:
            V.err(f"population[{i}].model", "cuneate populations run in ridge scenes in this "
                                            "build (stimulus.kind = \"ridges\")")
        if p["model"] not in AVAILABLE_MODELS:
            V.err(f"population[{i}].model", f"{p['model']!r} blocks are not available in this "
                                            f"build (available: {', '.join(AVAILABLE_MODELS)})")
    if projs and not ridges:
        V.err("projection[0]", "projections (coincidence delays) run in ridge scenes in this "
                               "build (stimulus.kind = \"ridges\")")
    scene = Scene(source, sections, pops, projs, base_dir)
    n_trials = 1 if st["kind"] == "recorded" else sections["scene"]["trials"] * len(
        scene.classes())
    need = n_trials * sum(p["size"] for p in pops if p["model"] == "izhikevich")
    capacity = int(hw["clock_hz"] // hw["update_hz"])
    if need > capacity:
        V.err("hardware.clock_hz", f"the scene needs {need} Izhikevich neurons ({n_trials} "
                                   f"trials) but one core at {hw['clock_hz']:g} Hz / "
                                   f"{hw['update_hz']:g} Hz holds {capacity}")
    return scene


def _projections(V, raw: dict, names: list) -> list:
    projs = []
    for i, pr in enumerate(raw.get("projection", [])):
        q = V.table(f"projection[{i}]", pr, PROJECTION)
        for end in ("source", "target"):
            if q[end] not in names:
                V.err(f"projection[{i}].{end}", f"unknown population {q[end]!r}")
        if any(d < 0 for d in q["delays_ms"]):
            V.err(f"projection[{i}].delays_ms", "out of range: delays must be >= 0")
        projs.append(q)
    return projs


def load_scene(path) -> Scene:
    """Read and validate a scene file (errors name the file)."""
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise SceneError(f"{p}: cannot read scene: {exc.strerror or exc}") from None
    return parse_scene(text, str(p), p.parent)


def default_scene() -> Scene:
    """The embedded default scene (the four-material grasp)."""
    return parse_scene(DEFAULT_SCENE_TOML, "<default scene>")


def example_names() -> list[str]:
    """Names of the example scenes shipped with the package."""
    root = resources.files("cuneate.sim.examples")
    return sorted(p.name for p in root.iterdir() if p.name.endswith(".toml"))


def example_path(name: str) -> Path | None:
    """The shipped example ``name`` (``examples/NAME.toml``, ``NAME.toml`` or ``NAME``)."""
    n = Path(name).name
    if not n.endswith(".toml"):
        n += ".toml"
    p = Path(str(resources.files("cuneate.sim.examples") / n))
    return p if p.is_file() else None
