"""Afferent scenes (grasp, slide, pulses and recorded stimuli): synthesize (or load) FBG traces,
drive Izhikevich afferents through the host front end, decode, compare engines.

Only what the scene calls for is computed:

* effects: :func:`cuneate.golden.tactile.apply_effects` calls only the listed effects;
* blocks: :data:`BLOCKS` maps a population model to the builder of its hardware configuration;
  only the models the scene uses are built, each sized to its neurons (a scene's trials are
  separate neurons of one core: one build and one run serve every trial);
* engines: :data:`ENGINES` maps an engine name to its runner; only the scene's engines run.

:func:`run` returns a :class:`SceneRun` whose ``ran`` lists exactly the effects, blocks and
engines computed, with wall time per stage and per engine.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...golden import izhikevich as golden
from ...golden.budget import BASE_BYTES, array_bytes
from ...golden.fbg import IIRFilter, design_bandpass
from ...hdl.izhikevich import PIPELINE_DEPTH
from ...hdl.izhikevich.range import search_estimate
from ...hdl.lib.config import MIN_NEURONS
from ...hdl.lib.fixed import QFormat
from .. import progress as prog
from ..engines.registry import ENGINES as ENGINE_TRAITS
from ..engines.registry import block_engines, engine_for, estimate_seconds
from ..engines.waves import FORMATS, Waves, wave_files
from ..fanout.scene import channel_plan, check_fanout_engines, fanout_transport, scene_fanout
from ..host.driver import AfferentEncoding, FbgDriver
from ..izhikevich.engines import engine_core
from ..network.scene import check_layer_engines, layer_estimate, run_layer, scene_layer
from ..report import format_run as fmt_run
from ..report import front_end_detail, summary_dict
from ..report import write_report as write
from ..spikes import write_spikes
from .runner import decode_engines, decoders_agreement, engines_agreement
from .scene import Scene
from .stimulus import synthesize

__all__ = ["SceneRun", "run", "BLOCKS", "ENGINES", "synthesize", "build_neurons",
           "front_end", "summary", "write_report", "format_run", "write_spike_files",
           "waves_request", "estimate", "n_driven", "core_config", "scene_channel_plan"]


@dataclass
class Neurons:
    """The scene's driven neurons, in core order (trial-major, then population, then grating)."""

    trial: list = field(default_factory=list)
    population: list = field(default_factory=list)
    grating: list = field(default_factory=list)
    preset: list = field(default_factory=list)
    encoding: list = field(default_factory=list)

    def __len__(self):
        return len(self.trial)


@dataclass
class SceneRun:
    """The result of an afferent scene (``kind = "afferent"``)."""

    scene: Scene
    classes: list
    trial_class: list
    traces: list                # per trial: (n_samples, channels) nm
    trial_info: list
    neurons: Neurons
    currents: np.ndarray        # (n_samples, n_neurons) float mV/ms
    saturations: dict
    config: object
    dt_ms: float
    n_ticks: int
    spikes: dict                # engine -> list of arrays (ms) per neuron
    counters: dict              # engine -> transport counters
    decoded: dict               # engine -> Decoded
    agreement: dict
    ran: dict
    timing: dict
    decode_agreement: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)   # "spikes": engine -> file, "waves": window
    # the cuneate layer: population, trial and index per neuron, spikes and counters by engine
    layer: dict = field(default_factory=dict)
    kind: str = "afferent"


# --------------------------------------------------------------------------- estimate
#: What a scene run holds beyond a bare process (the decoder's and the report's libraries and
#: figures): measured 284 MiB peak for the smallest scene.
REPORT_BYTES = 100 << 20


def n_driven(scene: Scene) -> tuple[int, int]:
    """``(trials, neurons)``: every trial of every class, and the driven Izhikevich neurons of
    all of them (the core holds them all)."""
    trials = scene.n_trials()
    return trials, trials * sum(p["size"] for p in scene.populations
                                if p["model"] == "izhikevich")


