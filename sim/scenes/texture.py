"""Texture scenes: textures slid under the MEMS fingertip, SA afferents on the Izhikevich core,
the seeds' decoders.

A scene with ``sensor.kind = "mems"`` and ``stimulus.kind = "textures"`` (or ``"recorded"``:
a MEMS fingertip's recorded traces, one table per trial) runs the texture experiment of the
seed works (brief section 4b). Each trial slides one texture of ``stimulus.textures`` under
the fingertip (:mod:`cuneate.golden.sliding`: indentation to ``force_mN``, a slide of
``slide_mm`` at ``velocity_mm_per_s``, retraction), its surface a specimen of synthesis seed
``stimulus.texture_seed`` (:mod:`cuneate.golden.textures`); the 16 tethers
(:mod:`cuneate.golden.mems`, with only the listed effects) are sampled at
``sensor.sample_rate_hz``, and opponent tethers subtracted give the eight shear signals ``S``
(0-3: the sliding direction of sensors 0-3, the seeds' channels 2-4, 5-7, 12-10, 15-13; 4-7:
across). Each population's ``pairs`` (default the four sliding-direction pairs) drive SA
Izhikevich afferents with ``I = (K/R) S`` where ``S >= S_th`` (``frontend.sa_gain`` = K/R,
``frontend.sa_threshold_mV``).

The afferents run on the afferent scenes' machinery (:func:`cuneate.sim.scenes.afferent.run`:
every trial a neuron of one core sized to them at ``hardware.update_hz``, 20 kHz by default
as the seeds' 50 µs step; the host driver quantizes and streams the currents; golden, fixed,
the HDL simulators and the board engine), then each engine's trains are decoded with the
seeds' decoders (:func:`cuneate.sim.decode.decode_textures`: rate, rate + CV and
Victor-Purpura, each by k nearest neighbours under leave-one-out, per channel and on all
channels).

With a ``[grid]`` (``forces_mN``, ``velocities_mm_per_s``) the scene is run once per
condition (its own core each; on a local Dask cluster of ``grid.workers`` processes, or the
scheduler ``grid.scheduler``, ``"sync"`` in this process), each condition decoded alone (the
heat map), then the spatial VP: spike times within the slide rescaled by the trial's velocity
into positions, decoded across the velocities at the scene's force and across the forces at
its velocity (:func:`cuneate.sim.decode.decode_conditions`), in time and in space.
"""

from __future__ import annotations

import copy
import html
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["fill_defaults", "validate", "estimate", "run", "summary", "write_report",
           "format_run", "TextureRun", "GridRun", "protocol", "synthesize", "build_neurons",
           "condition_scene", "SEEDS"]

#: A MEMS fingertip scene's defaults where they differ from the schema's (FBG) ones.
DEFAULTS = {"sensor": {"channels": 16, "sample_rate_hz": 2000.0, "effects": []},
            "hardware": {"update_hz": 20000.0},
            "stimulus": {"velocity_mm_per_s": 15.0, "spread_force": 0.03,
                         "spread_velocity": 0.01},
            "decoder": {"kind": "vp", "neighbours": 1}}
#: The seeds' figures (brief sections 4 and 4b), beside which the report puts ours.
SEEDS = {"rate": "68 %", "rate + CV": "68-93 % by channel (78 % in the short paper)",
         "VP": "93-97 % (q = 5/s)", "grid": "most of 25 conditions > 85 %, worst slow and weak",
         "spatial, velocities": "90 %", "spatial, forces": "48 %"}


# --------------------------------------------------------------------------- validation
def protocol(scene):
    """The platform's :class:`~cuneate.golden.sliding.Protocol` of a texture scene."""
    from ...golden.sliding import Protocol
    st = scene["stimulus"]
    return Protocol(force_N=st["force_mN"] / 1000.0, velocity_mm_per_s=st["velocity_mm_per_s"],
                    slide_mm=st["slide_mm"], rest_ms=st["rest_ms"], indent_ms=st["indent_ms"],
                    hold_ms=st["hold_ms"], retract_ms=st["retract_ms"],
                    spread_force=st["spread_force"], spread_velocity=st["spread_velocity"],
                    spread_friction=st["spread_friction"], jitter_mm=st["jitter_mm"])


def fill_defaults(V, raw: dict, sections: dict) -> None:
    """A MEMS fingertip scene's own defaults (:data:`DEFAULTS`) for the keys it does not give;
    the trial's length follows from the protocol (``scene.duration_ms`` is refused)."""
    for sec, keys in DEFAULTS.items():
        given = raw.get(sec, {})
        for k, v in keys.items():
            if k not in given:
                sections[sec][k] = copy.deepcopy(v)
    if sections["sensor"]["channels"] != 16:
        V.err("sensor.channels", f"a MEMS fingertip has 16 tethers (4 sensors x 4), got "
                                 f"{sections['sensor']['channels']}")
    if "duration_ms" in raw.get("scene", {}):
        V.err("scene.duration_ms", "a texture trial lasts its protocol's phases (stimulus."
                                   "rest_ms, indent_ms, hold_ms, slide_mm / velocity_mm_per_s, "
                                   "retract_ms); leave duration_ms out")
    st = sections["stimulus"]
    if st["kind"] == "textures":
        from ...golden.textures import TEXTURES
        if st["textures"] is None:
            st["textures"] = list(TEXTURES)
        sections["scene"]["duration_ms"] = protocol(sections).duration_ms


