"""Learning scenes: a cuneate layer that learns the MEMS fingertip's stimuli with AIDP, on
golden, the twin and the layer's RTL (the thesis's protocol, brief section 5b).

A scene with ``sensor.kind = "mems"`` and ``stimulus.kind = "learning"`` slides each stimulus
of ``stimulus.textures`` (textures and shapes, :mod:`cuneate.golden.textures`) once under the
fingertip, encodes the 16 tethers with ``len(learning.afferent_gains)`` SA afferents each (the
stimuli's templates), and presents the templates, jittered, to a learning cuneate layer
(:mod:`cuneate.sim.plasticity.protocol`: the test presentations, ``learning.presentations`` of
each stimulus in one pseudo-random order, the test presentations again). Every engine of
``run.engines`` (the plasticity block's: golden, fixed, amaranth, icarus, verilator,
verilator-fast, board, axi) runs the whole sequence; the report shows the weights before and after, the
learning curves, each CN's selectivity, the stimuli decoded from the CNs before and after
learning (kNN on spike counts and on Victor-Purpura distances) and how the engines agree.
"""

from __future__ import annotations

import html
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["validate", "estimate", "run", "summary", "write_report", "format_run",
           "LearningRun"]

#: the anchor beside which the report puts the 10-texture figure (brief section 5b)
ANCHOR = "a median of 96 % texture decoding across 25 learning CNs on 10 textures"


# --------------------------------------------------------------------------- validation
def validate(V, raw: dict, sections: dict, pops: list, projs: list) -> None:
    """Check and complete a learning scene in place; ``V.err`` raises the scene error."""
    from .texture import validated_texture
    from .texture_trials import protocol
    sen, st, lp, dec = (sections[k] for k in ("sensor", "stimulus", "learning", "decoder"))
    if sen["kind"] != "mems":
        V.err("sensor.kind", "a learning scene presents the MEMS fingertip's stimuli: "
                             "sensor.kind = \"mems\"")
    if st["textures"] is None:
        st["textures"] = ["corduroy", "latex", "paper", "bars", "dots"]
    if not st["textures"] or len(st["textures"]) < 2:
        V.err("stimulus.textures", "a layer learns to tell at least two stimuli apart")
    names = [validated_texture(V, i, t).name for i, t in enumerate(st["textures"])]
    if len(set(names)) != len(names):
        V.err("stimulus.textures", "names a stimulus twice")
    if sections["scene"]["trials"] != 1 and "trials" in raw.get("scene", {}):
        V.err("scene.trials", "a learning scene synthesizes one response of each stimulus "
                              "(its template); the presentations are learning.presentations")
    sections["scene"]["trials"] = 1
    sections["scene"]["duration_ms"] = protocol(sections).duration_ms
    if projs or len(pops) != 1 or pops[0]["model"] != "izhikevich":
        V.err("population", "a learning scene has one population: the SA Izhikevich "
                            "afferents on the tethers")
    p = pops[0]
    if p["encoding"] not in (None, "SA"):
        V.err("population[0].encoding", "the learning scene's afferents are SA")
    p["encoding"] = "SA"
    if p["pairs"] is not None:
        V.err("population[0].pairs", "a learning scene's afferents take tethers (gratings "
                                     "0-15), as the thesis's 16 channels")
    w = lp["window_ms"]
    if len(w) != 2 or not 0 <= w[0] < w[1] <= sections["scene"]["duration_ms"]:
        V.err("learning.window_ms", f"must be [start, end] within the trial (0 .. "
                                    f"{sections['scene']['duration_ms']:g} ms)")
    if not lp["afferent_gains"] or any(g <= 0 for g in lp["afferent_gains"]):
        V.err("learning.afferent_gains", "must list gains > 0")
    g = p["gratings"] if p["gratings"] is not None else list(range(sen["channels"]))
    n_aff = len(g) * len(lp["afferent_gains"])
    if lp["synapses_per_cn"] > n_aff:
        V.err("learning.synapses_per_cn", f"{lp['synapses_per_cn']} synapses but only "
                                          f"{n_aff} afferents")
    if lp["initial_weight_max"] > lp["w_max"]:
        V.err("learning.initial_weight_max", f"above w_max ({lp['w_max']:g} mV/ms)")
    if dec["kind"] not in ("vp", "none"):
        V.err("decoder.kind", "a learning scene decodes with kNN on counts and Victor-Purpura "
                              "(kind = \"vp\") or not at all (\"none\")")
    if dec["neighbours"] >= lp["test_presentations"]:
        V.err("decoder.neighbours", f"{dec['neighbours']} neighbours, but each stimulus has "
                                    f"{lp['test_presentations']} test presentations")
    from ...golden.izhikevich import to_params
    try:
        to_params(lp["cn_preset"])
    except ValueError as exc:
        V.err("learning.cn_preset", str(exc))
    try:
        from ..plasticity.protocol import layer_config
        from .scene import Scene
        layer_config(Scene("<check>", sections, pops, [], None, "learning"), n_aff)
    except ValueError as exc:
        V.err("learning", str(exc))


