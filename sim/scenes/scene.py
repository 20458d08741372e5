"""Scene files: what a run simulates, in TOML (read with :mod:`tomllib`).

A scene names the sensor and the physical effects to model, the stimulus, the host front end,
the neuron populations and their projections, the decoder, the hardware configuration, the
engines to run, and the trials and seeds. :func:`load_scene` validates a file against the
schema (:mod:`cuneate.sim.scenes.schema`) and the checks of its kind
(:mod:`cuneate.sim.scenes.registry`) and returns a :class:`Scene` (plain dictionaries with every
default filled in); any problem raises :class:`SceneError` naming the file, the dotted key and
the reason (unknown key, wrong type, missing unit, out of range, an engine the scene's block
does not run, not available in this build). The embedded default scene
(:data:`DEFAULT_SCENE_TOML`) is the four-material grasp; more scenes ship in
``cuneate.sim.scenes.examples`` (:func:`example_path`). See docs/scenes.md.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from ..engines.registry import UnknownEngine, check_engine
from .registry import KINDS, kind_for, kind_module
from .schema import (EFFECT_NAMES, EFFECT_PARAMS, MEMS_EFFECT_PARAMS, NUM, POPULATION, PROJECTION,
                     RECORDING, SCHEMA, F, SceneError, Validator)

__all__ = ["SceneError", "Scene", "load_scene", "parse_scene", "default_scene",
           "DEFAULT_SCENE_TOML", "example_path", "example_names"]


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


#: what one trial is, by stimulus kind
TRIAL_NOUNS = {"grasp": "grasp", "slide": "slide", "pulses": "pulse", "recorded": "recording",
               "ridges": "ridge", "press": "press",
               "learning": "presentation"}


@dataclass
class Scene:
    """A validated scene: one dictionary per section (defaults filled), populations and
    projections as lists of dictionaries, and where it came from."""

    source: str
    sections: dict
    populations: list
    projections: list
    base_dir: Path | None = None
    kind: str = "afferent"              # the scene kind (:mod:`cuneate.sim.scenes.registry`)

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

    @property
    def trial_noun(self) -> str:
        """What one trial is, by stimulus kind (a grasp, a slide, a pulse, a recording, a
        ridge, a press): reports and decoding rows name trials with it."""
        return TRIAL_NOUNS.get(self.sections["stimulus"]["kind"], "trial")

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
        if st["kind"] in ("textures", "learning"):
            return [t if isinstance(t, str) else t["name"] for t in st["textures"]]
        if st["recordings"]:
            return list(dict.fromkeys(r["label"] for r in st["recordings"]))
        return [st["label"]]

    def n_trials(self) -> int:
        """The trials of a run: every class's ``scene.trials``, or one per recording."""
        st = self.sections["stimulus"]
        if st["kind"] == "recorded":
            return max(1, len(st["recordings"]))
        return self.sections["scene"]["trials"] * len(self.classes())

    def to_dict(self) -> dict:
        return copy.deepcopy(self.sections) | {"population": copy.deepcopy(self.populations),
                                                "projection": copy.deepcopy(self.projections)}