def _texture(V, i: int, t):
    from ...golden.textures import Texture, texture
    if isinstance(t, dict):
        unknown = set(t) - set(Texture.__dataclass_fields__) - {"like"}
        if unknown or "name" not in t:
            V.err(f"stimulus.textures[{i}]", f"a texture table takes name, like and the "
                                             f"parameters of cuneate.golden.textures.Texture"
                                             + (f" (unknown: {', '.join(sorted(unknown))})"
                                                if unknown else " (name is missing)"))
    try:
        return texture(t)
    except (ValueError, TypeError) as exc:
        V.err(f"stimulus.textures[{i}]", str(exc))


def validate(V, raw: dict, sections: dict, pops: list, projs: list) -> None:
    """Check and complete a texture scene in place; ``V.err`` raises the scene error."""
    sen, st, hw, dec, grid = (sections[k] for k in ("sensor", "stimulus", "hardware",
                                                    "decoder", "grid"))
    if sen["kind"] != "mems":
        V.err("sensor.kind", "a textures stimulus slides under the MEMS fingertip: "
                             "sensor.kind = \"mems\"")
    if st["kind"] not in ("textures", "recorded"):
        V.err("stimulus.kind", f"a MEMS fingertip takes textures or its recorded traces, got "
                               f"{st['kind']!r}")
    if st["kind"] == "textures":
        if not st["textures"]:
            V.err("stimulus.textures", "must not be empty")
        names = [_texture(V, i, t).name for i, t in enumerate(st["textures"])]
        if len(set(names)) != len(names):
            V.err("stimulus.textures", "names a texture twice")
    if hw["fanout"]:
        V.err("hardware.fanout", "each afferent of a texture scene has its own opponent "
                                 "signal: there is nothing to fan out")
    if projs or any(p["model"] != "izhikevich" for p in pops):
        V.err("population", "a texture scene's populations are Izhikevich SA afferents")
    for i, p in enumerate(pops):
        key = f"population[{i}]"
        if p["gratings"] is not None:
            V.err(f"{key}.gratings", "a MEMS fingertip's afferents take opponent pairs: "
                                     "write pairs (0-3 sliding direction, 4-7 across)")
        if p["encoding"] not in (None, "SA"):
            V.err(f"{key}.encoding", "texture scenes decode SA afferents (encoding = \"SA\"), "
                                     "as the seeds")
        p["encoding"] = "SA"
        pairs = p["pairs"] if p["pairs"] is not None else [0, 1, 2, 3]
        for j, x in enumerate(pairs):
            if not 0 <= x < 8:
                V.err(f"{key}.pairs[{j}]", f"out of range: pair {x} (0-3: sliding direction "
                                           f"of sensors 0-3, 4-7: across)")
        if len(set(pairs)) != len(pairs) or not pairs:
            V.err(f"{key}.pairs", "must list distinct pairs")
        p["gratings"] = p["pairs"] = list(pairs)
    if dec["kind"] not in ("vp", "none"):
        V.err("decoder.kind", f"a texture scene decodes with the seeds' decoders (kind = "
                              f"\"vp\": rate, rate + CV, Victor-Purpura) or \"none\", got "
                              f"{dec['kind']!r}")
    if dec["population"]:
        V.err("decoder.population", "a texture scene decodes every afferent, per channel")
    forces, vels = grid["forces_mN"], grid["velocities_mm_per_s"]
    if raw.get("grid"):
        if st["kind"] != "textures":
            V.err("grid", "a grid of sensing conditions needs synthesized textures")
        for key, xs in (("grid.forces_mN", forces), ("grid.velocities_mm_per_s", vels)):
            if xs is not None and (not xs or any(x <= 0 for x in xs)
                                   or len(set(xs)) != len(xs)):
                V.err(key, "must list distinct values > 0")
        if len(forces or [0]) * len(vels or [0]) < 2:
            V.err("grid", "a grid needs at least two conditions (forces_mN x "
                          "velocities_mm_per_s)")


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
    from .scene import Scene
    sec = copy.deepcopy(scene.sections)
    sec["stimulus"]["force_mN"] = float(force_mN)
    sec["stimulus"]["velocity_mm_per_s"] = float(velocity_mm_per_s)
    sec["grid"] = {**sec["grid"], "forces_mN": None, "velocities_mm_per_s": None}
    sec["scene"]["duration_ms"] = protocol(sec).duration_ms
    name = f"{scene.name} ({force_mN:g} mN, {velocity_mm_per_s:g} mm/s)"
    sec["scene"]["name"] = name
    return Scene(scene.source, sec, copy.deepcopy(scene.populations), [], scene.base_dir,
                 "texture")