# --------------------------------------------------------------------------- estimate, run
def _work(scene) -> dict:
    lp = scene["learning"]
    n_cls = len(scene.classes())
    n_pres = n_cls * (lp["presentations"] + 2 * lp["test_presentations"])
    ticks = n_pres * int(round((lp["window_ms"][1] - lp["window_ms"][0] + lp["gap_ms"])
                               * lp["update_hz"] / 1000.0))
    M, K = lp["cns"], lp["synapses_per_cn"]
    from ...hdl.plasticity.config import CYCLES_PER_TARGET_EXTRA, TICK_PROLOGUE
    return {"presentations": n_pres, "ticks": ticks, "synapse_updates": ticks * M * K,
            "cycles": ticks * (TICK_PROLOGUE + M * (K + CYCLES_PER_TARGET_EXTRA) + 8)}


def estimate(scene, engines: list[str]) -> dict:
    """Memory (bytes) and time (s): the afferents' templates, then each engine's run of the
    whole sequence (synapse updates for golden and fixed, cycles for the RTL engines)."""
    from ..engines.registry import ENGINES, estimate_seconds
    w = _work(scene)
    lp = scene["learning"]
    n_cls = len(scene.classes())
    from ..plasticity.protocol import n_afferents
    aff = n_afferents(scene)
    n_s = scene["scene"]["duration_ms"] * scene["hardware"]["update_hz"] / 1000.0
    seconds = 5e-8 * n_cls * aff * n_s
    for e in engines:
        work = w["cycles"] if ENGINES[e].hdl else w["synapse_updates"]
        seconds += estimate_seconds("plasticity", e, work)
    nbytes = 8.0 * n_cls * aff * n_s * 3 + 64.0 * w["presentations"] * aff * 50
    return {"bytes": nbytes, "seconds": seconds,
            "what": f"{w['presentations']} presentations, {w['ticks']} ticks of "
                    f"{lp['cns']} CNs x {lp['synapses_per_cn']} synapses on "
                    f"{', '.join(engines)}"}


@dataclass
class LearningRun:
    """A learning scene's run: the templates, the presentations, the layer's configuration,
    each engine's run and what it learnt."""

    scene: object
    templates: dict
    presentations: object
    phase: np.ndarray
    config: object
    runs: dict
    results: dict
    agreement: dict
    stdp: dict | None = None
    timing: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)
    kind: str = "learning"