def parse_scene(text: str, source: str = "<scene>", base_dir: Path | None = None) -> Scene:
    """Validate TOML ``text``; errors name ``source``. The checks run in a fixed order (the
    first problem found is the one reported): the sections against the schema, the sensor, the
    stimulus, the front end, the hardware and engines, the decoder, the populations and
    projections, what this build runs, the trials a board and a core hold."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: not valid TOML: {exc}") from None
    V = Validator(source)
    sections = _schema_sections(V, raw)
    taxels = sections["sensor"]["kind"] == "taxels"
    mems = sections["sensor"]["kind"] == "mems"
    _check_sensor(V, raw, sections, taxels, mems)
    kind = _scene_kind(sections, taxels, mems)
    _check_stimulus(V, sections, mems, base_dir)
    _check_frontend(V, sections, taxels, mems)
    _check_hardware(V, sections)
    _check_engines(V, sections, kind)
    _check_decoder(V, sections, kind)
    pops, projs = _populations_and_projections(V, raw, sections, kind, taxels, mems)
    _check_what_this_build_runs(V, sections, pops, projs, kind)
    scene = Scene(source, sections, pops, projs, base_dir, kind.name)
    _check_trials_fit(V, scene)
    return scene


def _schema_sections(V, raw: dict) -> dict:
    """Every section of the schema checked and its defaults filled; an unknown one refused."""
    for k in raw:
        if k not in SCHEMA and k not in ("population", "projection"):
            V.err(k, f"unknown section (known: {', '.join([*SCHEMA, 'population', 'projection'])})")
    return {sec: V.table(sec, raw.get(sec, {}), schema, sec) for sec, schema in SCHEMA.items()}


def _check_sensor(V, raw: dict, sections: dict, taxels: bool, mems: bool) -> None:
    """[sensor]: a MEMS fingertip's defaults and grid, a taxel skin's (no optical effects),
    the effects and their parameter tables, the saturation range."""
    sensor = sections["sensor"]
    if mems:
        # a MEMS fingertip's own defaults (16 tethers, its sample rate, the seeds' 20 kHz ...)
        kind_module("texture").fill_defaults(V, raw, sections)
    elif raw.get("grid"):
        V.err("grid", "a grid of sensing conditions runs texture scenes (sensor.kind = "
                      "\"mems\")")
    if taxels:
        # a taxel skin reads force directly: none of the optical effects of a grating apply
        if raw.get("sensor", {}).get("effects"):
            V.err("sensor.effects", "FBG effects do not apply to a taxel sensor (leave the list "
                                    "empty or out)")
        sensor["effects"] = []
    elif sensor["grid"] is not None:
        V.err("sensor.grid", "a grid needs sensor.kind = \"taxels\"")
    effect_params = MEMS_EFFECT_PARAMS if mems else EFFECT_PARAMS
    for i, e in enumerate(sensor["effects"]):
        if e not in EFFECT_NAMES:
            V.err(f"sensor.effects[{i}]", f"unknown effect {e!r} (known: "
                                          f"{', '.join(EFFECT_NAMES)})")
        if mems and e not in effect_params:
            V.err(f"sensor.effects[{i}]", f"{e!r} is not an effect of a MEMS fingertip (it "
                                          f"has: {', '.join(effect_params)})")
    if not taxels and not mems and "strain" not in sensor["effects"]:
        V.err("sensor.effects", "must include 'strain' (the mechanical term every trace has)")
    if len(set(sensor["effects"])) != len(sensor["effects"]):
        V.err("sensor.effects", "lists an effect twice")
    for e in EFFECT_PARAMS:
        params = effect_params.get(e, {})
        given = raw.get("sensor", {}).get(e)
        if given is not None and e not in sensor["effects"]:
            V.err(f"sensor.{e}", f"parameters given for effect {e!r}, which sensor.effects "
                                 f"does not list (it would not be computed)")
        sensor[e] = V.table(f"sensor.{e}", given or {}, params) if e in sensor["effects"] \
            else {}
    sat = sensor.get("saturation") or {}
    lo, hi = ("min_mV", "max_mV") if mems else ("min_nm", "max_nm")
    if sat and not sat[lo] < sat[hi]:
        V.err("sensor.saturation", f"{lo} ({sat[lo]:g}) must be below {hi} ({sat[hi]:g})")


def _scene_kind(sections: dict, taxels: bool, mems: bool):
    """The scene's kind: its stimulus's, a taxel skin's or MEMS fingertip's for the kinds an
    afferent stimulus would otherwise take."""
    kind = kind_for(sections["stimulus"]["kind"])
    if taxels and kind.name == "afferent":
        kind = KINDS["skin"]            # its checks say what a taxel sensor takes
    if mems and kind.name == "afferent":
        kind = KINDS["texture"]         # a MEMS fingertip's recorded traces, say
    return kind


def _check_stimulus(V, sections: dict, mems: bool, base_dir: Path | None) -> None:
    """[stimulus] by kind (the loading window needs a grasp); recorded files resolved against
    ``base_dir``."""
    st, channels = sections["stimulus"], sections["sensor"]["channels"]
    if st["kind"] == "grasp":
        _check_materials(V, st)
        _check_coupling(V, st, channels)
        if any(c <= 0 for c in st["coupling_microstrain_per_N"]):
            V.err("stimulus.coupling_microstrain_per_N", "out of range: values must be > 0")
    if sections["frontend"]["window"] == "loading" and st["kind"] != "grasp":
        V.err("frontend.window", "'loading' needs a grasp stimulus (it has a loading phase)")
    if st["kind"] == "pulses":
        if not st["pulse_amplitudes_N"] or any(a <= 0 for a in st["pulse_amplitudes_N"]):
            V.err("stimulus.pulse_amplitudes_N", "must list amplitudes > 0")
        amps = [f"{a:g}" for a in st["pulse_amplitudes_N"]]
        if len(set(amps)) != len(amps):
            V.err("stimulus.pulse_amplitudes_N", f"lists an amplitude twice ({', '.join(amps)}): "
                                                 f"each amplitude is one class")
        _check_coupling(V, st, channels)
    if st["kind"] == "slide" and (not st["periods_mm"] or any(p <= 0 for p in st["periods_mm"])):
        V.err("stimulus.periods_mm", "must list periods > 0")
    if st["recordings"] and not (mems and st["kind"] == "recorded"):
        V.err("stimulus.recordings", "one table per recorded trial of a MEMS fingertip "
                                     "(sensor.kind = \"mems\", stimulus.kind = \"recorded\")")
    if st["kind"] == "recorded":
        _check_recorded(V, st, base_dir)


def _check_materials(V, st: dict) -> None:
    """A grasp's materials: known names or tables (name, young_MPa ...), each once."""
    from ...golden.tactile import MATERIALS
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


