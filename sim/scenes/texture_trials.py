"""The trials of a texture scene (:mod:`cuneate.sim.scenes.texture`): the platform's
protocol, the fingertip's stimulus (synthesized or recorded), the afferents, one condition run
through the afferent scenes' machinery and decoded with the seeds' decoders, and the conditions
of a grid."""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field

import numpy as np

from ...golden import mems
from ...golden.mems import pair_names
from ...golden.sliding import Protocol, prepare, slide_loads, surface_extent
from ...golden.textures import surface, texture
from .. import progress as prog
from ..decode import decode_textures
from ..host.driver import AfferentEncoding
from ..host.traces import TraceError, load_trace
from . import afferent
from .afferent import Neurons
from .scene import Scene
from .stimulus import merge_counts

__all__ = ["DEFAULTS", "SEEDS", "protocol", "conditions", "is_grid", "condition_scene",
           "synthesize", "build_neurons", "TextureRun", "channel_names", "trains_by_channel",
           "decode_run", "run_single", "core_cost", "pct"]

DEFAULTS = {"sensor": {"channels": 16, "sample_rate_hz": 2000.0, "effects": []},
            "hardware": {"update_hz": 20000.0},
            "stimulus": {"velocity_mm_per_s": 15.0, "spread_force": 0.03,
                         "spread_velocity": 0.01},
            "decoder": {"kind": "vp", "neighbours": 1}}
#: The seeds' figures (brief sections 4 and 4b), beside which the report puts ours.
SEEDS = {"rate": "68 %", "rate + CV": "68-93 % by channel (78 % in the short paper)",
         "VP": "93-97 % (q = 5/s)", "grid": "most of 25 conditions > 85 %, worst slow and weak",
         "spatial, velocities": "90 %", "spatial, forces": "48 %"}



def protocol(scene):
    """The platform's :class:`~cuneate.golden.sliding.Protocol` of a texture scene."""
    st = scene["stimulus"]
    return Protocol(force_N=st["force_mN"] / 1000.0, velocity_mm_per_s=st["velocity_mm_per_s"],
                    slide_mm=st["slide_mm"], rest_ms=st["rest_ms"], indent_ms=st["indent_ms"],
                    hold_ms=st["hold_ms"], retract_ms=st["retract_ms"],
                    spread_force=st["spread_force"], spread_velocity=st["spread_velocity"],
                    spread_friction=st["spread_friction"], jitter_mm=st["jitter_mm"])


# --------------------------------------------------------------------------- conditions
def conditions(scene) -> list[tuple[float, float]]:
    """The scene's ``(force_mN, velocity_mm_per_s)`` conditions: its grid's, or its own."""
    st, g = scene["stimulus"], scene["grid"]
    forces = g["forces_mN"] or [st["force_mN"]]
    vels = g["velocities_mm_per_s"] or [st["velocity_mm_per_s"]]
    return [(f, v) for f in forces for v in vels]


def is_grid(scene) -> bool:
    return len(conditions(scene)) > 1


def condition_scene(scene, force_mN: float, velocity_mm_per_s: float):
    """``scene`` at one condition, without its grid: the scene one cell runs."""
    sec = copy.deepcopy(scene.sections)
    sec["stimulus"]["force_mN"] = float(force_mN)
    sec["stimulus"]["velocity_mm_per_s"] = float(velocity_mm_per_s)
    sec["grid"] = {**sec["grid"], "forces_mN": None, "velocities_mm_per_s": None}
    sec["scene"]["duration_ms"] = protocol(sec).duration_ms
    name = f"{scene.name} ({force_mN:g} mN, {velocity_mm_per_s:g} mm/s)"
    sec["scene"]["name"] = name
    return Scene(scene.source, sec, copy.deepcopy(scene.populations), [], scene.base_dir,
                 "texture")


# --------------------------------------------------------------------------- the stimulus
def synthesize(scene):
    """Every trial of a texture scene: ``(classes, trial_class, S, infos, effect_counts)``
    (``S``: per trial the eight opponent signals ``(n_samples, 8)`` in V; ``infos``: the trial's
    drawn parameters, with its 16 tethers' outputs under ``"tethers_V"``) - what
    :func:`cuneate.sim.scenes.afferent.run` takes as a stimulus."""
    st, sen, sc = scene["stimulus"], scene["sensor"], scene["scene"]
    fs = sen["sample_rate_hz"]
    params = {e: sen[e] for e in sen["effects"]}
    rng = np.random.default_rng(sc["seed"])
    counts: dict = {}
    if st["kind"] == "recorded":
        return _recorded(scene, rng, params)
    prot = protocol(scene)
    xr, yr = surface_extent(prot)
    classes = scene.classes()
    trial_class, traces, infos = [], [], []
    for name, spec in zip(classes, st["textures"]):
        prep = prepare(surface(texture(spec), st["texture_seed"], xr, yr))
        for _ in range(sc["trials"]):
            n, tx, ty, info = slide_loads(prep, prot, rng, fs)
            v, c = mems.sensor_effects(mems.tether_outputs(n, tx, ty), sen["effects"], params,
                                       rng, fs)
            merge_counts(counts, c)
            info["tethers_V"] = v
            trial_class.append(name)
            traces.append(mems.opponent_signals(v))
            infos.append(info)
    return classes, trial_class, traces, infos, counts