def run(scene, engines=None, build_dir=None, progress=False, log=None):
    """Run a learning scene on its engines (see the module docstring)."""
    from .. import progress as prog
    from ..plasticity import protocol as P
    from ..plasticity.engines import run_learning
    engines = list(engines or scene.engines)
    lp = scene["learning"]
    timing = {}
    t0 = time.perf_counter()
    with prog.step("synthesizing each stimulus's afferent responses"):
        tpl = P.templates(scene)
    timing["templates_s"] = time.perf_counter() - t0
    pres, learn, phase = P.protocol_presentations(scene, tpl)
    cfg = P.layer_config(scene, len(tpl["afferents"]))
    runs, timing["engines_s"] = {}, {}
    for e in engines:
        t1 = time.perf_counter()
        with prog.step(f"{e}: {pres.n} presentations, {pres.n * pres.n_ticks} ticks of "
                       f"{cfg.n_targets} CNs x {cfg.n_synapses} synapses"):
            runs[e] = run_learning(e, cfg, pres, learn, lp["snapshot_every"],
                                   None if build_dir is None else Path(build_dir) / e)
        timing["engines_s"][e] = time.perf_counter() - t1
    t1 = time.perf_counter()
    with prog.step("what the layer learnt: weights, selectivity, decoding"):
        results = P.analyse(scene, tpl, pres, phase, cfg, runs)
        agree = P.agreement(runs, "fixed", cfg.rule.w_max, lp["strong_fraction"])
    timing["analysis_s"] = time.perf_counter() - t1
    stdp = None
    if lp["compare_stdp"]:
        stdp = _stdp(scene, tpl, pres, learn, phase, cfg)
    return LearningRun(scene, tpl, pres, phase, cfg, runs, results, agree, stdp, timing)


def _stdp(scene, tpl, pres, learn, phase, cfg) -> dict:
    """Golden's pair-based STDP on the same sequence (its weights and decoding)."""
    from ...golden.cuneate_layer import simulate_layer
    from ...golden.stdp import StdpParams
    from ..plasticity.engines import LearningRun as ERun
    from ..plasticity.engines import golden_layer
    from ..plasticity.protocol import analyse
    p = StdpParams(w_max=cfg.rule.w_max)
    r = simulate_layer(pres, cfg.weights_real, golden_layer(cfg), "stdp", p, learn,
                       scene["learning"]["snapshot_every"])
    er = ERun("golden STDP", r.spike_pres, r.spike_tick, r.spike_cn, r.counts, r.weights,
              None, r.snapshots, seconds=r.seconds)
    return {"params": p.to_dict(),
            **analyse(scene, tpl, pres, phase, cfg, {"golden STDP": er})["golden STDP"]}


# --------------------------------------------------------------------------- results
def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.1f}"


def _row(d, decoder: str, channel: str = "all channels"):
    r = d.row(decoder, channel) if not d.reason else None
    return None if r is None else r.accuracy


def _per_cn(d) -> dict:
    """Each CN alone, VP kNN: the median and range over the CNs that spiked."""
    if d.reason:
        return {"median": None, "min": None, "max": None, "n": 0}
    acc = [r.accuracy for r in d.rows if r.decoder == "VP" and r.channel != "all channels"
           and r.accuracy is not None]
    if not acc:
        return {"median": None, "min": None, "max": None, "n": 0}
    return {"median": float(np.median(acc)), "min": float(min(acc)), "max": float(max(acc)),
            "n": len(acc)}


def _decoding_summary(res) -> dict:
    out = {}
    for ph in ("before", "after"):
        d = res[f"decoding_{ph}"]
        out[ph] = {"counts": _row(d, "rate"), "vp": _row(d, "VP"),
                   "vp_each_cn": _per_cn(d), "reason": d.reason or None}
    return out


def _engine_summary(res, cfg, frac) -> dict:
    wmax = cfg.rule.w_max
    wa = np.asarray(res["weights_after"])
    return {"decoding": _decoding_summary(res),
            "strong_per_cn_before": res["strong_before"].tolist(),
            "strong_per_cn_after": res["strong_after"].tolist(),
            "strong_fraction_after": float(np.mean(wa > frac * wmax)),
            "weight_mean_after": float(wa.mean()), "weight_median_after": float(np.median(wa)),
            "weak_fraction_after": float(np.mean(wa < 0.1 * wmax)),
            "selectivity_after": res["selectivity_after"]["index"].tolist(),
            "selectivity_before": res["selectivity_before"]["index"].tolist(),
            "preferred_after": res["selectivity_after"]["preferred"].tolist(),
            "clamp_counts": res["clamp_counts"], "seconds": res["seconds"],
            "curve": res["curve"]}