def estimate(scene, engines: list[str], n_samples: int | None = None) -> dict:
    """Memory (bytes) and time (s): the afferent machinery's estimate of each condition
    (:func:`cuneate.sim.scenes.afferent.estimate`), the synthesis of every trial, and the VP
    matrices; a grid's conditions share its workers."""
    from . import afferent
    conds = conditions(scene)
    workers = scene["grid"]["workers"] if len(conds) > 1 else 1
    nbytes, seconds = 0.0, 0.0
    for f, v in conds:
        sc = condition_scene(scene, f, v) if len(conds) > 1 else scene
        est = afferent.estimate(sc, engines, n_samples)
        trials, n = afferent.n_driven(sc)
        n_s = n_samples or sc["scene"]["duration_ms"] * sc["sensor"]["sample_rate_hz"] / 1e3
        seconds += est["seconds"] + 2e-5 * trials * n_s + 1e-8 * n * trials * 200 ** 2
        nbytes = max(nbytes, est["bytes"] + 8.0 * trials * n_s * 40)
    lanes = max(1, min(workers, len(conds)))
    return {"bytes": nbytes * lanes, "seconds": seconds / lanes,
            "what": f"{len(conds)} condition(s) of {scene.n_trials()} trial(s) on "
                    f"{', '.join(engines)}"}


# --------------------------------------------------------------------------- the stimulus
def _merge_counts(agg: dict, counts: dict) -> None:
    """Add one trial's effect counts into ``agg`` (integers summed, floats their maximum,
    parameters kept)."""
    for e, cnt in counts.items():
        a = agg.setdefault(e, {})
        for k, v in cnt.items():
            if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
                a[k] = a.get(k, 0) + int(v)
            elif isinstance(v, float):
                a[k] = max(a.get(k, v), v)


def synthesize(scene):
    """Every trial of a texture scene: ``(classes, trial_class, S, infos, effect_counts)``
    (``S``: per trial the eight opponent signals ``(n_samples, 8)`` in V; ``infos``: the trial's
    drawn parameters, with its 16 tethers' outputs under ``"tethers_V"``) - what
    :func:`cuneate.sim.scenes.afferent.run` takes as a stimulus."""
    from ...golden import mems
    st, sen, sc = scene["stimulus"], scene["sensor"], scene["scene"]
    fs = sen["sample_rate_hz"]
    params = {e: sen[e] for e in sen["effects"]}
    rng = np.random.default_rng(sc["seed"])
    counts: dict = {}
    if st["kind"] == "recorded":
        return _recorded(scene, rng, params)
    from ...golden.sliding import prepare, slide_loads, surface_extent
    from ...golden.textures import surface, texture
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
            _merge_counts(counts, c)
            info["tethers_V"] = v
            trial_class.append(name)
            traces.append(mems.opponent_signals(v))
            infos.append(info)
    return classes, trial_class, traces, infos, counts


def _recorded(scene, rng, params):
    """A MEMS fingertip's recorded trials (``stimulus.file``, or one ``recordings`` table per
    trial): 16 tethers each, cut to the shortest recording (the trials share one core's run)."""
    from ...golden import mems
    from ..host.traces import TraceError, load_trace
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
        _merge_counts(counts, c)
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
    from ..host.driver import AfferentEncoding
    from .afferent import Neurons
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
    from ...golden.mems import pair_names
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
    from ..decode import decode_textures
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
    from .. import progress as prog
    from . import afferent
    arun = afferent.run(scene, engines, build_dir, progress, log, waves=waves,
                        synth=synthesize, build=build_neurons, in_turn=in_turn)
    t0 = time.perf_counter()
    with prog.step("decoding the textures (rate, rate + CV, Victor-Purpura; kNN, "
                   "leave-one-out)"):
        decoding = decode_run(scene, arun)
    return TextureRun(arun, decoding, channel_names(scene),
                      {"decode_s": time.perf_counter() - t0})


@dataclass
class GridRun:
    """A grid of sensing conditions: each condition's decoding rows per engine, and the
    spatial VP's table."""

    scene: object
    cells: list                         # one dict per condition
    spatial: list                       # rows across velocities / forces
    timing: dict
    kind: str = "texture"


def run_condition(cond: tuple, scene, engines, build_dir):
    """One cell of a grid (a worker's task): its scene's run, compacted to what the grid
    keeps: trains per engine and channel, the trials' classes, velocities and slide starts,
    the decoding's rows."""
    f, v = cond
    sc = condition_scene(scene, f, v)
    bd = Path(build_dir) / f"{f:g}mN_{v:g}mmps" if build_dir else None
    t0 = time.perf_counter()
    r = run_single(sc, engines, bd)
    a = r.afferent
    n = len(a.trial_class)
    return {"force_mN": f, "velocity_mm_per_s": v, "channels": r.channels,
            "trial_class": list(a.trial_class),
            "velocity": [i["velocity_mm_per_s"] for i in a.trial_info],
            "slide_ms": [i["phases_ms"]["slide"] for i in a.trial_info],
            "trains": {e: trains_by_channel(sp, n, r.channels) for e, sp in a.spikes.items()},
            "decoding": {e: d.to_dict() for e, d in r.decoding.items()},
            "spikes": {e: int(sum(len(s) for s in sp)) for e, sp in a.spikes.items()},
            "seconds": time.perf_counter() - t0}


