"""The scene schema: every section and key a scene may have, with its type, default, bounds and
choices, and the validator that checks a table against it.

Quantities carry their unit in the key name (``duration_ms``, ``velocity_mm_per_s``,
``young_MPa``); a key given without its unit (``duration = 700``) is refused with the keys that
would be accepted. See :mod:`cuneate.sim.scenes.scene` for parsing whole scenes and
docs/scenes.md for the full reference.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

__all__ = ["SceneError", "F", "NUM", "SCHEMA", "POPULATION", "PROJECTION", "EFFECT_NAMES",
           "EFFECT_PARAMS", "MEMS_EFFECT_PARAMS", "MODELS", "STIMULUS_KINDS", "UNIT_KEYS",
           "RECORDING", "Validator"]

EFFECT_NAMES = ("strain", "temperature", "noise", "resolution", "saturation",
                "dropped_samples", "crosstalk")
#: Neuron models a scene may name (``cuneate`` is the coincidence block's cuneate neurons).
MODELS = ("izhikevich", "lif", "cuneate")
STIMULUS_KINDS = ("grasp", "slide", "pulses", "recorded", "press", "ridges", "textures",
                  "learning")


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
    #: the longest text a string key (or a list's string item) takes: names and labels title
    #: figures and pages, whose layout grows with them (a 100 000-character label took the
    #: figure layout past 2 GB); paths and descriptions are longer
    max_len: int = 200


NUM = (int, float)
EFFECT_PARAMS = {
    "temperature": {"offset_K": F(NUM, 0.0), "drift_K_per_s": F(NUM, 0.0, lo=-100, hi=100)},
    "noise": {"sigma_pm": F(NUM, 0.5, lo=0, hi=1e4)},
    "resolution": {"step_pm": F(NUM, 1.0, lo=1e-6, hi=1e4)},
    "saturation": {"min_nm": F(NUM, -2.0), "max_nm": F(NUM, 2.0)},
    "dropped_samples": {"probability": F(NUM, 0.001, lo=0, hi=0.5)},
    "crosstalk": {"fraction": F(NUM, 0.02, lo=0, hi=1)},
}
#: A MEMS fingertip's effects and their parameters (mV of a tether's output; no strain or
#: temperature term: :mod:`cuneate.golden.mems`).
MEMS_EFFECT_PARAMS = {
    "noise": {"sigma_mV": F(NUM, 0.01, lo=0, hi=1e3)},
    "resolution": {"step_mV": F(NUM, 0.005, lo=1e-9, hi=1e3)},
    "saturation": {"min_mV": F(NUM, -50.0), "max_mV": F(NUM, 50.0)},
    "dropped_samples": {"probability": F(NUM, 0.001, lo=0, hi=0.5)},
    "crosstalk": {"fraction": F(NUM, 0.02, lo=0, hi=1)},
}

SCHEMA: dict = {
    "scene": {"name": F(str, "scene"), "description": F(str, "", max_len=4000),
              "duration_ms": F(NUM, 700.0, lo=1, hi=600_000),
              "trials": F(int, 10, lo=1, hi=10_000), "seed": F(int, 1, lo=0, hi=2**32 - 1)},
    "sensor": {"kind": F(str, "fbg", choices=("fbg", "taxels", "mems")),
               "channels": F(int, 2, lo=1, hi=1024),
               "grid": F(list, None, items=int),
               "sample_rate_hz": F(NUM, 1000.0, lo=1, hi=1e6),
               "lambda_B_nm": F(NUM, 1550.0, lo=100, hi=5000),
               "effects": F(list, ["strain"], items=str),
               **{e: F(dict, {}) for e in EFFECT_PARAMS}},
    # a texture scene's grid of sensing conditions: one run per force x velocity
    "grid": {"forces_mN": F(list, None, items=NUM),
             "velocities_mm_per_s": F(list, None, items=NUM),
             "scheduler": F(str, ""), "workers": F(int, 2, lo=1, hi=256)},
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
                 "file": F(str, "", max_len=4096), "time_key": F(str, "Time"),
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
                 "onset_ms": F(NUM, 30.0, lo=0, hi=1e4),
                 # textures (MEMS fingertip): the platform's protocol and the specimens
                 "textures": F(list, None, items=(str, dict)),
                 "texture_seed": F(int, 1, lo=0, hi=2**32 - 1),
                 "force_mN": F(NUM, 400.0, lo=1, hi=1e5),
                 "slide_mm": F(NUM, 12.0, lo=0.1, hi=1e3),
                 "rest_ms": F(NUM, 50.0, lo=0, hi=1e5),
                 "indent_ms": F(NUM, 200.0, lo=1, hi=1e5),
                 "hold_ms": F(NUM, 100.0, lo=0, hi=1e5),
                 "retract_ms": F(NUM, 150.0, lo=1, hi=1e5),
                 "spread_friction": F(NUM, 0.02, lo=0, hi=1),
                 "jitter_mm": F(NUM, 0.05, lo=0, hi=10),
                 # recorded MEMS traces: one table per trial, and the outputs' unit
                 "recordings": F(list, [], items=dict),
                 "signal_unit": F(str, "V", choices=("V", "mV"))},
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
                 # a MEMS fingertip's SA threshold S_th on the opponent difference
                 "sa_threshold_mV": F(NUM, 0.1, lo=0, hi=1e4),
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
                 "rounding": F(str, "nearest", choices=("nearest", "truncate")),
                 "fanout": F(bool, False),
                 "fanout_sample_bits": F(int, 16, lo=4, hi=32),
                 # trials a board built for the scene holds at once (None: every trial)
                 "board_trials": F(int, None, lo=1, hi=1_000_000)},
    "decoder": {"kind": F(str, "tree", choices=("tree", "knn", "winner", "pattern", "vp",
                                                 "none")),
                "target": F(str, "material"),
                "features": F(str, "isi", choices=("isi", "trial")),
                "cv_folds": F(int, 50, lo=2, hi=10_000), "max_depth": F(int, 3, lo=1, hi=64),
                "neighbours": F(int, 3, lo=1, hi=1000),
                "window_ms": F(list, None, items=NUM),
                "decision": F(str, "soft", choices=("soft", "majority")),
                "permutations": F(int, 0, lo=0, hi=10_000),
                "tolerance": F(NUM, 0.10, lo=0, hi=1),
                # the population decoded ("": every afferent; or an afferent population, or
                # the cuneate layer)
                "population": F(str, ""),
                # texture scenes (kind "vp"): the Victor-Purpura cost, in time and in space
                "q_per_s": F(NUM, 5.0, lo=0, hi=1e6),
                "q_per_mm": F(NUM, None, lo=0, hi=1e6)},
    # a learning scene (stimulus.kind = "learning"): the thesis's protocol and the layer
    "learning": {"presentations": F(int, 300, lo=1, hi=100_000),
                 "test_presentations": F(int, 40, lo=2, hi=10_000),
                 "jitter_ms": F(NUM, 5.0, lo=0, hi=1e3),
                 "window_ms": F(list, [200.0, 700.0], items=NUM),
                 "gap_ms": F(NUM, 50.0, lo=0, hi=1e4),
                 "order_seed": F(int, 2, lo=0, hi=2**32 - 1),
                 "anatomy_seed": F(int, 3, lo=0, hi=2**32 - 1),
                 "afferent_gains": F(list, [0.5, 0.7, 1.0, 1.4, 2.0], items=NUM),
                 "cns": F(int, 16, lo=1, hi=4096),
                 "synapses_per_cn": F(int, 20, lo=1, hi=4096),
                 "initial_weight_max": F(NUM, 3.6, lo=0, hi=1e3),
                 "cn_preset": F(str, "RS"),
                 "update_hz": F(NUM, 2000.0, lo=10, hi=1e6),
                 "tau_syn_ms": F(NUM, 6.4, lo=1e-3, hi=1e4),
                 "g_inh": F(NUM, 0.3, lo=0, hi=1e3),
                 "current_limit": F(NUM, 64.0, lo=1e-3, hi=1e4),
                 "tau_rise_ms": F(NUM, 4.0, lo=1e-3, hi=1e4),
                 "tau_decay_ms": F(NUM, 12.5, lo=1e-3, hi=1e4),
                 "tau_1_ms": F(NUM, 21.0, lo=1e-3, hi=1e4),
                 "latency_ms": F(NUM, 1.0, lo=0, hi=1e3),
                 "theta": F(NUM, 0.0, lo=-1e3, hi=1e3),
                 "eta": F(NUM, 2e-6, lo=0, hi=1e3),
                 "w_max": F(NUM, 6.0, lo=1e-3, hi=1e3),
                 "w_pot": F(NUM, 4.5, lo=-1e3, hi=1e3),
                 "w_dep": F(NUM, 0.5, lo=-1e3, hi=1e3),
                 "slope": F(NUM, 0.5, lo=1e-6, hi=1e3),
                 "strong_fraction": F(NUM, 0.5, lo=0, hi=1),
                 "snapshot_every": F(int, 50, lo=1, hi=100_000),
                 # golden's pair-based STDP on the same protocol, beside AIDP
                 "compare_stdp": F(bool, False)},
    "run": {"engines": F(list, ["golden", "fixed", "verilator"], items=str),
            "waves": F(str, "", max_len=4096),
            "waves_start_tick": F(int, 0, lo=0),
            "waves_ticks": F(int, 100, lo=1, hi=100_000_000)},
}
POPULATION = {"name": F(str, required=True), "model": F(str, "izhikevich", choices=MODELS),
              "preset": F(str, None), "size": F(int, None, lo=1, hi=1_000_000),
              "encoding": F(str, None, choices=("FA", "SA", "force", "spikes")),
              "gratings": F(list, None, items=int),
              # a MEMS fingertip's opponent pairs (0-3: sliding direction, 4-7: across)
              "pairs": F(list, None, items=int),
              "inputs": F(list, [], items=str),
              "gain": F(NUM, None),
              # an SA population's own threshold (default frontend.sa_threshold_pm)
              "threshold_pm": F(NUM, None, lo=0, hi=1e9)}
#: One recorded MEMS trial (``stimulus.recordings``).
RECORDING = {"file": F(str, required=True), "label": F(str, required=True)}
PROJECTION = {"source": F(str, required=True), "target": F(str, required=True),
              "delays_ms": F(list, [0.0], items=NUM), "weight": F(NUM, 1.0),
              "psp": F(str, "biexp", choices=("biexp", "exp", "delta"))}

UNIT_KEYS = {}
for _sec, _keys in SCHEMA.items():
    for _k in _keys:
        for suffix in ("_ms", "_hz", "_nm", "_pm", "_mm", "_mm2", "_MPa", "_N", "_K",
                       "_mm_per_s", "_microstrain_per_N", "_microstrain", "_K_per_s",
                       "_ticks", "_mV", "_mV_per_N", "_mN", "_per_s", "_per_mm"):
            if _k.endswith(suffix):
                UNIT_KEYS.setdefault((_sec, _k[: -len(suffix)]), []).append(_k)


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


class Validator:
    """Checks values and tables against the schema; every refusal is one line naming the source,
    the dotted key and the reason (:class:`SceneError`)."""

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
        for i, x in enumerate(v if isinstance(v, list) else [v]):
            if isinstance(x, str) and len(x) > f.max_len:
                self.err(key if not isinstance(v, list) else f"{key}[{i}]",
                         f"{len(x)} characters; at most {f.max_len} (names and labels title "
                         f"the figures and the report)")
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
                cand = UNIT_KEYS.get((section, k)) if section else None
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