def summary(run: LearningRun) -> dict:
    """The run as a JSON-ready dictionary (``run.json``)."""
    from ..provenance import cuneate_version, provenance
    sc, cfg, lp = run.scene, run.config, run.scene["learning"]
    frac = lp["strong_fraction"]
    pres = run.presentations
    return {
        "kind": "learning", "scene": sc.name, "source": sc.source, "version": cuneate_version(),
        "stimuli": run.templates["trial_class"], "afferents": len(run.templates["afferents"]),
        "cns": cfg.n_targets, "synapses_per_cn": cfg.n_synapses,
        "presentations": {ph: int(np.count_nonzero(run.phase == ph)) for ph in
                          ("before", "training", "after")},
        "ticks_per_presentation": pres.n_ticks, "window_ticks": pres.window_ticks,
        "dt_ms": pres.dt_ms, "jitter_merged_spikes": int(pres.merged),
        "engines": {e: _engine_summary(res, cfg, frac) for e, res in run.results.items()},
        "agreement": run.agreement,
        "stdp": None if run.stdp is None else _engine_summary(run.stdp, cfg, frac),
        "layer": cfg.to_dict(), "timing": run.timing, "anchor": ANCHOR,
        "resolved_scene": sc.to_dict(),
        "provenance": provenance(seeds={"scene.seed": sc["scene"]["seed"],
                                        "learning.order_seed": lp["order_seed"],
                                        "learning.anatomy_seed": lp["anatomy_seed"],
                                        "stimulus.texture_seed":
                                            sc["stimulus"]["texture_seed"]}),
    }


def format_run(run: LearningRun) -> str:
    """The lines ``cuneate run`` prints for a learning scene."""
    sc, cfg, lp = run.scene, run.config, run.scene["learning"]
    frac = lp["strong_fraction"]
    n_tr = int(np.count_nonzero(run.phase == "training"))
    out = [f"{sc.name}: {len(run.templates['trial_class'])} stimuli, "
           f"{len(run.templates['afferents'])} afferents, {cfg.n_targets} CNs x "
           f"{cfg.n_synapses} synapses; {n_tr} training presentations (jitter "
           f"{lp['jitter_ms']:g} ms), {lp['test_presentations']} test presentations of each "
           f"stimulus before and after; engines {', '.join(run.runs)}"]
    rows = list(run.results.items()) + ([("golden STDP", run.stdp)] if run.stdp else [])
    for e, res in rows:
        s = _engine_summary(res, cfg, frac)
        d = s["decoding"]
        out.append(f"  {e:14s} decoding before -> after: counts {_pct(d['before']['counts'])}"
                   f" -> {_pct(d['after']['counts'])} %, VP {_pct(d['before']['vp'])} -> "
                   f"{_pct(d['after']['vp'])} %, each CN alone (VP, median) "
                   f"{_pct(d['before']['vp_each_cn']['median'])} -> "
                   f"{_pct(d['after']['vp_each_cn']['median'])} %")
        sa = np.asarray(s["strong_per_cn_after"])
        out.append(f"  {'':14s} strong synapses (> {frac:g} w_max) per CN after: "
                   f"{sa.min()}-{sa.max()} (median {np.median(sa):g}) of {cfg.n_synapses}; "
                   f"before {np.median(s['strong_per_cn_before']):g}; {res['seconds']:.1f} s")
    for k, a in run.agreement.items():
        out.append(f"  {k}: {a['weights_identical']}/{a['weights']} weights identical (max "
                   f"|diff| {a['max_abs_weight_diff']:.4g} mV/ms, strong/weak agree on "
                   f"{100 * a['strong_agree']:.1f} %), spikes "
                   f"{'identical' if a['spikes_identical'] else 'differ'} "
                   f"({a['spikes']} vs {a['spikes_reference']})")
    fx = run.runs.get("fixed")
    if fx is not None:
        c = {k: v for k, v in fx.clamp_counts.items() if v}
        out.append("  fixed clamps: " + (", ".join(f"{k} {v}" for k, v in c.items()) or
                                        "none"))
    return "\n".join(out)


