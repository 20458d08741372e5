"""The learning protocol of the seed works' thesis (brief section 5b) on the texture fingertip:
afferent responses, jittered presentations, a cuneate layer learning on every engine, and what
it learnt.

1. **Afferent responses** (:func:`templates`): each stimulus (textures and shapes of
   :mod:`cuneate.golden.textures`) slid once under the MEMS fingertip
   (:func:`cuneate.sim.scenes.texture_trials.synthesize`); each of the 16 tethers drives
   ``len(gains)`` SA Izhikevich afferents, ``I = g K v`` where ``v >= S_th`` (``K`` =
   ``frontend.sa_gain``, ``g`` one of ``learning.afferent_gains``), float64 forward Euler at
   the scene's ``hardware.update_hz``: 16 x 5 = 80 afferents, one spike train each - the
   stimulus's template.
2. **Presentations** (:func:`protocol_presentations`): the test presentations
   (``test_presentations`` of each stimulus, in stimulus order), the training presentations
   (``presentations`` of each stimulus in one fixed pseudo-random order, ``order_seed``), the
   same test presentations again; every spike jittered (Gaussian, ``jitter_ms``) within
   ``window_ms`` of its template, then ``gap_ms`` of silence (:func:`cuneate.golden
   .cuneate_layer.presentations`). One sequence: the layer learns only in the training part
   (each of its windows ends with the step; the test windows only clear the drives).
3. **The layer** (:func:`layer_config`): ``cns`` CNs of ``synapses_per_cn`` synapses, each to
   an afferent drawn at random (``anatomy_seed``), initial weights uniform in
   ``[0, initial_weight_max]``, AIDP with the ``[learning]`` rule's parameters.
4. **What it learnt** (:func:`analyse`): the weights before and after (the fraction of strong
   synapses, ``w > strong_fraction w_max``, per CN), learning curves, each CN's selectivity
   (its mean spike count per stimulus), and the stimuli decoded from the CN population before
   and after learning (kNN, leave-one-out, on the CNs' spike counts and on Victor-Purpura
   distances summed over the CNs, :func:`cuneate.sim.decode.decode_textures`; each CN alone
   too, the anchor's per-neuron figure).
"""

from __future__ import annotations

import numpy as np

__all__ = ["templates", "protocol_presentations", "layer_config", "analyse", "rule_of",
           "PHASES", "strong_counts", "selectivity", "agreement"]

#: the protocol's phases, in order
PHASES = ("before", "training", "after")


def rule_of(lp: dict):
    """The AIDP rule of a scene's ``[learning]`` table."""
    from ...golden.aidp import AidpParams
    return AidpParams(tau_rise_ms=lp["tau_rise_ms"], tau_decay_ms=lp["tau_decay_ms"],
                      tau_1_ms=lp["tau_1_ms"], latency_ms=lp["latency_ms"], theta=lp["theta"],
                      eta=lp["eta"], w_max=lp["w_max"], w_pot=lp["w_pot"], w_dep=lp["w_dep"],
                      slope=lp["slope"])


def templates(scene) -> dict:
    """Every stimulus's afferent responses: ``{"classes", "trains"}`` (per stimulus, one
    spike-time array per afferent, ms), ``"afferents"`` (tether, gain of each), ``"tethers"``
    (per stimulus the 16 tethers' outputs, V) and the synthesis's effect counts."""
    from ...golden import izhikevich as giz
    from ..scenes.texture_trials import synthesize
    lp, fe, hw = scene["learning"], scene["frontend"], scene["hardware"]
    fs = scene["sensor"]["sample_rate_hz"]
    classes, trial_class, _S, infos, counts = synthesize(scene)
    tethers = scene.populations[0]["gratings"]
    gains = lp["afferent_gains"]
    hold = int(round(hw["update_hz"] / fs))
    dt = 1000.0 / hw["update_hz"]
    thr = fe["sa_threshold_mV"] / 1000.0
    trains = []
    for info in infos:
        v = info["tethers_V"][:, tethers]
        cur = np.concatenate([np.where(v >= thr, fe["sa_gain"] * g * v, 0.0)[:, :, None]
                              for g in gains], axis=2).reshape(v.shape[0], -1)
        cur = np.nan_to_num(cur)
        I = np.repeat(cur, hold, axis=0)
        r = giz.simulate(scene.populations[0]["preset"], I, n_steps=I.shape[0],
                         n_neurons=I.shape[1], dt_ms=dt)
        trains.append([np.asarray(s, dtype=np.float64) for s in r.spikes_ms])
    aff = [(t, g) for t in tethers for g in gains]
    return {"classes": list(classes), "trial_class": list(trial_class), "trains": trains,
            "afferents": aff, "tethers": [i["tethers_V"] for i in infos],
            "effect_counts": counts, "dt_ms": dt}