def spatial_rows(scene, cells: list) -> list[dict]:
    """The spatial VP (and the temporal one beside it) across the velocities at the scene's
    force and across the forces at its velocity: spikes within the slide, as times from its
    start (ms) or positions (mm, times the trial's velocity)."""
    from ..decode import decode_conditions
    st, dec = scene["stimulus"], scene["decoder"]
    q_t = dec["q_per_s"] / 1000.0
    q_x = dec["q_per_mm"] if dec["q_per_mm"] is not None else \
        dec["q_per_s"] / st["velocity_mm_per_s"]
    rows = []
    for across, keep in (("velocities", lambda c: c["force_mN"] == st["force_mN"]),
                         ("forces", lambda c: c["velocity_mm_per_s"] == st["velocity_mm_per_s"])):
        sel = [c for c in cells if keep(c)]
        if len(sel) < 2:
            continue
        label = [f"{c['force_mN']:g} mN, {c['velocity_mm_per_s']:g} mm/s" for c in sel]
        for e in sel[0]["trains"]:
            y, cond = [], []
            t_tr = {ch: [] for ch in sel[0]["channels"]}
            x_tr = {ch: [] for ch in sel[0]["channels"]}
            for c, lab in zip(sel, label):
                y += c["trial_class"]
                cond += [lab] * len(c["trial_class"])
                for ch, trs in c["trains"][e].items():
                    for s, (t0, t1), vel in zip(trs, c["slide_ms"], c["velocity"]):
                        w = s[(s >= t0) & (s < t1)] - t0
                        t_tr[ch].append(w)
                        x_tr[ch].append(w * vel / 1000.0)
            classes = list(dict.fromkeys(y))
            for space, trains, q in (("time", t_tr, q_t), ("space", x_tr, q_x)):
                for r in decode_conditions(trains, y, classes, cond, q, dec["neighbours"]):
                    rows.append({"engine": e, "across": across, "conditions": label,
                                 "metric": space, "q": q,
                                 "q_unit": "per ms" if space == "time" else "per mm"} | r)
    return rows


def run_grid(scene, engines=None, build_dir=None, progress=False, log=None) -> GridRun:
    """Every condition of the scene's grid (Dask, :func:`cuneate.sim.sweep.dask_map`), then
    the spatial VP."""
    from .. import progress as prog
    from ..sweep import dask_connect, dask_map
    g = scene["grid"]
    names = list(engines or scene.engines)
    conds = conditions(scene)
    remote = dask_connect(g["scheduler"] or None)
    cells = {}
    t0 = time.perf_counter()
    with prog.step(f"running {len(conds)} sensing conditions", total=len(conds),
                   unit="condition") as st:
        def done(c, cell):
            cells[c] = cell
            st.update(1)
            st.note(f"{c[0]:g} mN, {c[1]:g} mm/s")
        dask_map(run_condition, conds, (scene, names, build_dir), done,
                 g["scheduler"] or None, g["workers"], remote)
    t1 = time.perf_counter()
    with prog.step("spatial VP across velocities and forces"):
        spatial = spatial_rows(scene, [cells[c] for c in conds])
    return GridRun(scene, [cells[c] for c in conds], spatial,
                   {"conditions_s": t1 - t0, "spatial_s": time.perf_counter() - t1,
                    "workers": "sync" if g["scheduler"] == "sync" else
                    (g["scheduler"] or f"local cluster of {g['workers']}")})


def run(scene, engines=None, build_dir=None, progress=False, log=None, waves=None,
        in_turn: int | None = None):
    """Run a texture scene: one condition (:class:`TextureRun`) or its grid
    (:class:`GridRun`)."""
    if is_grid(scene):
        if waves is not None or scene["run"]["waves"] or in_turn:
            raise ValueError("a grid of conditions runs each condition on its engines as a "
                             "whole (no waveforms, no trials in turn: run one condition)")
        return run_grid(scene, engines, build_dir, progress, log)
    return run_single(scene, engines, build_dir, progress, log, waves, in_turn)


# --------------------------------------------------------------------------- results
def _pct(x) -> str:
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


def _decoding_summary(d) -> dict:
    return d.to_dict()


def summary(run) -> dict:
    """The run as a JSON-ready dictionary (``run.json``)."""
    from ..provenance import provenance
    from ..report import summary_dict
    if isinstance(run, GridRun):
        return {"scene": run.scene.name, "source": run.scene.source, "kind": "texture grid",
                "cells": [{k: v for k, v in c.items() if k != "trains"} for c in run.cells],
                "spatial": run.spatial, "timing": run.timing, "seeds": SEEDS,
                "resolved_scene": run.scene.to_dict(),
                "provenance": provenance(seeds={"scene.seed": run.scene["scene"]["seed"],
                                                "stimulus.texture_seed":
                                                    run.scene["stimulus"]["texture_seed"]})}
    a = run.afferent
    out = summary_dict(a)
    out.update({"kind": "texture", "channels": run.channels,
                "accuracy": {e: d.accuracy for e, d in run.decoding.items()},
                "accuracy_is": "balanced accuracy of VP + kNN (leave-one-out), mean over the "
                               "channels each decoded alone (chance 1/textures)",
                "texture_decoding": {e: _decoding_summary(d) for e, d in run.decoding.items()},
                "seeds": SEEDS, "core": core_cost(run.scene, a),
                "trial_info": [{k: v for k, v in i.items() if k != "tethers_V"}
                               for i in a.trial_info]})
    out["timing"] = dict(out["timing"]) | run.timing
    out["provenance"]["seeds"]["stimulus.texture_seed"] = run.scene["stimulus"]["texture_seed"]
    return out


