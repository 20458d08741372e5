"""Running a scene of any kind, and what every kind compares between engines.

:func:`run_scene` looks the scene's kind up in the registry (:mod:`cuneate.sim.scenes.registry`)
and runs it with the kind's module; :func:`agreement` compares two engines' spike trains,
:func:`engines_agreement` every engine's with the reference's, :func:`decode_engines` decodes
each engine's spikes and :func:`decoders_agreement` holds their accuracies to golden's.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...golden import budget, metrics
from .. import progress as prog
from ..decode import decode_trials, decoded_neurons
from .registry import kind_module

__all__ = ["run_scene", "agreement", "kind_of", "check_budget", "EngineRuns", "run_engines",
           "decode_engines", "engines_agreement", "decoders_agreement"]


def kind_of(run_or_scene) -> str:
    """The scene kind of a scene or of a run."""
    return getattr(run_or_scene, "kind", "afferent")


def run_scene(scene, engines: list[str] | None = None, build_dir: Path | None = None,
              progress: bool = False, log=None, waves=None, in_turn: int | None = None):
    """Run ``scene`` on its engines (or ``engines``) with its kind's module; returns that
    kind's run (``run.kind`` names the kind; ``run.ran`` lists exactly what was computed).
    ``progress``: show what each stage does (:mod:`cuneate.sim.progress`, on stderr) when no
    command has chosen how yet. ``waves``: a :class:`~cuneate.sim.engines.waves.Waves` window
    (afferent scenes; the others refuse it). ``in_turn``: an afferent scene's trials that many
    at a time, group after group (:mod:`cuneate.sim.scenes.in_turn`; texture scenes too).

    The kind's estimate of the run's memory and time is checked first
    (:func:`check_budget`): a run that would exhaust the machine's memory or exceed the time
    limit in force is refused before anything is allocated."""
    if progress and prog.mode() == "quiet":
        prog.configure("auto")
    check_budget(scene, list(engines or scene.engines))
    mod = kind_module(scene.kind)
    if scene.kind == "afferent":
        return mod.run(scene, engines, build_dir, progress, log, waves=waves, in_turn=in_turn)
    if scene.kind == "texture":                 # its afferents on the afferent machinery
        return mod.run(scene, engines, build_dir, progress, log, waves=waves, in_turn=in_turn)
    if waves is not None or scene["run"]["waves"]:
        raise ValueError(f"waveforms are written for afferent and texture scenes (the "
                         f"Izhikevich core); a {scene.kind} scene has none")
    if in_turn is not None:
        raise ValueError(f"trials in turn are an afferent scene's; a {scene.kind} scene has "
                         f"none")
    return mod.run(scene, engines, build_dir, progress, log)


def check_budget(scene, engines: list[str], **known) -> dict:
    """The kind's ``estimate(scene, engines, **known)`` checked against the memory and time
    limits (:func:`cuneate.golden.budget.check`; ``BudgetError`` refuses, one line)."""
    est = kind_module(scene.kind).estimate(scene, engines, **known)
    budget.check(f"the scene ({est['what']})", est["bytes"], est["seconds"],
                 "fewer trials or neurons, a shorter scene.duration_ms, a lower update rate "
                 "or faster engines")
    return est


@dataclass
class EngineRuns:
    """A scene run on several engines (:func:`run_engines`): the scene, each engine's result,
    what ran, the wall times; ``files``: what was written (``"spikes"``: engine -> file)."""

    scene: object
    results: dict
    ran: dict
    timing: dict
    files: dict = field(default_factory=dict, kw_only=True)


def run_engines(names: list[str], run, build_dir: Path | None = None, log=None,
                progress: bool = False) -> tuple[dict, dict]:
    """``(results, seconds)``: ``results[e] = run(e, its build dir)`` and the seconds it took,
    for each engine ``e`` of ``names`` in turn; a background engine (an HDL simulator) builds
    in ``build_dir/<e>`` when ``build_dir`` is given, any other gets None. ``log(e, result,
    seconds)`` after each; ``progress``: a bar over the engines."""
    from ..engines.registry import ENGINES
    results, seconds = {}, {}
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(names), desc="engines", unit="engine", leave=False)
    for e in names:
        t0 = time.perf_counter()
        bd = Path(build_dir) / e if build_dir and ENGINES[e].background else None
        results[e] = run(e, bd)
        seconds[e] = time.perf_counter() - t0
        if log:
            log(e, results[e], seconds[e])
        if bar:
            bar.update(1)
    if bar:
        bar.close()
    return results, seconds


def agreement(a: list, b: list, dt_ms: float) -> dict:
    """How the spike trains ``a`` and ``b`` (one per neuron, ms) agree: totals, identical
    trains, spike-count differences, Victor-Purpura distance at q = 5/s
    (:data:`~cuneate.golden.metrics.VP_Q_PER_MS`, the sweep's and the README's) and the
    fraction of spikes within one tick of ``dt_ms``."""
    cnt_a = np.array([len(s) for s in a])
    cnt_b = np.array([len(s) for s in b])
    vp = [metrics.victor_purpura(x, y, metrics.VP_Q_PER_MS) for x, y in zip(a, b)]
    within = [metrics.fraction_within(x, y, dt_ms) for x, y in zip(a, b)]
    within = [w for w in within if w is not None]
    return {"neurons": len(a), "spikes_a": int(cnt_a.sum()), "spikes_b": int(cnt_b.sum()),
            "identical_trains": int(sum(np.array_equal(x, y) for x, y in zip(a, b))),
            "mean_abs_count_diff": float(np.mean(np.abs(cnt_a - cnt_b))) if a else 0.0,
            "max_abs_count_diff": int(np.max(np.abs(cnt_a - cnt_b))) if a else 0,
            "mean_victor_purpura": float(np.mean(vp)) if vp else 0.0,
            "victor_purpura_q_per_s": 1000.0 * metrics.VP_Q_PER_MS,
            "fraction_within_1_tick": float(np.mean(within)) if within else None}


def engines_agreement(spikes: dict, lay: dict, dt_ms: float) -> dict:
    """Each engine's spike trains against the reference ("fixed" if it ran, else the first
    engine), the afferents' and the cuneate layer's."""
    out = {}
    ref = "fixed" if "fixed" in spikes else next(iter(spikes))
    for e in spikes:
        if e == ref:
            continue
        out[f"{e} vs {ref}"] = agreement(spikes[e], spikes[ref], dt_ms)
        if lay:
            out[f"{lay['population']}: {e} vs {ref}"] = agreement(
                lay["spikes"][e], lay["spikes"][ref], dt_ms)
    return out


def decoders_agreement(decoded: dict, tol: float) -> dict:
    """Each engine's decoding accuracy against golden's, within ``decoder.tolerance``."""
    dec_agree = {}
    if "golden" in decoded:
        for e, d in decoded.items():
            g = decoded["golden"]
            if e == "golden" or d.accuracy is None or g.accuracy is None:
                continue
            diff = abs(d.accuracy - g.accuracy)
            dec_agree[f"{e} vs golden"] = {"difference": diff, "tolerance": tol,
                                           "within": bool(diff <= tol)}
    return dec_agree


def decode_engines(scene, spikes: dict, neurons, lay: dict, trial_class, classes,
                   timing: dict) -> dict:
    """Each engine's spikes decoded (the afferent decoders, "tree" and "knn"; none else)."""
    t0 = time.perf_counter()
    dec = scene["decoder"]
    decoded = {}
    if dec["kind"] in ("tree", "knn"):
        for e, sp in spikes.items():
            d_sp, d_trial, d_index = decoded_neurons(dec["population"], sp, neurons, lay, e)
            noun = scene.trial_noun
            with prog.step(f"decoding {e} ({dec['kind']} on {dec['features']} features of "
                           f"{dec['population'] or 'every afferent'}, {noun}-grouped"
                           + (" and published protocols)" if dec["features"] == "isi"
                              else ")")):
                decoded[e] = decode_trials(
                    d_sp, d_trial, d_index, trial_class, classes, dec["kind"],
                    dec["features"], dec["cv_folds"], dec["max_depth"], dec["neighbours"],
                    scene["scene"]["seed"], dec["window_ms"], dec["decision"],
                    dec["permutations"], noun=noun)
    timing["decode_s"] = time.perf_counter() - t0
    return decoded