def protocol_presentations(scene, tpl: dict):
    """The protocol's one sequence of presentations and its phases: ``(pres, learn flags,
    phase of each presentation)``."""
    from ...golden.cuneate_layer import presentations
    lp, sc = scene["learning"], scene["scene"]
    classes = tpl["trial_class"]
    n_cls = len(classes)
    rng = np.random.default_rng(lp["order_seed"])
    train = np.repeat(np.arange(n_cls), lp["presentations"])
    rng.shuffle(train)
    test = np.repeat(np.arange(n_cls), lp["test_presentations"])
    dt = 1000.0 / lp["update_hz"]
    win = tuple(lp["window_ms"])
    # the test presentations are the same jittered spikes before and after learning
    t = presentations(tpl["trains"], test, win, dt, lp["jitter_ms"], lp["gap_ms"],
                      [sc["seed"], 1])
    tr = presentations(tpl["trains"], train, win, dt, lp["jitter_ms"], lp["gap_ms"],
                       [sc["seed"], 2])
    idx = np.concatenate([np.arange(t.n), t.n + np.arange(tr.n), np.arange(t.n)])
    both = _concat(t, tr)
    seq = both.select(idx)
    seq.merged = 2 * t.merged + tr.merged
    phase = np.array(["before"] * t.n + ["training"] * tr.n + ["after"] * t.n)
    learn = phase == "training"
    return seq, learn, phase


def _concat(a, b):
    from ...golden.cuneate_layer import Presentations
    off = np.concatenate([a.offsets, a.offsets[-1] + b.offsets[1:]])
    return Presentations(np.concatenate([a.ticks, b.ticks]),
                         np.concatenate([a.sources, b.sources]), off, a.n_ticks,
                         a.window_ticks, np.concatenate([a.order, b.order]), a.dt_ms)


def n_afferents(scene) -> int:
    """A learning scene's afferents: each listed tether at each gain."""
    return len(scene.populations[0]["gratings"]) * len(scene["learning"]["afferent_gains"])


def layer_config(scene, n_sources: int | None = None):
    """The layer's :class:`~cuneate.hdl.plasticity.PlasticityConfig` of a scene
    (``n_sources``: its afferents, :func:`n_afferents` when not given)."""
    if n_sources is None:
        n_sources = n_afferents(scene)
    from ...hdl.plasticity import PlasticityConfig
    lp, hw = scene["learning"], scene["hardware"]
    rng = np.random.default_rng(lp["anatomy_seed"])
    M, K = lp["cns"], lp["synapses_per_cn"]
    src = np.array([np.sort(rng.choice(n_sources, K, replace=False)) for _ in range(M)])
    w0 = rng.uniform(0.0, lp["initial_weight_max"], (M, K))
    return PlasticityConfig(
        n_sources=n_sources, sources=src, weights=w0, rule=rule_of(lp),
        tau_syn_ms=lp["tau_syn_ms"], g_inh=lp["g_inh"], current_limit=lp["current_limit"],
        param_sets=(lp["cn_preset"],), clock_hz=hw["clock_hz"], update_hz=lp["update_hz"],
        rounding=hw["rounding"])


def strong_counts(w, w_max: float, fraction: float) -> np.ndarray:
    """Strong synapses (``w > fraction w_max``) per CN."""
    return np.count_nonzero(np.asarray(w) > fraction * w_max, axis=1)