def _rows_text(d, e: str) -> list[str]:
    out = []
    for dec in ("VP", "rate + CV", "rate"):
        b, a, r = d.best(dec), d.row(dec, "all channels"), d.channel_range(dec)
        out.append(f"  {e:10s} {dec:9s} "
                   + (f"{_pct(r[0]):>5s} % over the channels ({_pct(r[1])}-{_pct(r[2])})"
                      if r else "-")
                   + (f", best {b.channel} {_pct(b.accuracy)}" if b else "")
                   + (f", all channels {_pct(a.accuracy)} %" if a and a.accuracy is not None
                      else "") + f"  (seeds: {SEEDS[dec]})")
    return out


def format_run(run) -> str:
    """The lines ``cuneate run`` prints for a texture scene."""
    from ..decode import confusions
    if isinstance(run, GridRun):
        return _format_grid(run)
    a = run.afferent
    sc = run.scene
    out = [f"{sc.name}: {len(a.classes)} textures x {sc['scene']['trials']} trials, "
           f"{len(a.neurons)} afferents ({len(run.channels)} channels a trial), engines "
           f"{', '.join(a.spikes)}"]
    first = next(iter(run.decoding.values()), None)
    if first is not None:
        out.append(f"  decoding: k = {first.neighbours} nearest neighbours, leave-one-out, "
                   f"balanced accuracy (chance {100 / max(1, len(a.classes)):.0f} %); VP q = "
                   f"{first.q_per_s:g}/s; window {first.window_ms[0]:g}-{first.window_ms[1]:g} "
                   f"ms")
    for e, d in run.decoding.items():
        if d.reason:
            s = a.saturations
            out.append(f"  {e:10s} NOT DECODED: {d.reason} (currents peak at "
                       f"{s['max_mV_per_ms']:.2f} mV/ms; an RS neuron needs about 3.8)")
            continue
        out += _rows_text(d, e)
        h = d.headline
        conf = confusions(h.protocol)
        if conf:
            out.append(f"  {'':10s} confusions of VP on {h.channel}: " + ", ".join(
                f"{t} taken for {p} {n}x" for t, p, n in conf[:6]))
        vt = d.vp_timing
        if vt:
            out.append(f"  {'':10s} VP: {len(vt)} matrices of {vt[0]['trains']} trains, "
                       f"{min(x['spikes'] for x in vt)}-{max(x['spikes'] for x in vt)} spikes, "
                       f"{1000 * np.mean([x['seconds'] for x in vt]):.1f} ms a matrix")
    turn = a.ran.get("in_turn")
    if turn:
        out.append(f"  trials in turn: {turn['trials_at_a_time']} at a time on the board's core, "
                   f"{turn['groups']} groups of {turn['ticks_a_group']} ticks, each from the "
                   f"state the last left")
    c = core_cost(sc, a)
    out.append(f"  core: {c['update_hz'] / 1e3:g} kHz (dt {c['dt_ms']:g} ms) at "
               f"{c['clock_hz'] / 1e6:g} MHz holds {c['neurons_per_core']} neurons "
               f"({c['neurons_per_core_at_16kHz']} at 16 kHz); this scene uses "
               f"{c['neurons_used']}")
    for k, v in a.agreement.items():
        out.append(f"  {k}: {v['identical_trains']}/{v['neurons']} identical trains, mean "
                   f"|spike count diff| {v['mean_abs_count_diff']:.2f}")
    board = a.counters.get("board") or {}
    if "link_budget" in board:
        from ..host.uart import format_budget
        out.append(f"  board link: {board['frames_sent']} frames to the device, "
                   f"{board['frames_received']} back, {board['frames_lost']} lost; line load:")
        out += [f"    {line}" for line in format_budget(board["link_budget"]["measured"])]
    n_sat = a.saturations.get("format_low", 0) + a.saturations.get("format_high", 0)
    if n_sat:
        out.append(f"  warning: {n_sat} of {a.saturations['values']} currents saturated to "
                   f"{a.saturations['format']}")
    return "\n".join(out)


def _grid_table(run, engine: str) -> tuple[list, list, dict]:
    """Forces, velocities and ``{(decoder, which): matrix}`` of balanced accuracies."""
    forces = sorted({c["force_mN"] for c in run.cells})
    vels = sorted({c["velocity_mm_per_s"] for c in run.cells})
    mats = {}
    for key in (("VP", "channels' mean"), ("VP", "all channels"), ("rate + CV", "channels' mean"),
                ("rate", "channels' mean")):
        m = np.full((len(forces), len(vels)), np.nan)
        for c in run.cells:
            d = c["decoding"].get(engine)
            if not d or not d["rows"]:
                continue
            if key[1] == "channels' mean":
                accs = [r["balanced_accuracy"] for r in d["rows"] if r["decoder"] == key[0]
                        and r["channel"] != "all channels" and r["balanced_accuracy"] is not None]
                acc = float(np.mean(accs)) if accs else None
            else:
                acc = next((r["balanced_accuracy"] for r in d["rows"]
                            if r["decoder"] == key[0] and r["channel"] == key[1]), None)
            if acc is not None:
                m[forces.index(c["force_mN"]), vels.index(c["velocity_mm_per_s"])] = acc
        mats[key] = m
    return forces, vels, mats