def _check_coupling(V, st: dict, channels: int) -> None:
    """One strain coupling per channel."""
    if len(st["coupling_microstrain_per_N"]) != channels:
        V.err("stimulus.coupling_microstrain_per_N",
              f"needs one value per channel ({channels}), got "
              f"{len(st['coupling_microstrain_per_N'])}")


def _check_recorded(V, st: dict, base_dir: Path | None) -> None:
    """A recorded stimulus: a file or a table per trial (not both), paths resolved against
    ``base_dir``."""
    if st["file"] and st["recordings"]:
        V.err("stimulus.file", "give either file (one trial) or recordings (a table per "
                               "trial), not both")
    if not st["file"] and not st["recordings"]:
        V.err("stimulus.file", "missing required key for a recorded stimulus")

    def here(f):
        p = Path(f)
        return str(base_dir / p if not p.is_absolute() and base_dir is not None else p)
    if st["file"]:
        st["file"] = here(st["file"])
    st["recordings"] = [V.table(f"stimulus.recordings[{i}]", r, RECORDING)
                        for i, r in enumerate(st["recordings"])]
    for r in st["recordings"]:
        r["file"] = here(r["file"])


def _check_frontend(V, sections: dict, taxels: bool, mems: bool) -> None:
    """[frontend]: a given filter (both coefficient lists, stable), else the band edges below
    Nyquist (an FBG sensor's)."""
    fe = sections["frontend"]
    if (fe["filter_b"] is None) != (fe["filter_a"] is None):
        V.err("frontend.filter_a" if fe["filter_a"] is None else "frontend.filter_b",
              "filter coefficients need both filter_b and filter_a")
    if fe["filter_b"] is not None:
        from ...golden.fbg import IIRFilter
        try:
            rep = IIRFilter(b=fe["filter_b"], a=fe["filter_a"]).check()
        except ValueError as exc:
            V.err("frontend.filter_a", str(exc))
        if not rep.stable:
            V.err("frontend.filter_a", f"unstable filter: {rep.message}")
    fs = sections["sensor"]["sample_rate_hz"]
    if not taxels and not mems and fe["filter_b"] is None and \
            not 0 < fe["filter_low_hz"] < fe["filter_high_hz"] < fs / 2:
        V.err("frontend.filter_high_hz", f"band edges must satisfy 0 < filter_low_hz < "
                                         f"filter_high_hz < sample_rate_hz/2 = {fs / 2:g}")