# --------------------------------------------------------------------------- the report
def _figures(run: LearningRun, out: Path) -> list:
    from ..report import pyplot, save_figure
    plt = pyplot()
    cfg, lp = run.config, run.scene["learning"]
    wmax, frac = cfg.rule.w_max, lp["strong_fraction"]
    names = []
    tpl = run.templates
    # afferent templates
    fig, axes = plt.subplots(1, len(tpl["trains"]), figsize=(3.0 * len(tpl["trains"]), 3.2),
                             sharey=True, squeeze=False)
    w0, w1 = lp["window_ms"]
    for ax, name, tr in zip(axes[0], tpl["trial_class"], tpl["trains"]):
        for i, s in enumerate(tr):
            s = s[(s >= w0) & (s < w1)]
            ax.plot(s, np.full(s.size, i), "|", ms=2, color="k")
        ax.set_title(name, fontsize=8)
        ax.set_xlabel("ms")
    axes[0][0].set_ylabel("afferent (tether x gain)")
    fig.tight_layout()
    save_figure(fig, out / "templates.png")
    names.append(("templates.png", "Each stimulus's afferent responses within the window "
                                   "(the templates the presentations jitter)"))
    engines = list(run.results)
    # weights before / after
    fig, axes = plt.subplots(2, len(engines), figsize=(4.2 * len(engines), 6.0),
                             squeeze=False)
    for k, e in enumerate(engines):
        res = run.results[e]
        bins = np.linspace(0, wmax, 31)
        ax = axes[0][k]
        ax.hist(np.ravel(res["weights_before"]), bins, alpha=0.6, label="before")
        ax.hist(np.ravel(res["weights_after"]), bins, alpha=0.6, label="after")
        ax.axvline(frac * wmax, color="k", lw=0.6, ls="--")
        ax.set(title=f"{e}: weights", xlabel="w (mV/ms)", ylabel="synapses")
        ax.legend(fontsize=7)
        ax = axes[1][k]
        x = np.arange(cfg.n_targets)
        ax.bar(x - 0.2, res["strong_before"], 0.4, label="before")
        ax.bar(x + 0.2, res["strong_after"], 0.4, label="after")
        ax.set(title=f"{e}: strong synapses per CN (> {frac:g} w_max)", xlabel="CN",
               ylabel=f"of {cfg.n_synapses}")
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, out / "weights.png")
    names.append(("weights.png", "Weight distributions before and after learning, and the "
                                 "strong synapses of each CN (dashed: the strong threshold)"))
    # weight matrices
    fig, axes = plt.subplots(len(engines), 2, figsize=(10, 2.0 + 1.6 * len(engines)),
                             squeeze=False)
    for k, e in enumerate(engines):
        res = run.results[e]
        for c, (what, w) in enumerate((("before", res["weights_before"]),
                                       ("after", res["weights_after"]))):
            full = np.full((cfg.n_targets, cfg.n_sources), np.nan)
            for j in range(cfg.n_targets):
                full[j, cfg.src[j]] = np.asarray(w)[j]
            im = axes[k][c].imshow(full, aspect="auto", vmin=0, vmax=wmax, cmap="viridis",
                                   interpolation="nearest")
            axes[k][c].set(title=f"{e}, {what}", xlabel="afferent (tether x gain)",
                           ylabel="CN")
        fig.colorbar(im, ax=axes[k].tolist(), label="w (mV/ms)")
    save_figure(fig, out / "weight_matrix.png", bbox_inches="tight")
    names.append(("weight_matrix.png", "Each CN's synapses by afferent (blank: no synapse), "
                                       "before and after learning"))
    # learning curves
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.6))
    for e in engines:
        res = run.results[e]
        if len(res["curve"]) > 1:
            c = np.array(res["curve"])
            axes[0].plot(c[:, 0], 100 * c[:, 1], marker=".", label=e)
        if res["step"] is not None:
            st = np.asarray(res["step"])[run.phase == "training"]
            axes[1].plot(_smooth(st), label=e)
        axes[2].plot(_smooth(res["training_counts"]), label=e)
    axes[0].set(title="strong synapses during training", xlabel="presentations",
                ylabel="% of synapses")
    axes[1].set(title="mean |weight step| per presentation (smoothed)",
                xlabel="presentations", ylabel="mV/ms", yscale="log")
    axes[2].set(title="CN spikes per presentation (mean over CNs, smoothed)",
                xlabel="presentations", ylabel="spikes in the window")
    for ax in axes:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, out / "curves.png")
    names.append(("curves.png", "Learning curves: strong synapses, the weight steps and the "
                                "CNs' activity over the training presentations"))
    # selectivity
    e = "fixed" if "fixed" in run.results else engines[0]
    res = run.results[e]
    fig, axes = plt.subplots(1, 2, figsize=(11, 0.6 + 0.28 * cfg.n_targets + 1.5))
    for ax, ph in zip(axes, ("before", "after")):
        s = res[f"selectivity_{ph}"]
        im = ax.imshow(s["mean_counts"], aspect="auto", cmap="magma")
        ax.set_xticks(range(len(tpl["trial_class"])), tpl["trial_class"], rotation=30,
                      fontsize=7)
        ax.set(title=f"{e}: mean spikes per presentation, {ph} learning", ylabel="CN")
        fig.colorbar(im, ax=ax)
    fig.tight_layout()
    save_figure(fig, out / "selectivity.png")
    names.append(("selectivity.png", "Each CN's mean spike count per stimulus before and after "
                                     "learning (its selectivity)"))
    return names