def grid_notes(run, engine: str) -> list[str]:
    """What the grid's heat map says against the seeds: cells above 85 %, and where the worst
    one lies."""
    forces, vels, mats = _grid_table(run, engine)
    m = mats[("VP", "channels' mean")]
    if np.all(np.isnan(m)):
        return [f"{engine}: no condition decoded"]
    i, j = np.unravel_index(np.nanargmin(m), m.shape)
    above = int(np.sum(m > 0.85))
    corner = forces[i] == forces[0] and vels[j] == vels[0]
    return [f"{engine}: {above} of {m.size} conditions above 85 % (VP, mean of the channels); the "
            f"worst, {100 * m[i, j]:.1f} %, at {forces[i]:g} mN and {vels[j]:g} mm/s"
            + (" - the slowest and weakest, as in the seeds" if corner else
               " - not the slowest and weakest corner the seeds report "
               f"({100 * m[0, 0]:.1f} % there)")]


def _format_grid(run) -> str:
    out = [f"{run.scene.name}: grid of {len(run.cells)} conditions "
           f"({run.timing['conditions_s']:.1f} s on {run.timing['workers']})"]
    for e in run.cells[0]["decoding"]:
        forces, vels, mats = _grid_table(run, e)
        out.append(f"  {e}: VP + kNN (leave-one-out), mean of the channels, balanced accuracy % "
                   f"(rows force mN, columns velocity mm/s)")
        out.append("    " + "".join(f"{v:>8g}" for v in [float("nan")] + vels)
                   .replace("nan", "   "))
        for i, f in enumerate(forces):
            out.append(f"    {f:>8g}" + "".join(
                f"{100 * x:8.1f}" if x == x else "       -"
                for x in mats[("VP", "channels' mean")][i]))
        out += ["  " + x for x in grid_notes(run, e)]
    for r in run.spatial:
        if r["channel"] != "all channels":
            continue
        out.append(f"  {r['engine']}: across {r['across']}, VP in {r['metric']} "
                   f"(q {r['q']:.3g} {r['q_unit']}), all channels, {r['protocol']}: "
                   f"{_pct(r['balanced_accuracy'])} %")
    return "\n".join(out)


# --------------------------------------------------------------------------- the report
def _fig_signals(run, out: Path, plt) -> list[tuple[str, str]]:
    a = run.afferent
    fs = run.scene["sensor"]["sample_rate_hz"]
    firsts = [a.trial_class.index(c) for c in a.classes]
    cols = min(5, len(firsts))
    rows = -(-len(firsts) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.4 * rows), squeeze=False,
                             sharex=True, sharey=True)
    for ax, t in zip(axes.flat, firsts):
        x = a.traces[t]
        tm = np.arange(x.shape[0]) * 1000.0 / fs
        for k in range(min(4, x.shape[1])):
            ax.plot(tm, 1e3 * x[:, k], lw=0.6, label=f"pair {k}")
        ph = a.trial_info[t].get("phases_ms", {}).get("slide")
        if ph:
            ax.axvspan(*ph, color="0.92", zorder=0)
        ax.set_title(a.trial_class[t], fontsize=8)
    for ax in axes.flat[len(firsts):]:
        ax.axis("off")
    axes[0][0].set_ylabel("S (mV)")
    axes[-1][0].set_xlabel("time (ms)")
    axes[0][0].legend(fontsize=6)
    fig.tight_layout()
    from ..report import save_figure
    save_figure(fig, out / "signals.png")
    fig, ax = plt.subplots(figsize=(8, 3.4))
    v = a.trial_info[firsts[0]]["tethers_V"]
    tm = np.arange(v.shape[0]) * 1000.0 / fs
    for ch in range(v.shape[1]):
        ax.plot(tm, 1e3 * v[:, ch], lw=0.6, label=f"{ch + 1}")
    ax.set(xlabel="time (ms)", ylabel="tether output (mV)",
           title=f"the 16 tethers, first trial of {a.trial_class[firsts[0]]}")
    ax.legend(fontsize=6, ncol=8)
    fig.tight_layout()
    save_figure(fig, out / "tethers.png")
    return [("tethers.png", "The 16 tethers' outputs (1-based channels), first trial"),
            ("signals.png", "Opponent signals S of the sliding direction (the seeds' 2-4, 5-7, "
                            "12-10, 15-13), first trial of each texture; grey: the slide")]