def _check_hardware(V, sections: dict) -> None:
    """[hardware]: whole ticks per sample, at least one clock cycle per tick."""
    hw, fs = sections["hardware"], sections["sensor"]["sample_rate_hz"]
    ratio = hw["update_hz"] / fs
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        V.err("hardware.update_hz", f"must be a whole multiple of sensor.sample_rate_hz "
                                    f"({fs:g}): each sample is held for a whole number of "
                                    f"ticks, got ratio {ratio:g}")
    if hw["clock_hz"] / hw["update_hz"] < 1:
        V.err("hardware.clock_hz", "must be >= update_hz")


def _check_engines(V, sections: dict, kind) -> None:
    """[run].engines: each runs the scene's block (and the channel fan-out if asked), at least
    one, each once."""
    engines = sections["run"]["engines"]
    for i, e in enumerate(engines):
        try:
            check_engine(kind.block, e)
        except UnknownEngine as exc:
            V.err(f"run.engines[{i}]", str(exc))
    if sections["hardware"]["fanout"]:
        from ..fanout.scene import fanout_scene_engines
        ok = fanout_scene_engines()
        if kind.block != "izhikevich":
            V.err("hardware.fanout", "the channel fan-out feeds afferent scenes' Izhikevich "
                                     "afferents")
        for i, e in enumerate(engines):
            if e not in ok:
                V.err(f"run.engines[{i}]", f"engine {e!r} does not run the channel fan-out "
                                           f"(hardware.fanout; engines that do: "
                                           f"{', '.join(ok)})")
    if not engines:
        V.err("run.engines", "must name at least one engine")
    if len(set(engines)) != len(engines):
        V.err("run.engines", "names an engine twice")


def _check_decoder(V, sections: dict, kind) -> None:
    """[decoder]: the window inside the run, an afferent scene's decoder kinds."""
    dec, st = sections["decoder"], sections["stimulus"]
    if dec["window_ms"] is not None and (len(dec["window_ms"]) != 2
                                         or not dec["window_ms"][0] < dec["window_ms"][1]):
        V.err("decoder.window_ms", "must be [start, end] with start < end")
    elif dec["window_ms"] is not None and st["kind"] != "recorded":
        dur = sections["scene"]["duration_ms"]
        if dec["window_ms"][0] >= dur or dec["window_ms"][1] <= 0:
            V.err("decoder.window_ms", f"[{dec['window_ms'][0]:g}, {dec['window_ms'][1]:g}] ms "
                                       f"lies outside the run (0 .. {dur:g} ms): no spike "
                                       f"would be decoded")
    if kind.name == "afferent":
        _check_afferent_decoder(V, dec, st, sections["scene"]["trials"])


def _populations_and_projections(V, raw: dict, sections: dict, kind, taxels: bool,
                                 mems: bool) -> tuple[list, list]:
    """The [[population]] tables (defaults by model and kind), the scene kind's own checks,
    each population's sensor and wiring, the [[projection]] tables."""
    for key in ("population", "projection"):
        if isinstance(raw.get(key), dict):
            V.err(key, f"wrong type: write [[{key}]] (an array of tables), not [{key}]")
    pops_raw = raw.get("population", [])
    if not isinstance(pops_raw, list) or not pops_raw:
        V.err("population", "at least one [[population]] table is required")
    pops = []
    for i, p in enumerate(pops_raw):
        pops.append(V.table(f"population[{i}]", p, POPULATION))
        if pops[-1]["preset"] is None and pops[-1]["model"] == "izhikevich":
            pops[-1]["preset"] = "RS"
    ridges = kind.name == "ridge"
    projs = []
    if ridges:
        projs = _projections(V, raw, [p["name"] for p in pops])
    if raw.get("learning") and kind.name != "learning":
        V.err("learning", "the learning protocol belongs to learning scenes (stimulus.kind = "
                          "\"learning\")")
    if kind.name != "afferent":
        kind_module(kind).validate(V, raw, sections, pops, projs)
    _check_population_sensors(V, pops, kind, taxels, mems)
    _check_population_wiring(V, pops, sections["sensor"]["channels"])
    if not ridges:
        projs = _projections(V, raw, [p["name"] for p in pops])
    return pops, projs