def _smooth(x, n: int = 25):
    x = np.asarray(x, dtype=np.float64)
    if x.size < n:
        return x
    return np.convolve(x, np.ones(n) / n, mode="valid")


def _tables(run: LearningRun) -> str:
    from ..report import html_table
    cfg, lp = run.config, run.scene["learning"]
    frac = lp["strong_fraction"]
    rows, srows, crows = [], [], []
    items = list(run.results.items()) + ([("golden STDP", run.stdp)] if run.stdp else [])
    for e, res in items:
        s = _engine_summary(res, cfg, frac)
        d = s["decoding"]
        for ph in ("before", "after"):
            x = d[ph]
            rows.append([e, ph, _pct(x["counts"]), _pct(x["vp"]),
                         f"{_pct(x['vp_each_cn']['median'])} ({_pct(x['vp_each_cn']['min'])}-"
                         f"{_pct(x['vp_each_cn']['max'])}, {x['vp_each_cn']['n']} CNs)",
                         x["reason"] or ""])
        sa, sb = np.asarray(s["strong_per_cn_after"]), np.asarray(s["strong_per_cn_before"])
        srows.append([e, f"{np.median(sb):g} ({sb.min()}-{sb.max()})",
                      f"{np.median(sa):g} ({sa.min()}-{sa.max()})",
                      f"{100 * s['strong_fraction_after']:.1f}",
                      f"{100 * s['weak_fraction_after']:.1f}",
                      f"{np.median(s['selectivity_before']):.2f}",
                      f"{np.median(s['selectivity_after']):.2f}"])
        if res.get("clamp_counts"):
            crows.append([e] + [str(v) for v in res["clamp_counts"].values()])
    arows = [[k, f"{a['weights_identical']}/{a['weights']}", f"{a['max_abs_weight_diff']:.4g}",
              f"{100 * a['strong_agree']:.1f}",
              "identical" if a["spikes_identical"] else "differ",
              f"{a['spikes']} / {a['spikes_reference']}"] for k, a in run.agreement.items()]
    from ...hdl.plasticity import CLAMP_KINDS
    n = len(run.templates["trial_class"])
    return f"""<h2>Decoding the stimuli from the CNs</h2>
<p>The test presentations ({lp['test_presentations']} of each stimulus, the same jittered spikes
before and after learning), each decided by its k = {run.scene['decoder']['neighbours']}
nearest neighbours among the others (leave-one-out, balanced accuracy, chance
{100 / n:.0f} %): on the CNs' spike counts in the window (one vector), on Victor-Purpura
distances (q = {run.scene['decoder']['q_per_s']:g}/s) summed over the CNs, and on each CN alone
(VP; median and range over the CNs that spiked). The anchor: {ANCHOR}.</p>
{html_table(rows, ["engine", "learning", "counts kNN %", "VP kNN %", "each CN alone, VP %",
                   "not decoded"])}
<h2>Weights and selectivity</h2>
<p>Strong: w &gt; {frac:g} w_max ({frac * cfg.rule.w_max:g} mV/ms); weak: w &lt; 0.1 w_max.
Selectivity index of a CN: (r_pref - mean r_others) / (r_pref + mean r_others), its mean spike
counts over the test presentations.</p>
{html_table(srows, ["engine", "strong per CN before: median (range)", "after",
                    "strong % after", "weak % after", "selectivity before (median)",
                    "after (median)"])}
<h2>Engines</h2>
{html_table(arows, ["engines", "identical weights", "max |diff| mV/ms", "strong/weak agree %",
                    "spikes", "spikes (engine / reference)"])}
<h3>Clamps (flagged and counted)</h3>
{html_table(crows, ["engine", *CLAMP_KINDS])}"""