def _fig_decoding(run, e: str, d, out: Path, plt) -> list[tuple[str, str]]:
    from sklearn.metrics import ConfusionMatrixDisplay
    from ..report import save_figure
    names = []
    h = d.headline
    D = d.matrices[h.channel]
    y = run.afferent.trial_class
    fig, ax = plt.subplots(figsize=(6.2, 5.2))
    im = ax.imshow(D, cmap="viridis")
    fig.colorbar(im, ax=ax, label="Victor-Purpura distance")
    edges = [i for i in range(1, len(y)) if y[i] != y[i - 1]]
    for b in edges:
        ax.axhline(b - 0.5, color="w", lw=0.5)
        ax.axvline(b - 0.5, color="w", lw=0.5)
    mids = [(a + b - 1) / 2 for a, b in zip([0] + edges, edges + [len(y)])]
    ax.set_xticks(mids, [y[int(m)] for m in mids], rotation=60, fontsize=7)
    ax.set_yticks(mids, [y[int(m)] for m in mids], fontsize=7)
    ax.set_title(f"{e}: VP distances (q = {d.q_per_s:g}/s), {h.channel}", fontsize=9)
    fig.tight_layout()
    save_figure(fig, out / f"vp_matrix_{e}.png")
    names.append((f"vp_matrix_{e}.png", f"Victor-Purpura distances between every pair of "
                                        f"trials on {e}, channel {h.channel} (the seeds' "
                                        f"Fig. 3B): trials grouped by texture"))
    rows = [r for r in (d.best("rate"), d.best("rate + CV"), h, d.row("VP", "all channels"))
            if r is not None and r.protocol is not None]
    fig, axes = plt.subplots(1, len(rows), figsize=(5.0 * len(rows), 4.8), squeeze=False)
    for ax, r in zip(axes[0], rows):
        p = r.protocol
        ConfusionMatrixDisplay(p.confusion, display_labels=p.labels).plot(
            ax=ax, cmap="Blues", colorbar=False, xticks_rotation=60, values_format="d")
        ax.set_title(f"{e}: {r.decoder}, {r.channel}\nbalanced {_pct(p.balanced_accuracy)} % "
                     f"(chance {100 * p.chance_balanced:.0f} %)", fontsize=8)
        ax.tick_params(labelsize=6)
    fig.tight_layout()
    save_figure(fig, out / f"confusion_{e}.png")
    names.append((f"confusion_{e}.png", f"Confusion matrices on {e} (leave-one-out kNN): "
                                        f"rate, rate + CV and VP on their best channels, VP "
                                        f"on all channels"))
    return names


def _decoding_html(run) -> str:
    from ..decode import TEXTURE_DECODERS, confusions
    from ..report import html_table
    a = run.afferent
    head_rows, chan_rows, recall_rows, conf_rows, vp_rows = [], [], [], [], []
    for e, d in run.decoding.items():
        if d.reason:
            head_rows.append([e, "NOT DECODED", d.reason, "-", "-", "-"])
            continue
        for dec in ("VP", "rate + CV", "rate"):
            b, al, r = d.best(dec), d.row(dec, "all channels"), d.channel_range(dec)
            head_rows.append([e, dec, f"{_pct(r[0])} ({_pct(r[1])}-{_pct(r[2])})" if r else "-",
                              f"{_pct(b.accuracy)} ({b.channel})" if b else "-",
                              _pct(al.accuracy) if al else "-", SEEDS[dec]])
        for dec in TEXTURE_DECODERS:
            chan_rows.append([e, dec] + [(_pct(r.accuracy) if r.accuracy is not None
                                          else r.reason) if (r := d.row(dec, c)) else "-"
                                         for c in run.channels + ["all channels"]])
        h = d.headline
        recall_rows.append([e, h.channel] + [_pct(h.protocol.recall.get(c))
                                              for c in a.classes])
        conf_rows.append([e, h.channel, "; ".join(f"{t} taken for {p} ({n}x)"
                                                  for t, p, n in confusions(h.protocol))
                          or "none"])
        for x in d.vp_timing:
            vp_rows.append([e, x["what"], x["trains"], x["spikes"], f"{1000 * x['seconds']:.1f}"])
    chance = 100 / max(1, len(a.classes))
    return f"""<h2>Decoding: which texture, from the afferents' spike trains</h2>
<p>Each trial decided by its k = {next(iter(run.decoding.values())).neighbours} nearest
neighbours among all other trials (leave-one-out, scikit-learn); balanced accuracy = mean
per-texture recall, chance {chance:.0f} %. Rate: spikes per second in the window; rate + CV:
with the coefficient of variation of the ISIs (features scaled on the training trials); VP:
Victor-Purpura distance. "Best" is the channel decoding best, chosen on these same trials as
the seeds report it; "all channels" involves no choice (rates and CVs of every channel as one
vector, VP distances summed).</p>
{html_table(head_rows, ["engine", "decoder", "each channel alone: mean % (range)",
                        "best channel %", "all channels %", "seeds"])}
<h3>Per channel (balanced accuracy %)</h3>
{html_table(chan_rows, ["engine", "decoder"] + run.channels + ["all channels"])}
<h3>Per-texture recall of VP on the best channel (%)</h3>
{html_table(recall_rows, ["engine", "channel"] + list(a.classes))}
<h3>Confusions of VP on the best channel</h3>
{html_table(conf_rows, ["engine", "channel", "trials taken for another texture"])}
<h3>Victor-Purpura matrices (compiled, one per channel)</h3>
{html_table(vp_rows, ["engine", "channel", "trains", "spikes", "ms a matrix"])}"""