def _check_population_sensors(V, pops: list, kind, taxels: bool, mems: bool) -> None:
    """Each population's encoding (default by model) against the sensor: LIF and force on a
    taxel skin, an SA threshold in afferent scenes, opponent pairs on a MEMS fingertip."""
    for i, p in enumerate(pops):
        if p["encoding"] is None:
            p["encoding"] = "spikes" if p["model"] == "cuneate" else "FA"
        if not taxels and p["model"] == "lif":
            V.err(f"population[{i}].model", "LIF populations run on a taxel skin in this build "
                                            "(sensor.kind = \"taxels\", stimulus.kind = "
                                            "\"press\")")
        if p["threshold_pm"] is not None and (p["encoding"] != "SA" or kind.name != "afferent"):
            V.err(f"population[{i}].threshold_pm", "a threshold gates the SA afferents of an "
                                                   "afferent scene (encoding = \"SA\")")
        if not taxels and p["encoding"] == "force":
            V.err(f"population[{i}].encoding", "force encoding needs sensor.kind = \"taxels\"")
        if p["pairs"] is not None and not mems:
            V.err(f"population[{i}].pairs", "opponent pairs are a MEMS fingertip's "
                                            "(sensor.kind = \"mems\"); FBG afferents take "
                                            "gratings")


def _check_population_wiring(V, pops: list, channels: int) -> None:
    """Each population's name (unique), inputs, preset, and gratings (one neuron each) or
    size (a spike-driven population's)."""
    names = [p["name"] for p in pops]
    for i, p in enumerate(pops):
        key = f"population[{i}]"
        if names.count(p["name"]) > 1:
            V.err(f"{key}.name", f"duplicate population name {p['name']!r}")
        for j, src in enumerate(p["inputs"]):
            if src not in names or src == p["name"]:
                V.err(f"{key}.inputs[{j}]", f"unknown source population {src!r}")
        if p["model"] == "izhikevich":
            from ...golden.izhikevich import to_params
            try:
                to_params(p["preset"])
            except ValueError as exc:
                V.err(f"{key}.preset", str(exc))
        if p["encoding"] == "spikes" and not p["inputs"]:
            V.err(f"{key}.inputs", "a population driven by spikes needs inputs")
        if p["encoding"] != "spikes":
            g = p["gratings"] if p["gratings"] is not None else list(range(channels))
            for j, x in enumerate(g):
                if not 0 <= x < channels:
                    V.err(f"{key}.gratings[{j}]", f"out of range: grating {x} (the sensor has "
                                                  f"{channels} channels)")
            p["gratings"] = g
            if p["size"] is not None and p["size"] != len(g):
                V.err(f"{key}.size", f"a sensor-driven population has one neuron per grating "
                                     f"({len(g)}), got {p['size']}")
            p["size"] = len(g)
        elif p["size"] is None:
            V.err(f"{key}.size", "missing required key for a spike-driven population")


def _check_what_this_build_runs(V, sections: dict, pops: list, projs: list, kind) -> None:
    """Only what this build simulates: cuneate populations and projections in ridge scenes and
    an afferent scene's cuneate layer, a decoded population of an afferent scene."""
    dec, names = sections["decoder"], [p["name"] for p in pops]
    for i, p in enumerate(pops):
        if p["model"] == "cuneate" and kind.name not in ("ridge", "afferent"):
            V.err(f"population[{i}].model", "cuneate populations run in ridge scenes and as "
                                            "the cuneate layer of afferent scenes")
    if kind.name == "afferent":
        from ..network.scene import validate_layer
        validate_layer(V, sections, pops, projs)
    elif projs and kind.name != "ridge":
        V.err("projection[0]", "projections (coincidence delays) run in ridge scenes and into "
                               "the cuneate layer of afferent scenes")
    if dec["population"] and (kind.name != "afferent" or dec["population"] not in names):
        V.err("decoder.population", f"{dec['population']!r}: an afferent scene decodes one of "
                                    f"its populations ({', '.join(names)}), or every afferent "
                                    f"(\"\")" if kind.name == "afferent" else
              "only afferent scenes decode a chosen population")