def estimate(scene: Scene, engines: list[str], n_samples: int | None = None) -> dict:
    """Memory (bytes) and time (s) of running ``scene`` on ``engines``, from its parameters
    (``n_samples``: the trace's length when known, else the scene's duration): the traces
    and their synthesis, the front end's arrays (shifts, currents, raw currents), the golden
    engine's per-tick currents, the batch engines' write schedules and the spikes; the state
    range search, each engine's updates (or cycles) at the registry's speed."""
    sen, hw = scene["sensor"], scene["hardware"]
    fs = sen["sample_rate_hz"]
    if n_samples is None:
        n_samples = round(scene["scene"]["duration_ms"] * fs / 1000.0)
    trials, n = n_driven(scene)
    hold = max(1, round(hw["update_hz"] / fs))
    n_ticks = float(n_samples) * hold
    n_core = max(n, MIN_NEURONS)
    per_sample = array_bytes(n_samples, n)
    nbytes = (BASE_BYTES + REPORT_BYTES + 4 * array_bytes(trials, n_samples, sen["channels"])
              + 6 * per_sample + 200.0 * n_ticks / 16e3 * n * 16)      # spikes at <= 200 Hz
    seconds = search_estimate(len({p["preset"] for p in scene.populations}), 2,
                              1000.0 / hw["update_hz"])["seconds"]
    seconds += 2e-6 * trials * n_samples * sen["channels"] + 1e-6 * n_samples * n
    for e in engines:
        if e == "golden":
            nbytes += 2 * array_bytes(n_ticks, n)    # held per tick, and the model's copy
        elif ENGINE_TRAITS[e].level == "rtl":
            nbytes += 48 * per_sample             # the write schedule as Python integers
        per_tick = n_core + PIPELINE_DEPTH + 8 if ENGINE_TRAITS[e].hdl else n_core
        seconds += estimate_seconds("izhikevich", e, n_ticks * per_tick)
    layer = layer_estimate(scene, trials, n_core, n_ticks, engines)
    nbytes, seconds = nbytes + layer[0], seconds + layer[1]
    return {"bytes": nbytes, "seconds": seconds, "ticks": n_ticks, "neurons": n,
            "what": f"{trials} trial(s) x {n // max(trials, 1)} neuron(s), {n_ticks:.3g} ticks "
                    f"on {', '.join(engines)}"}


# --------------------------------------------------------------------------- neurons, blocks
def _filter(fe, fs) -> IIRFilter:
    if fe["filter_b"] is not None:
        f = IIRFilter(b=fe["filter_b"], a=fe["filter_a"])
        f.require_stable()
        return f
    return design_bandpass(fe["filter_low_hz"], fe["filter_high_hz"], fs, fe["filter_order"],
                           fe["filter_kind"])


def build_neurons(scene: Scene, n_trials: int) -> Neurons:
    fe, fs = scene["frontend"], scene["sensor"]["sample_rate_hz"]
    filt = None
    nn = Neurons()
    encs = {}
    for p in scene.populations:
        if p["encoding"] == "FA":
            filt = filt or _filter(fe, fs)
            encs[p["name"]] = AfferentEncoding(
                "FA", p["gain"] if p["gain"] is not None else fe["gain_S"],
                fe["delta_lambda_unit_pm"], filt, fe["fa_rectify"], 0.0, fs)
        elif p["encoding"] == "SA":
            encs[p["name"]] = AfferentEncoding(
                "SA", p["gain"] if p["gain"] is not None else fe["sa_gain"], fe["sa_unit_pm"],
                None, "none", fe["sa_threshold_pm"] if p["threshold_pm"] is None
                else p["threshold_pm"], fs)
    for t in range(n_trials):
        for p in (p for p in scene.populations if p["model"] == "izhikevich"):
            for g in p["gratings"]:
                nn.trial.append(t)
                nn.population.append(p["name"])
                nn.grating.append(g)
                nn.preset.append(p["preset"])
                nn.encoding.append(encs[p["name"]])
    return nn