def write_report(run, out: Path) -> Path:
    """Write the spike files, figures, ``run.json`` and ``index.html`` into ``out``; returns
    the HTML path."""
    from .. import progress as prog
    from ..report import (agreement_html, engine_figures, files_html, fmt, html_table,
                          pyplot, ran_html, write_page)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if isinstance(run, GridRun):
        return _write_grid(run, out)
    from .afferent import write_spike_files
    a = run.afferent
    a.files["spikes"] = write_spike_files(a, out)
    with prog.step("writing the texture report"):
        plt = pyplot()
        figs = _fig_signals(run, out, plt)
        for e in a.spikes:
            engine_figures(a, e, out, plt)
            figs += [(f"raster_{e}.png", f"Spikes on {e}, one row per afferent, grouped by "
                                         f"texture"),
                     (f"isi_{e}.png", f"Inter-spike intervals on {e} per texture")]
        for e, d in run.decoding.items():
            if not d.reason:
                figs += _fig_decoding(run, e, d, out, plt)
        summ = summary(run)
        (out / "run.json").write_text(json.dumps(summ, indent=2, default=float))
    c = summ["core"]
    st = run.scene["stimulus"]
    body = f"""<p>Scene: {html.escape(run.scene.source)}. {len(a.trial_class)} trials of
{len(a.classes)} textures (specimens of synthesis seed {st['texture_seed']}), {len(a.neurons)}
SA afferents ({len(run.channels)} a trial), {a.n_ticks} ticks of {a.dt_ms:g} ms.</p>
{_decoding_html(run)}
<h2>The core at the scene's rate</h2>
<p>{c['update_hz'] / 1e3:g} kHz updates (dt {c['dt_ms']:g} ms, the seeds' step): at
{c['clock_hz'] / 1e6:g} MHz one core holds {c['neurons_per_core']} neurons (
{c['neurons_per_core_at_16kHz']} at the reference core's 16 kHz); this scene uses
{c['neurons_used']}.</p>
{agreement_html(a)}
{ran_html(a, summ['provenance'], [['decode textures', fmt(run.timing['decode_s'], 2)]])}
{files_html(a.files)}"""
    return write_page(out, run.scene.name, body, figs)


def _write_grid(run, out: Path) -> Path:
    from ..report import html_table, pyplot, save_figure, write_page
    plt = pyplot()
    figs = []
    for e in run.cells[0]["decoding"]:
        forces, vels, mats = _grid_table(run, e)
        fig, axes = plt.subplots(1, 4, figsize=(17, 3.8))
        for ax, (key, m) in zip(axes, mats.items()):
            im = ax.imshow(100 * m, cmap="RdYlGn", vmin=0, vmax=100, origin="lower")
            for (i, j), x in np.ndenumerate(m):
                ax.text(j, i, "-" if x != x else f"{100 * x:.0f}", ha="center", va="center",
                        fontsize=8)
            ax.set_xticks(range(len(vels)), [f"{v:g}" for v in vels])
            ax.set_yticks(range(len(forces)), [f"{f:g}" for f in forces])
            ax.set(xlabel="velocity (mm/s)", ylabel="force (mN)",
                   title=f"{e}: {key[0]}, {key[1]}")
        fig.colorbar(im, ax=axes, label="balanced accuracy %", shrink=0.8)
        save_figure(fig, out / f"grid_{e}.png")
        figs.append((f"grid_{e}.png", f"Decoding per sensing condition on {e} (kNN, "
                                      f"leave-one-out, balanced accuracy %; the seeds' heat "
                                      f"map is VP on its channel)"))
    cell_rows = []
    for c in run.cells:
        for e, d in c["decoding"].items():
            pc = d["per_channel"]
            allv = next((r["balanced_accuracy"] for r in d["rows"] if r["decoder"] == "VP"
                         and r["channel"] == "all channels"), None)
            cell_rows.append([f"{c['force_mN']:g}", f"{c['velocity_mm_per_s']:g}", e,
                              c["spikes"][e]] + [
                f"{_pct(pc[k]['mean'])} ({_pct(pc[k]['lowest'])}-{_pct(pc[k]['highest'])})"
                if pc.get(k) else "-" for k in ("rate", "rate + CV", "VP")]
                + [_pct(allv), d["reason"] or "", f"{c['seconds']:.1f}"])
    sp_rows = [[r["engine"], r["across"], r["metric"], f"{r['q']:.3g} {r['q_unit']}",
                r["channel"], r["protocol"], _pct(r["balanced_accuracy"]),
                f"{100 * r['chance']:.0f}", SEEDS[f"spatial, {r['across']}"]
                if r["metric"] == "space" else ""] for r in run.spatial]
    notes = [n for e in run.cells[0]["decoding"] for n in grid_notes(run, e)]
    body = f"""<p>Scene: {html.escape(run.scene.source)}. {len(run.cells)} sensing conditions,
each run as its own scene ({html.escape(str(run.timing['workers']))}, {run.timing['conditions_s']:.1f}
s) and decoded alone; then the spatial VP.</p>
<h2>Conditions</h2>
<ul>{''.join(f'<li>{html.escape(n)}</li>' for n in notes)}</ul>
{html_table(cell_rows, ["force mN", "velocity mm/s", "engine", "spikes",
                        "rate % (channels' mean, range)", "rate + CV %", "VP %",
                        "VP all channels %", "note", "run s"])}
<h2>Spatial VP across conditions</h2>
<p>Spikes within the slide, as times from its start (VP in time) or as positions on the
texture (time x the trial's velocity: VP in space, cost per mm). Pooled: each trial decided
by every other trial of every condition; leave one condition out: by the other conditions'
trials alone (the decoder never saw the condition it decides).</p>
{html_table(sp_rows, ["engine", "across", "VP in", "q", "channel", "protocol",
                      "balanced accuracy %", "chance %", "seeds"])}"""
    (out / "run.json").write_text(json.dumps(summary(run), indent=2, default=float))
    return write_page(out, run.scene.name, body, figs)