def _check_trials_fit(V, scene: Scene) -> None:
    """The trials a board holds (``hardware.board_trials``) and the Izhikevich neurons of every
    trial on one core."""
    hw, st = scene["hardware"], scene["stimulus"]
    n_trials = scene.n_trials()
    in_turn = scene.kind in ("afferent", "texture") and st["kind"] != "recorded"
    if hw["board_trials"] is not None and (not in_turn or hw["board_trials"] > n_trials):
        V.err("hardware.board_trials", f"a board holds some of an afferent scene's trials "
                                       f"(1 .. {n_trials})" if in_turn else "a board holds some "
              "of the trials of an afferent or texture scene with synthesized trials")
    need = n_trials * sum(p["size"] for p in scene.populations if p["model"] == "izhikevich")
    capacity = int(hw["clock_hz"] // hw["update_hz"])
    if need > capacity:
        V.err("hardware.clock_hz", f"the scene needs {need} Izhikevich neurons ({n_trials} "
                                   f"trials) but one core at {hw['clock_hz']:g} Hz / "
                                   f"{hw['update_hz']:g} Hz holds {capacity}")


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


def _check_afferent_decoder(V, dec: dict, st: dict, trials: int) -> None:
    """An afferent scene decodes with a tree or k nearest neighbours (``winner`` and
    ``pattern`` belong to the skin and ridge scenes); per-trial kNN needs more training samples
    in the smallest fold than ``neighbours``."""
    if dec["kind"] in ("winner", "pattern", "vp"):
        what = {"winner": "a taxel skin", "pattern": "ridge scenes",
                "vp": "texture scenes (sensor.kind = \"mems\")"}[dec["kind"]]
        V.err("decoder.kind", f"{dec['kind']!r} decodes {what}; a scene of FBG afferents "
                              f"takes \"tree\", \"knn\" or \"none\"")
    if dec["kind"] != "knn" or dec["features"] != "trial" or st["kind"] == "recorded":
        return
    n_classes = len(st.get({"grasp": "materials", "slide": "periods_mm",
                            "pulses": "pulse_amplitudes_N"}.get(st["kind"], ""), []) or [0])
    n = trials * n_classes
    folds = min(dec["cv_folds"], trials)
    train = n - -(-n // folds)
    if folds >= 2 and dec["neighbours"] > train:
        V.err("decoder.neighbours", f"{dec['neighbours']} neighbours, but the smallest training "
                                    f"fold holds {train} trial(s) ({trials} trials x "
                                    f"{n_classes} classes, {folds} folds)")


def load_scene(path) -> Scene:
    """Read and validate a scene file (errors name the file)."""
    p = Path(path)
    try:
        text = p.read_bytes().decode("utf-8")
    except OSError as exc:
        raise SceneError(f"{p}: cannot read scene: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        line = p.read_bytes()[:exc.start].count(b"\n") + 1
        raise SceneError(f"{p}: line {line}: not UTF-8 text (byte {exc.object[exc.start]:#04x} "
                         f"at offset {exc.start}); TOML scene files are UTF-8") from None
    return parse_scene(text, str(p), p.parent)


def default_scene() -> Scene:
    """The embedded default scene (the four-material grasp)."""
    return parse_scene(DEFAULT_SCENE_TOML, "<default scene>")


def example_names() -> list[str]:
    """Names of the example scenes shipped with the package."""
    root = resources.files("cuneate.sim.scenes.examples")
    return sorted(p.name for p in root.iterdir() if p.name.endswith(".toml"))


def example_path(name: str) -> Path | None:
    """The shipped example ``name`` (``examples/NAME.toml``, ``NAME.toml`` or ``NAME``)."""
    n = Path(name).name
    if not n.endswith(".toml"):
        n += ".toml"
    p = Path(str(resources.files("cuneate.sim.scenes.examples") / n))
    return p if p.is_file() else None
