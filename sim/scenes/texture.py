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
from pathlib import Path

import numpy as np

from ...golden.textures import Texture, texture
from .. import progress as prog
from ..decode import TEXTURE_DECODERS, confusions
from ..report import (agreement_html, engine_figures, files_html, fmt, html_table, pyplot, ran_html,
                      save_figure, summary_dict, write_page)
from . import afferent
from .afferent import write_spike_files
from .texture_grid import GridRun, format_grid, grid_summary, run_grid, write_grid
from .texture_trials import DEFAULTS, SEEDS, condition_scene, conditions, core_cost, is_grid
from .texture_trials import pct as _pct
from .texture_trials import protocol, run_single

__all__ = ["fill_defaults", "validate", "estimate", "run", "summary", "write_report",
           "format_run"]


# --------------------------------------------------------------------------- validation
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


def validated_texture(V, i: int, t):
    """The texture named or described by ``stimulus.textures[i]`` (``V.err`` refuses it)."""
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
        names = [validated_texture(V, i, t).name for i, t in enumerate(st["textures"])]
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


# --------------------------------------------------------------------------- estimate, run
def estimate(scene, engines: list[str], n_samples: int | None = None) -> dict:
    """Memory (bytes) and time (s): the afferent machinery's estimate of each condition
    (:func:`cuneate.sim.scenes.afferent.estimate`), the synthesis of every trial, and the VP
    matrices; a grid's conditions share its workers."""
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


def summary(run) -> dict:
    """The run as a JSON-ready dictionary (``run.json``)."""
    if isinstance(run, GridRun):
        return grid_summary(run)
    a = run.afferent
    out = summary_dict(a)
    out.update({"kind": "texture", "channels": run.channels,
                "accuracy": {e: d.accuracy for e, d in run.decoding.items()},
                "accuracy_is": "balanced accuracy of VP + kNN (leave-one-out), mean over the "
                               "channels each decoded alone (chance 1/textures)",
                "texture_decoding": {e: d.to_dict() for e, d in run.decoding.items()},
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
                   + (f", best {b.channel} {_pct(b.accuracy)} %" if b else "")
                   + (f", all channels {_pct(a.accuracy)} %" if a and a.accuracy is not None
                      else "") + f"  (seeds: {SEEDS[dec]})")
    return out


def format_run(run) -> str:
    """The lines ``cuneate run`` prints for a texture scene."""
    if isinstance(run, GridRun):
        return format_grid(run)
    a = run.afferent
    sc = run.scene
    out = [f"{sc.name}: {len(a.classes)} textures x {sc['scene']['trials']} trials, "
           f"{len(a.neurons)} afferents ({len(run.channels)} channel(s) a trial), engines "
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
    if a.ran.get("in_turn"):
        from ..report import in_turn_line
        out.append(in_turn_line(a.ran["in_turn"]))
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
    fig, axes = plt.subplots(1, len(rows), figsize=(5.0 * len(rows), 5.0), squeeze=False,
                             layout="constrained")
    for ax, r in zip(axes[0], rows):
        p = r.protocol
        ConfusionMatrixDisplay(p.confusion, display_labels=p.labels).plot(
            ax=ax, cmap="Blues", colorbar=False, xticks_rotation=60, values_format="d")
        ax.set_title(f"{e}: {r.decoder}, {r.channel}\nbalanced {_pct(p.balanced_accuracy)} % "
                     f"(chance {100 * p.chance_balanced:.0f} %)", fontsize=8)
        ax.tick_params(labelsize=6)
    save_figure(fig, out / f"confusion_{e}.png", bbox_inches="tight")
    names.append((f"confusion_{e}.png", f"Confusion matrices on {e} (leave-one-out kNN): "
                                        f"rate, rate + CV and VP on their best channels, VP "
                                        f"on all channels"))
    return names


def _decoding_html(run) -> str:
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
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if isinstance(run, GridRun):
        return write_grid(run, out)
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