def selectivity(counts, classes_of, n_classes: int) -> dict:
    """Each CN's mean spike count per stimulus (``(M, n_classes)``), its preferred stimulus
    and its selectivity index ``(r_pref - mean(r_others)) / (r_pref + mean(r_others))`` (0 for
    a silent CN)."""
    counts = np.asarray(counts, dtype=np.float64)
    y = np.asarray(classes_of)
    mean = np.array([counts[y == c].mean(axis=0) if np.any(y == c) else
                     np.zeros(counts.shape[1]) for c in range(n_classes)]).T
    pref = mean.argmax(axis=1)
    top = mean.max(axis=1)
    others = (mean.sum(axis=1) - top) / max(1, n_classes - 1)
    si = np.divide(top - others, top + others, out=np.zeros_like(top),
                   where=(top + others) > 0)
    return {"mean_counts": mean, "preferred": pref, "index": si}


def analyse(scene, tpl: dict, pres, phase, cfg, runs: dict) -> dict:
    """What each engine's layer learnt (see the module docstring)."""
    from ..decode import decode_textures
    lp, dec = scene["learning"], scene["decoder"]
    classes = tpl["trial_class"]
    n_cls = len(classes)
    win = pres.window_ticks * pres.dt_ms
    w_max = cfg.rule.w_max
    frac = lp["strong_fraction"]
    out = {}
    for e, r in runs.items():
        res: dict = {"engine": e, "seconds": r.seconds}
        trains = r.trains(pres.dt_ms, pres.window_ticks)
        for ph in ("before", "after"):
            idx = np.flatnonzero(phase == ph)
            y = [classes[c] for c in pres.order[idx]]
            tr = {f"CN {j}": [trains[p][j] for p in idx] for j in range(cfg.n_targets)}
            res[f"decoding_{ph}"] = decode_textures(tr, y, classes, (0.0, win),
                                                    dec["q_per_s"], dec["neighbours"])
            res[f"selectivity_{ph}"] = selectivity(r.counts[idx], pres.order[idx], n_cls)
        tr_idx = np.flatnonzero(phase == "training")
        res["training_counts"] = r.counts[tr_idx].mean(axis=1)
        w0 = r.snapshots[0][1] if r.snapshots else cfg.weights_real
        res["weights_before"], res["weights_after"] = np.asarray(w0), np.asarray(r.weights)
        res["strong_before"] = strong_counts(w0, w_max, frac)
        res["strong_after"] = strong_counts(r.weights, w_max, frac)
        first = int(tr_idx[0]) if tr_idx.size else 0
        curve = [(i - first, float(np.mean(np.asarray(w) > frac * w_max)),
                  float(np.mean(np.asarray(w))))
                 for i, w in r.snapshots if first <= i <= first + tr_idx.size]
        res["curve"] = curve
        res["step"] = r.extra.get("step")
        res["clamp_counts"] = r.clamp_counts
        out[e] = res
    return out


def agreement(runs: dict, reference: str = "fixed", w_max: float = 1.0,
              fraction: float = 0.5) -> dict:
    """How each engine's result compares with ``reference``'s: identical weights and spikes for
    the fixed-point engines; weight differences and the strong synapses' agreement for
    golden."""
    if reference not in runs:
        return {}
    ref = runs[reference]
    out = {}
    for e, r in runs.items():
        if e == reference:
            continue
        same_spikes = (np.array_equal(r.spike_pres, ref.spike_pres)
                       and np.array_equal(r.spike_tick, ref.spike_tick)
                       and np.array_equal(r.spike_cn, ref.spike_cn))
        d = np.abs(np.asarray(r.weights) - np.asarray(ref.weights))
        row = {"weights_identical": int(np.count_nonzero(d == 0)), "weights": int(d.size),
               "max_abs_weight_diff": float(d.max()), "mean_abs_weight_diff": float(d.mean()),
               "strong_agree": float(np.mean((np.asarray(r.weights) > fraction * w_max)
                                             == (np.asarray(ref.weights) > fraction * w_max))),
               "spikes_identical": bool(same_spikes), "spikes": int(r.spike_cn.size),
               "spikes_reference": int(ref.spike_cn.size)}
        out[f"{e} vs {reference}"] = row
    return out