def write_report(run: LearningRun, out: Path) -> Path:
    """Write the figures, the weights (``weights_<engine>.npz``, and as NIR graphs
    ``learned_<engine>.nir``), ``run.json`` and ``index.html`` into ``out``; returns the HTML
    path."""
    from .. import progress as prog
    from ..report import html_table, write_page
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with prog.step("writing the learning report"):
        figs = _figures(run, out)
        import nir
        from ..nir.export import learning_graph
        for e, res in run.results.items():
            np.savez(out / f"weights_{e}.npz", before=res["weights_before"],
                     after=res["weights_after"], sources=run.config.src)
            nir.write(out / f"learned_{e}.nir", learning_graph(run.config,
                                                               res["weights_after"]))
            run.files.setdefault("weights", {})[e] = f"weights_{e}.npz"
            run.files.setdefault("nir", {})[e] = f"learned_{e}.nir"
        summ = summary(run)
        (out / "run.json").write_text(json.dumps(summ, indent=2, default=_json))
    cfg, lp, t = run.config, run.scene["learning"], run.timing
    stages = [["templates", f"{t['templates_s']:.2f}"]] + \
        [[f"engine {e}", f"{s:.2f}"] for e, s in t["engines_s"].items()] + \
        [["analysis", f"{t['analysis_s']:.2f}"]]
    body = f"""<p>Scene: {html.escape(run.scene.source)}. Stimuli:
{html.escape(', '.join(run.templates['trial_class']))}; {len(run.templates['afferents'])}
afferents (16 tethers x {len(lp['afferent_gains'])} gains); {cfg.n_targets} CNs of
{cfg.n_synapses} synapses (afferents drawn at random), a lumped inhibitory interneuron, AIDP
(eta = {cfg.rule.eta:g}, w_max = {cfg.rule.w_max:g} mV/ms); presentations of
{lp['window_ms'][1] - lp['window_ms'][0]:g} ms + {lp['gap_ms']:g} ms, jitter
{lp['jitter_ms']:g} ms, dt = {1000 / lp['update_hz']:g} ms.</p>
{_tables(run)}
<h2>Time</h2>
{html_table(stages, ["stage", "wall s"])}
<p>Files: run.json, {html.escape(', '.join(run.files.get('weights', {}).values()))}; the
learned layers as NIR graphs (the Izhikevich CNs and the rule in the Output node's metadata):
{html.escape(', '.join(run.files.get('nir', {}).values()))}.</p>"""
    return write_page(out, run.scene.name, body, figs)


def _json(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    return str(x)