def build_izhikevich(scene: Scene, neurons: Neurons):
    """The Izhikevich core for the scene's Izhikevich neurons (one parameter set per preset),
    sized to them; refused if they do not fit the hardware clock's capacity."""
    hw = scene["hardware"]
    n = len(neurons)
    capacity = int(hw["clock_hz"] // hw["update_hz"])
    if n > capacity:
        raise ValueError(f"the scene needs {n} Izhikevich neurons but a core at "
                         f"{hw['clock_hz']:g} Hz / {hw['update_hz']:g} Hz holds {capacity}")
    core = scene_core(scene, neurons)
    presets = list(core["param_sets"])
    cfg = engine_core(core, n)
    return cfg, {"block": "izhikevich_core", "neurons": n, "core_neurons": cfg.n_neurons,
                 "capacity_at_clock": capacity, "param_sets": presets,
                 "current_format": str(cfg.I), "dt_ms": cfg.dt_ms}


def scene_core(scene: Scene, neurons: Neurons) -> dict:
    """The core keywords of ``neurons``: what the engines and a board for the scene share."""
    hw, presets = scene["hardware"], sorted(set(neurons.preset))
    return {"param_sets": tuple(presets), "update_hz": hw["update_hz"],
            "neuron_sets": [presets.index(p) for p in neurons.preset], "rounding": hw["rounding"],
            "current_format": QFormat(hw["current_int_bits"], hw["current_frac_bits"])}


#: Population model -> builder of its hardware configuration. Only the models a scene uses
#: are looked up and called.
BLOCKS = {"izhikevich": build_izhikevich}


def front_end(scene: Scene, neurons: Neurons, traces: list, infos: list, cfg):
    """The host driver for core ``cfg`` and the float currents (mV/ms) its front end computes
    from the traces, per sample ``(n_samples, n_neurons)`` (gaps held when the scene drops
    samples, zero outside the loading phase when its window says so), and the gaps held."""
    sen = scene["sensor"]
    on_gap = "hold" if "dropped_samples" in sen["effects"] else "error"
    drv = FbgDriver(cfg, neurons.encoding, sen["sample_rate_hz"],
                    scene["frontend"]["latency_ticks"], on_gap=on_gap)
    dl = np.stack([traces[t][:, g] for t, g in zip(neurons.trial, neurons.grating)], axis=1)
    x, gaps = drv.fill_gaps(dl)
    with np.errstate(over="ignore", invalid="ignore"):
        currents = drv.currents(x)
    bad = ~np.isfinite(currents)
    if bad.any():
        j, i = (int(v) for v in np.argwhere(bad)[0])
        raise ValueError(f"the front end's current of neuron {i} is {currents[j, i]!r} at sample "
                         f"{j} (shifts up to {float(np.max(np.abs(x))):.3g} nm): lower the front "
                         f"end's gain (frontend.gain_S, frontend.sa_gain, population gain)")
    if scene["frontend"]["window"] == "loading":
        # the front end sees the loading phase only (contact to stop), per trial
        t_ms = np.arange(dl.shape[0]) * 1000.0 / sen["sample_rate_hz"]
        for i, t in enumerate(neurons.trial):
            inf = infos[t]
            outside = (t_ms < scene["stimulus"]["contact_ms"]) | (t_ms > inf["stop_ms"])
            currents[outside, i] = 0.0
    return drv, currents, gaps


# --------------------------------------------------------------------------- engines
def run_golden(ctx) -> tuple[list, dict]:
    """Float64 golden model (forward Euler, same dt) on the unquantized currents, held per
    tick exactly as the driver holds them."""
    cfg, drv = ctx["config"], ctx["driver"]
    n = len(ctx["neurons"])
    params = [golden.to_params(p) for p in ctx["neurons"].preset]
    cur = drv.held(ctx["currents"], ctx["n_ticks"])
    try:
        r = golden.simulate(params, cur, n_steps=ctx["n_ticks"], n_neurons=n, dt_ms=cfg.dt_ms,
                            scheme="euler", progress=ctx.get("progress"))
    except golden.DivergenceError as exc:
        nn, i = ctx["neurons"], exc.neuron
        peak = float(np.max(np.abs(ctx["currents"][:, i])))
        raise ValueError(
            f"the golden engine diverged: neuron {i} (trial {nn.trial[i]}, population "
            f"{nn.population[i]!r}, grating {nn.grating[i]}) leaves |v|, |u| <= {exc.bound:g} at "
            f"t = {exc.t_ms:g} ms under front-end currents up to {peak:.3g} "
            f"mV/ms (the core saturates at {cfg.I.max_value:g}); lower the front end's gain "
            f"(frontend.gain_S, frontend.sa_gain, population gain) or the sensor effects' "
            f"size") from None
    return [np.asarray(s) for s in r.spikes_ms], {"spikes": int(sum(len(s) for s in
                                                                    r.spikes_ms))}


def _run_transport(engine):
    def run(ctx):
        kw = {"progress": ctx.get("progress")}
        if engine != "fixed":
            bd = ctx.get("build_dir")
            kw["build_dir"] = (Path(bd) / engine) if bd else None
        if engine in FORMATS and ctx.get("waves"):
            kw["waves"] = ctx["waves"]
        kw.update(ctx.get("engine_options", {}).get(engine, {}))
        impl = engine_for("izhikevich", engine, **kw)
        fan = ctx.get("fanout")                 # channels streamed, fanned out in front
        if fan is None:
            tr, drv, raw = impl.transport(), ctx["driver"], ctx["raw"]
        else:
            tr, drv, raw = fanout_transport(engine, fan, impl, kw), fan.driver, fan.raw
        layer = ctx.get("layer") if impl.layer == "chip" else None   # the network on chip
        try:
            tr.open(ctx["config"] if layer is None else layer.network)
            res = drv.stream(tr, None, ctx["n_ticks"], raw=raw)
        finally:
            tr.close()
        n = len(ctx["neurons"])
        if layer is not None:
            N, dt = layer.network.n_afferents, ctx["config"].dt_ms
            ctx["layer_spikes"][engine] = res.spikes.times_ms(dt, layer.n_targets, first=N)
        cnt = dict(res.counters)
        if getattr(tr, "sim_s", None) is not None:  # batch engines: the simulation alone
            cnt["simulate_ms"] = int(round(tr.sim_s * 1000))
        if hasattr(tr, "figures"):  # the board engine: cycles, bytes and frames on its line
            cnt.update({f"line_{k}": v for k, v in tr.figures().items()})
        return res.spikes.times_ms(ctx["config"].dt_ms, n), cnt
    return run


#: Engine name -> runner, for every engine the Izhikevich block runs on (the registry's list):
#: golden integrates the float currents, the others stream the quantized currents through the
#: host driver. Only the scene's engines are looked up and called.
ENGINES = {e: run_golden if e == "golden" else _run_transport(e)
           for e in block_engines("izhikevich")}


def _within(waves, n_ticks: int):
    """The waveform window cut to the run (``ValueError`` when it starts after it)."""
    return None if waves is None else waves.within(n_ticks)


def waves_request(scene: Scene, waves=None):
    """The waveform window of a run: ``waves`` when given, else the scene's ``run.waves``
    (a directory; relative to the current one), ``run.waves_start_tick`` and
    ``run.waves_ticks``; ``None`` when neither asks for waveforms."""
    if waves is not None or not scene["run"]["waves"]:
        return waves
    r = scene["run"]
    return Waves(Path(r["waves"]), r["waves_start_tick"], r["waves_ticks"])


def _build_blocks(scene: Scene, neurons: Neurons):
    """The core configuration of the scene's neurons and the description of every block
    built (one per population model)."""
    blocks, cfg = [], None
    for m in sorted({p["model"] for p in scene.populations} & set(BLOCKS)):
        cfg, desc = BLOCKS[m](scene, neurons)
        blocks.append(desc)
    return cfg, blocks


def core_config(scene: Scene, trials: int | None = None):
    """The core configuration a run of ``scene`` streams to (what a board must hold to run
    it: :class:`~cuneate.sim.link.pty.PtyBoard` serves one; ``trials``: of its first trials
    only), without running anything."""
    return _build_blocks(scene, build_neurons(scene, trials or n_driven(scene)[0]))[0]


def scene_channel_plan(scene: Scene):
    """The :class:`~cuneate.sim.fanout.scene.ChannelPlan` of a fan-out scene as a run builds
    it (every trial), without running an engine: what a board for the scene holds."""
    _, _, traces, infos, _ = synthesize(scene)
    neurons, cfg = build_neurons(scene, len(traces)), core_config(scene)
    drv = front_end(scene, neurons, traces, infos, cfg)[0]
    return channel_plan(scene, neurons, traces, infos, cfg, drv)


def run(scene: Scene, engines: list[str] | None = None, build_dir: Path | None = None,
        progress: bool = False, log=None, waves=None,
        engine_options: dict | None = None, in_turn: int | None = None, synth=None,
        build=None) -> SceneRun:
    """Run an afferent ``scene`` on its engines (or ``engines``); each stage reports through
    :mod:`cuneate.sim.progress` (and ``log``, if given, gets one line per stage). ``waves``
    (a :class:`~cuneate.sim.engines.waves.Waves` window, or the scene's ``run.waves``): the
    RTL engines (amaranth, icarus, verilator) dump it. ``engine_options``: more keywords for
    an engine's transport, by engine (``{"board": {"port": "/dev/ttyUSB0"}}``: the board
    engine on a programmed board, ``cuneate stream``). ``in_turn``: play the trials that many
    at a time on a core of that many, group after group (:mod:`.in_turn`). ``synth`` and
    ``build``: another kind's stimulus (``synth(scene)``, returning what :func:`synthesize`
    does) and neuron table (``build(scene, n_trials)``, as :func:`build_neurons`) run through
    the same machinery (texture scenes); only the afferent decoders ("tree", "knn") decode
    here.

    Its phases: the stimulus, the front end, the engines' context (trials in turn), the
    engines, the cuneate layer, decoding, the engines' agreement."""
    timing: dict = {}

    def say(msg):
        prog.say(msg)
        if log is not None:
            log(msg)
    t0 = time.perf_counter()
    names = list(engines or scene.engines)
    check_fanout_engines(scene, names)
    check_layer_engines(scene, names)
    classes, trial_class, traces, infos, effect_counts = _run_stimulus(
        scene, names, synth, say, timing, t0)
    build = build or build_neurons
    fe = _run_front_end(scene, names, traces, infos, build, in_turn, say, timing)
    neurons, cfg, blocks, currents, sat, n_ticks = (fe[k] for k in (
        "neurons", "config", "blocks", "currents", "sat", "n_ticks"))
    ctx = {"config": cfg, "driver": fe["driver"], "neurons": neurons, "currents": currents,
           "raw": fe["raw"], "n_ticks": n_ticks, "build_dir": build_dir,
           "waves": _within(waves_request(scene, waves), n_ticks),
           "engine_options": engine_options or {}, "fanout": fe["fanout"],
           "layer": fe["layer"], "layer_spikes": {}}
    turn, layer = None, fe["layer"]
    if in_turn:                                 # k trials at a time on the board's core
        from .in_turn import in_turn as turn_context
        nk = build(scene, in_turn)
        turn, ctx = turn_context(scene, ctx, len(traces), nk, _build_blocks(scene, nk)[0])
        layer = ctx["layer"]
        say(f"trials in turn: {turn.k} at a time, {turn.n_groups} groups")
    if layer is not None:
        blocks.append(layer.describe())
    for e in names:
        if e not in ENGINES:
            raise ValueError(f"unknown engine {e!r}; known: {', '.join(ENGINES)}")
    results = _run_engines(names, ctx, say, timing)
    ran_sp = {e: results[e][0] for e in names}        # the engines' own neurons
    spikes = {e: turn.unfold(s) for e, s in ran_sp.items()} if turn else ran_sp
    counters = {e: results[e][1] for e in names}
    if "board" in counters:
        _board_link_budget(scene, ctx, counters, ran_sp, cfg.update_hz)
    timing["engines_s"] = {e: results[e][2] for e in names}
    lay = _run_cuneate_layer(layer, ctx, names, ran_sp, turn, len(traces), timing)
    decoded = decode_engines(scene, spikes, neurons, lay, trial_class, classes, timing)
    agreement = engines_agreement(spikes, lay, cfg.dt_ms)
    dec_agree = decoders_agreement(decoded, scene["decoder"]["tolerance"])
    ran = {"effects": list(effect_counts) if effect_counts else
           ([] if scene["stimulus"]["kind"] == "recorded" else ["strain"]),
           "effect_counts": effect_counts, "blocks": blocks, "engines": list(spikes),
           "front_end": sorted({f"{e.mode}" for e in neurons.encoding}),
           "front_end_detail": front_end_detail(scene, neurons),
           "stimulus": scene["stimulus"]["kind"]} | ({"in_turn": turn.describe()} if turn else {})
    files = wave_files(ctx["waves"], list(spikes), cfg.clock_hz)
    return SceneRun(scene, classes, trial_class, traces, infos, neurons, currents, sat, cfg,
                    cfg.dt_ms, n_ticks, spikes, counters, decoded, agreement, ran, timing,
                    dec_agree, files=files, layer=lay)


def _run_stimulus(scene: Scene, names: list, synth, say, timing: dict, t0: float):
    """The stimulus (``synth`` or :func:`synthesize`): classes, each trial's class, traces,
    their infos and the effects' counts; a recorded one's budget checked now its length is
    known (``t0``: the run's start)."""
    n_grasps = scene["scene"]["trials"] * len(scene.classes())
    with prog.step(f"synthesizing the stimulus ({n_grasps} trial(s))"):
        classes, trial_class, traces, infos, effect_counts = (synth or synthesize)(scene)
    timing["stimulus_s"] = time.perf_counter() - t0
    if scene["stimulus"]["kind"] == "recorded":     # its length is known now
        from .runner import check_budget
        check_budget(scene, names, n_samples=traces[0].shape[0])
    say(f"stimulus: {len(traces)} trial(s) of {traces[0].shape[0]} samples x "
        f"{traces[0].shape[1]} grating(s) ({timing['stimulus_s']:.2f} s)")
    return classes, trial_class, traces, infos, effect_counts


def _run_front_end(scene: Scene, names: list, traces, infos, build, in_turn, say,
                   timing: dict) -> dict:
    """The neurons, the core configuration and blocks, the driver's currents (quantized, with
    their saturation counts, the gaps held and the samples past the run's end counted), the
    fan-out and the cuneate layer (none in turn: the board's is built then)."""
    t0 = time.perf_counter()
    with prog.step("front end: filtering and quantizing the currents"):
        neurons = build(scene, len(traces))
        cfg, blocks = _build_blocks(scene, neurons)
        drv, currents, gaps = front_end(scene, neurons, traces, infos, cfg)
        raw, sat = drv.quantize(currents)
        fan = scene_fanout(scene, neurons, traces, infos, cfg, drv, names, blocks)
        # in turn, the board's layer (its trials') is the one built and run
        layer = None if in_turn else scene_layer(scene, neurons, cfg)
    sat["gaps_held"] = gaps
    n_ticks = currents.shape[0] * drv.hold_ticks
    # samples whose tick (j R + L) falls at or after the run's end are never applied: counted
    sat["samples"] = int(currents.shape[0])
    sat["samples_past_end"] = int(np.count_nonzero(
        drv.tick_of_sample(np.arange(currents.shape[0])) >= n_ticks))
    if sat["samples_past_end"]:
        say(f"warning: latency of {drv.latency_ticks} ticks puts {sat['samples_past_end']} of "
            f"{sat['samples']} samples past the run's end: never applied")
    timing["front_end_s"] = time.perf_counter() - t0
    return {"neurons": neurons, "config": cfg, "blocks": blocks, "driver": drv,
            "currents": currents, "raw": raw, "sat": sat, "fanout": fan, "layer": layer,
            "n_ticks": n_ticks}


def _run_engines(names: list, ctx: dict, say, timing: dict) -> dict:
    """Each engine on ``ctx``: ``{engine: (spikes, counters, seconds)}``. HDL simulators run
    in their own processes: they start first, in the background (one at a time, the machine's
    other core serves the Python engines), overlapped with the Python engines."""
    results: dict = {}

    def one(e):
        t0 = time.perf_counter()
        with prog.step(f"engine {e}", total=ctx["n_ticks"], unit="tick") as st:
            sp, cnt = ENGINES[e](dict(ctx, progress=st.set, step=st))
        results[e] = (sp, cnt, time.perf_counter() - t0)
        say(f"engine {e}: {sum(len(x) for x in sp)} spikes ({results[e][2]:.1f} s)")

    background = [e for e in names if ENGINE_TRAITS[e].background]
    t_all = time.perf_counter()
    pool = None
    if background:
        from concurrent.futures import ThreadPoolExecutor

        def hdl():
            for e in background:
                one(e)
        pool = ThreadPoolExecutor(max_workers=1)
        fut = pool.submit(hdl)
    try:
        for e in names:
            if e not in background:
                one(e)
    finally:
        if pool is not None:
            try:
                fut.result()
            finally:
                pool.shutdown()
    timing["engines_wall_s"] = time.perf_counter() - t_all
    return results


def _board_link_budget(scene: Scene, ctx: dict, counters: dict, ran_sp: dict,
                       update_hz: float) -> None:
    """The board engine's UART link budget for the run (in its counters; ``update_hz``: the
    scene's core's)."""
    from ..host.uart import run_budget
    f, c = ctx["fanout"], ctx["config"]
    written = (f.config.n_channels, f.config.S.width) if f else (c.n_neurons, c.I.width)
    counters["board"]["link_budget"] = run_budget(
        counters["board"], ctx["n_ticks"] / update_hz, *written,
        scene["sensor"]["sample_rate_hz"], update_hz,
        sum(map(len, ran_sp["board"])) + sum(map(len, ctx["layer_spikes"].get("board", []))))


def _run_cuneate_layer(layer, ctx: dict, names: list, ran_sp: dict, turn, n_trials: int,
                       timing: dict) -> dict:
    """The cuneate layer's spikes on each engine (those its engine did not run alongside
    come from its own afferents' spikes), by trial and index; ``{}`` without a layer."""
    if layer is None:
        return {}
    t0 = time.perf_counter()
    M = layer.per_trial
    lay = {"population": layer.population, "spikes": dict(ctx["layer_spikes"]),
           "trial": [t for t in range(n_trials) for _ in range(M)],
           "index": list(range(M)) * n_trials, "counters": {}}
    for e in names:
        if e not in lay["spikes"]:
            with prog.step(f"cuneate layer on {e} ({layer.n_targets} neurons)"):
                lay["spikes"][e], lay["counters"][e] = run_layer(
                    e, ctx["layer"], ran_sp[e], ctx["n_ticks"])
    if turn:
        lay["spikes"] = {e: turn.unfold(s, layer.per_trial) for e, s in lay["spikes"].items()}
    timing["layer_s"] = time.perf_counter() - t0
    return lay


# --------------------------------------------------------------------------- results
def summary(run: SceneRun) -> dict:
    """The run as a JSON-ready dictionary (``run.json``)."""
    return summary_dict(run)


def write_spike_files(run: SceneRun, out: Path) -> dict:
    """Write ``spikes_<engine>.npz`` per engine into ``out`` (:mod:`cuneate.sim.spikes`:
    neuron table population, trial, grating, class; the cuneate layer's neurons after the
    afferents, grating -1); returns ``{engine: file name}``."""
    nn, lay = run.neurons, run.layer
    pop, trial, grating = list(nn.population), list(nn.trial), list(nn.grating)
    if lay:
        pop += [lay["population"]] * len(lay["trial"])
        trial += lay["trial"]
        grating += [-1] * len(lay["trial"])
    files = {}
    for e, trains in run.spikes.items():
        name = f"spikes_{e}.npz"
        write_spikes(Path(out) / name, list(trains) + list(lay["spikes"][e] if lay else []), e,
                     run.n_ticks * run.dt_ms, pop, trial, grating,
                     [run.trial_class[t] for t in trial], run.dt_ms)
        files[e] = name
    return files


def write_report(run: SceneRun, out: Path) -> Path:
    """Write the spike files, ``index.html``, ``run.json`` and figures into ``out``; returns
    the HTML path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    run.files["spikes"] = write_spike_files(run, out)
    w = run.files.get("waves")
    if w:
        for x in w["files"].values():
            for k in ("dump", "gtkw"):
                x[k] = os.path.relpath(x[k], out.resolve())
    return write(run, out)


def format_run(run: SceneRun) -> str:
    """The lines ``cuneate run`` prints for an afferent scene."""
    return fmt_run(run)