def _recorded(scene, rng, params):
    """A MEMS fingertip's recorded trials (``stimulus.file``, or one ``recordings`` table per
    trial): 16 tethers each, cut to the shortest recording (the trials share one core's run)."""
    st, sen = scene["stimulus"], scene["sensor"]
    recs = st["recordings"] or [{"file": st["file"], "label": st["label"]}]
    trs = [load_trace(r["file"], time_key=st["time_key"], data_key=st["data_key"],
                      struct=st["struct"] or None, time_unit=st["time_unit"],
                      shift_unit="nm" if st["signal_unit"] == "V" else "pm",
                      expect_fs_hz=sen["sample_rate_hz"], channels=mems.N_CHANNELS)
           for r in recs]
    n = min(t.d_lambda_nm.shape[0] for t in trs)
    counts: dict = {}
    traces, infos = [], []
    for r, t in zip(recs, trs):
        v, c = mems.sensor_effects(t.d_lambda_nm[:n], sen["effects"], params, rng,
                                   sen["sample_rate_hz"])
        merge_counts(counts, c)
        big = np.abs(v[np.isfinite(v)]) >= 10.0
        if big.any():
            raise TraceError(f"{r['file']}: a tether output of {float(np.max(np.abs(v))):.3g} V "
                             f"is not a MEMS bridge's (check stimulus.signal_unit)")
        traces.append(mems.opponent_signals(v))
        infos.append(t.info | {"tethers_V": v, "label": r["label"],
                               "samples_cut": int(t.d_lambda_nm.shape[0] - n)})
    return scene.classes(), [r["label"] for r in recs], traces, infos, counts


def build_neurons(scene, n_trials: int):
    """The afferents of ``n_trials`` trials (trial-major, then population, then pair): SA
    encodings ``I = (K/R) S`` above ``S_th``, with ``S`` in volts (the driver's unit of 1000
    "pm" makes its input the signal itself, its threshold in mV)."""
    fe, fs = scene["frontend"], scene["sensor"]["sample_rate_hz"]
    nn = Neurons()
    for t in range(n_trials):
        for p in scene.populations:
            enc = AfferentEncoding("SA", p["gain"] if p["gain"] is not None else fe["sa_gain"],
                                   1000.0, None, "none", fe["sa_threshold_mV"], fs)
            for g in p["pairs"]:
                nn.trial.append(t)
                nn.population.append(p["name"])
                nn.grating.append(g)
                nn.preset.append(p["preset"])
                nn.encoding.append(enc)
    return nn


# --------------------------------------------------------------------------- running
@dataclass
class TextureRun:
    """A texture scene's run: the afferent machinery's run (``afferent``: spikes, counters,
    agreement, ...) and the texture decoding of each engine."""

    afferent: object
    decoding: dict                      # engine -> TextureDecoding
    channels: list                      # channel names, in neuron order within a trial
    timing: dict = field(default_factory=dict)
    kind: str = "texture"

    @property
    def scene(self):
        return self.afferent.scene


def channel_names(scene) -> list[str]:
    """The decoded channels (one per population and pair) as the report names them."""
    names = pair_names()
    many = len(scene.populations) > 1
    return [f"{p['name']} {names[g]}" if many else names[g]
            for p in scene.populations for g in p["pairs"]]


def trains_by_channel(spikes, n_trials: int, channels: list[str]) -> dict:
    """An engine's trains (trial-major) as ``{channel: [train per trial]}``."""
    k = len(channels)
    return {c: [np.asarray(spikes[t * k + i]) for t in range(n_trials)]
            for i, c in enumerate(channels)}


def decode_run(scene, arun) -> dict:
    """The texture decoding of every engine of an afferent-machinery run ``arun``."""
    dec = scene["decoder"]
    if dec["kind"] == "none":
        return {}
    chans = channel_names(scene)
    n_trials = len(arun.trial_class)
    win = tuple(dec["window_ms"]) if dec["window_ms"] is not None else \
        (0.0, arun.n_ticks * arun.dt_ms)
    return {e: decode_textures(trains_by_channel(sp, n_trials, chans), arun.trial_class,
                               arun.classes, win, dec["q_per_s"], dec["neighbours"])
            for e, sp in arun.spikes.items()}


def run_single(scene, engines=None, build_dir=None, progress=False, log=None, waves=None,
               in_turn: int | None = None):
    """One condition: the afferent machinery (``in_turn``: its trials that many at a time, as
    a board holding them plays them, :mod:`cuneate.sim.scenes.in_turn`), then the texture
    decoders."""
    arun = afferent.run(scene, engines, build_dir, progress, log, waves=waves,
                        synth=synthesize, build=build_neurons, in_turn=in_turn)
    t0 = time.perf_counter()
    with prog.step("decoding the textures (rate, rate + CV, Victor-Purpura; kNN, "
                   "leave-one-out)"):
        decoding = decode_run(scene, arun)
    return TextureRun(arun, decoding, channel_names(scene),
                      {"decode_s": time.perf_counter() - t0})


def pct(x) -> str:
    """A fraction as a percentage with one decimal (``-`` for None)."""
    return "-" if x is None else f"{100 * x:.1f}"


def core_cost(scene, arun) -> dict:
    """What the scene's update rate costs: neurons per core at the scene's clock, at this rate
    and at the reference core's 16 kHz."""
    hw = scene["hardware"]
    return {"update_hz": hw["update_hz"], "dt_ms": 1000.0 / hw["update_hz"],
            "clock_hz": hw["clock_hz"],
            "neurons_per_core": int(hw["clock_hz"] // hw["update_hz"]),
            "neurons_per_core_at_16kHz": int(hw["clock_hz"] // 16e3),
            "neurons_used": len(arun.neurons)}


