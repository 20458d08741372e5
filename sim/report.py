"""The run report: a self-contained HTML page, PNG figures beside it, and ``run.json``.

Figures (all written by :func:`write_report` into the output directory, linked relatively):
``traces.png`` (d_lambda of the first trial of each class), ``currents.png`` (the front end's
currents for the same trials), ``raster_<engine>.png`` per engine, ``isi_<engine>.png`` (ISI
distributions per class), ``confusion_<engine>.png`` per decoded engine. Tables: accuracy per
engine, engine agreement, current range and saturations per class, what ran (effects, blocks,
engines) and wall time per stage.
"""

from __future__ import annotations

import html
import math
import json
import re
from pathlib import Path

import numpy as np

from . import progress as prog
from .provenance import cuneate_version, provenance

__all__ = ["write_report", "summary_dict", "figure_names", "page_head", "figures_html",
           "pyplot", "html_table", "fmt", "write_page", "DPI", "save_figure",
           "decoding_rows", "DECODING_HEAD", "printable", "format_run", "engine_figures",
           "agreement_html", "ran_html", "files_html", "board_link_html", "block_line",
           "in_turn_line", "fmt_distinct"]

#: Resolution of every report figure (dots per inch); figures are drawn at their display size.
DPI = 150


def pyplot():
    """matplotlib's pyplot on the non-interactive Agg backend."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig, path: Path, **kw) -> None:
    """Save ``fig`` at :data:`DPI` and close it."""
    fig.savefig(path, dpi=DPI, **kw)
    import matplotlib.pyplot as plt
    plt.close(fig)


def _first_trials(run) -> list[int]:
    seen, out = set(), []
    for t, c in enumerate(run.trial_class):
        if c not in seen:
            seen.add(c)
            out.append(t)
    return out


def figure_names(run) -> list[tuple[str, str]]:
    """``(file, caption)`` of every figure of an afferent run's report."""
    names = [("traces.png", "Bragg wavelength shift of the first trial of each class, per "
                            "grating"),
             ("currents.png", "Front-end currents of the same trials (filtered, scaled; what "
                              "the core's neurons receive)")]
    for e in run.spikes:
        names += [(f"raster_{e}.png", f"Spikes on {e}, one row per neuron, grouped by class"),
                  (f"isi_{e}.png", f"Inter-spike intervals on {e} per class (the decoder's "
                                   f"samples)")]
        if e in run.decoded and run.decoded[e].accuracy is not None:
            noun = run.scene.trial_noun
            names.append((f"confusion_{e}.png",
                          f"Confusion matrices on {e}: per {noun} with {noun}-grouped "
                          f"cross-validation (the headline)"
                          + (", and the published per-ISI protocol"
                             if run.decoded[e].row("published") else "")))
    return names


#: curves a trace or current panel draws at most
MAX_LINES = 12


def _fig_traces(run, out: Path, plt):
    firsts = _first_trials(run)[:MAX_LINES]
    fs = run.scene["sensor"]["sample_rate_hz"]
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.6))
    # at most MAX_LINES curves a panel (a hand of gratings would bury the legend): the first
    # gratings and afferents spread over the populations of each class's first trial, the
    # title says how many
    per = max(1, MAX_LINES // max(len(firsts), 1))
    n_g = run.traces[firsts[0]].shape[1] if firsts else 0
    for t in firsts:
        x = run.traces[t]
        tm = np.arange(x.shape[0]) * 1000.0 / fs
        for g in range(min(per, x.shape[1])):
            ax[0].plot(tm, x[:, g] * 1e3, lw=1, label=f"{run.trial_class[t]} g{g}")
    shown = "" if n_g <= per else f" ({per} of {n_g} gratings)"
    ax[0].set(xlabel="time (ms)", ylabel="Δλ (pm)",
              title=f"Bragg shift, first trial per class{shown}")
    ax[0].legend(fontsize=7)
    cols = {t: [i for i, u in enumerate(run.neurons.trial) if u == t] for t in firsts}
    n_a = len(cols[firsts[0]]) if firsts else 0
    tm = np.arange(run.currents.shape[0]) * 1000.0 / fs
    for t in firsts:
        picks = np.unique(np.linspace(0, len(cols[t]) - 1, min(per, len(cols[t]))).astype(int))
        for i in (cols[t][k] for k in picks):
            ax[1].plot(tm, run.currents[:, i], lw=1,
                       label=f"{run.trial_class[t]} {run.neurons.population[i]} "
                             f"g{run.neurons.grating[i]}")
    shown = "" if n_a <= per else f" ({per} of {n_a} afferents)"
    ax[1].set(xlabel="time (ms)", ylabel="current (mV/ms)", title=f"front-end currents{shown}")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    # two files so that each figure can be linked on its own
    ext = ax[1].get_tightbbox(fig.canvas.get_renderer()).transformed(
        fig.dpi_scale_trans.inverted())
    fig.savefig(out / "currents.png", dpi=DPI, bbox_inches=ext.expanded(1.02, 1.04))
    ext = ax[0].get_tightbbox(fig.canvas.get_renderer()).transformed(
        fig.dpi_scale_trans.inverted())
    save_figure(fig, out / "traces.png", bbox_inches=ext.expanded(1.02, 1.04))


def _fig_confusion(d, e: str, path: Path, plt):
    from sklearn.metrics import ConfusionMatrixDisplay
    rows = [d.headline] + [r for r in d.rows if r.name.startswith("published")]
    fig, axes = plt.subplots(1, len(rows), figsize=(5.4 * len(rows), 4.6), squeeze=False)
    for ax, r in zip(axes[0], rows):
        disp = ConfusionMatrixDisplay(r.confusion, display_labels=r.labels)
        disp.plot(ax=ax, cmap="Blues", colorbar=True, xticks_rotation=35, values_format="d")
        ax.set_title(f"{e}: {r.name}\nbalanced {100 * r.balanced_accuracy:.1f} % "
                     f"(chance {100 * r.chance_balanced:.0f} %), {r.n_samples} {r.unit}s",
                     fontsize=9)
        ax.set(xlabel=f"predicted ({r.unit})", ylabel="true")
    fig.tight_layout()
    save_figure(fig, path)


def engine_figures(run, e, out: Path, plt):
    """``raster_<e>.png``, ``isi_<e>.png`` (and ``confusion_<e>.png`` when the afferent
    decoder ran) of engine ``e``."""
    sp = run.spikes[e]
    order = sorted(range(len(sp)), key=lambda i: (run.classes.index(
        run.trial_class[run.neurons.trial[i]]), i))
    colors = {c: f"C{k}" for k, c in enumerate(run.classes)}
    fig, ax = plt.subplots(figsize=(8, 4))
    for row, i in enumerate(order):
        c = run.trial_class[run.neurons.trial[i]]
        ax.plot(sp[i], np.full(len(sp[i]), row), "|", ms=3, color=colors[c])
    for c in run.classes:
        ax.plot([], [], "|", color=colors[c], label=c)
    ax.set(xlabel="time (ms)", ylabel="neuron (grouped by class)", title=f"spikes: {e}")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    save_figure(fig, out / f"raster_{e}.png")
    fig, ax = plt.subplots(figsize=(6, 3.6))
    bins = np.logspace(-1, 3, 50)
    for c in run.classes:
        isi = np.concatenate([np.diff(sp[i]) for i in range(len(sp))
                              if run.trial_class[run.neurons.trial[i]] == c] or [np.zeros(0)])
        if isi.size:
            ax.hist(isi, bins=bins, histtype="step", label=f"{c} ({isi.size})", color=colors[c])
    ax.set(xscale="log", xlabel="ISI (ms)", ylabel="count", title=f"ISI per class: {e}")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "no ISIs (fewer than two spikes per afferent)",
                transform=ax.transAxes, ha="center")
    fig.tight_layout()
    save_figure(fig, out / f"isi_{e}.png")
    d = run.decoded.get(e)
    if d is not None and d.accuracy is not None:
        _fig_confusion(d, e, out / f"confusion_{e}.png", plt)


def class_currents(run) -> list[dict]:
    rows = []
    for c in run.classes:
        cols = [i for i, t in enumerate(run.neurons.trial) if run.trial_class[t] == c]
        peaks = run.currents[:, cols].max(axis=0)
        rows.append({"class": c, "peak_min": float(peaks.min()), "peak_max": float(peaks.max()),
                     "min": float(run.currents[:, cols].min())})
    return rows


def summary_dict(run) -> dict:
    """``run.json`` of an afferent run: what ran, the decoding per engine (headline: the
    balanced accuracy of the per-grasp decision), agreement, saturation, timing, the spike and
    waveform files, and the provenance (version, commit, tools, resolved scene, seeds)."""
    files = getattr(run, "files", {})
    return {
        "scene": run.scene.name, "source": run.scene.source, "classes": run.classes,
        "version": cuneate_version(),
        "trials": len(run.trial_class), "neurons": len(run.neurons), "ticks": run.n_ticks,
        "dt_ms": run.dt_ms,
        "accuracy": {e: d.accuracy for e, d in run.decoded.items()},
        "accuracy_is": f"balanced accuracy of the per-{run.scene.trial_noun} decision, "
                       f"{run.scene.trial_noun}-grouped cross-validation (chance 1/classes)",
        "decoded": {e: d.to_dict() for e, d in run.decoded.items()},
        "agreement": run.agreement, "decode_agreement": run.decode_agreement,
        "saturations": run.saturations,
        "current_per_class": class_currents(run), "ran": run.ran, "timing": run.timing,
        "counters": run.counters,
        "spike_counts": {e: int(sum(len(s) for s in sp)) for e, sp in run.spikes.items()},
        "spike_files": files.get("spikes", {}), "waves": files.get("waves"),
        "decoded_population": run.scene["decoder"]["population"] or "every afferent",
        "layer": _layer_summary(getattr(run, "layer", {})),
        "resolved_scene": run.scene.to_dict(),
        "provenance": provenance(seeds={"scene.seed": run.scene["scene"]["seed"],
                                        "decoder cross-validation": run.scene["scene"]["seed"]}),
    }


def _layer_summary(layer: dict) -> dict | None:
    """The cuneate layer of a run for ``run.json``: its neurons and spikes by engine (the
    trains are in the spike files)."""
    if not layer:
        return None
    return {"population": layer["population"], "neurons": len(layer["trial"]),
            "spike_counts": {e: int(sum(len(s) for s in sp))
                             for e, sp in layer["spikes"].items()},
            "counters": layer["counters"]}


#: Control characters no HTML page may hold (all but tab, line feed and carriage return).
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def printable(page: str) -> str:
    """``page`` with every control character (a NUL from a scene's name, say) shown as U+FFFD."""
    return _CONTROL.sub("\ufffd", page)


def html_table(rows, head) -> str:
    """An HTML table of ``rows`` under the header ``head`` (cells escaped)."""
    h = "".join(f"<th>{html.escape(str(x))}</th>" for x in head)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(x))}</td>" for x in r) + "</tr>"
                   for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


def page_head(name: str) -> str:
    """The start of a report page (doctype, title, style) up to and including its ``<h1>``."""
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>cuneate run: {html.escape(name)}</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:1em auto;}}
table{{border-collapse:collapse;margin:.5em 0;}}td,th{{border:1px solid #bbb;padding:2px 8px;}}
figure{{display:inline-block;margin:6px;vertical-align:top;max-width:100%;}}
img{{max-width:100%;}}figcaption{{font-size:90%;color:#333;max-width:700px;}}
pre{{background:#f6f6f6;padding:4px;}}</style></head><body>
<h1>{html.escape(name)}</h1>"""


def write_page(out: Path, head: str, body: str, figures) -> Path:
    """``out/index.html``: the page head (:func:`page_head` of ``head``), ``body`` and the
    figures section; returns its path."""
    path = Path(out) / "index.html"
    path.write_text(printable(f"{page_head(head)}\n{body}\n<h2>Figures</h2>\n"
                              f"{figures_html(figures)}\n</body></html>\n"))
    return path


def figures_html(names) -> str:
    """Linked figures, each ``file`` or ``(file, caption)``; one that fails to load says so on
    the browser console."""
    out = []
    for n in names:
        f, cap = (n, n) if isinstance(n, str) else n
        out.append(f'<figure><img src="{f}" alt="{html.escape(cap)}" onerror="console.error('
                   f'\'missing figure: \' + this.getAttribute(\'src\'))"><figcaption>'
                   f'{html.escape(cap)} <small>({f})</small></figcaption></figure>')
    return "".join(out)


def fmt(x, nd=3):
    """A number for a table: ``-`` for None, ``nd`` decimals for floats."""
    return "-" if x is None else (f"{x:.{nd}f}" if isinstance(x, float) else str(x))


def fmt_distinct(x, nd=3):
    """A figure in [0, 1] or >= 0 (a fraction, a distance) to the decimals that tell it from 0
    and 1: exactly 0 and 1 print as ``0`` and ``1``, anything else never rounds to them
    (0.99975 of spikes within a tick is ``0.99975``, not ``1.000``)."""
    if x is None:
        return "-"
    x = float(x)
    if x in (0.0, 1.0):
        return f"{x:g}"
    gaps = [g for g in (abs(x), abs(1.0 - x)) if g > 0]
    need = max(nd, 1 - math.floor(math.log10(min(gaps))))
    return f"{x:.{need}f}"


def _pct(x, nd=1):
    return "-" if x is None else f"{100 * x:.{nd}f}"


#: The header of the decoding table (:func:`decoding_rows`).
DECODING_HEAD = ["engine", "protocol", "cross-validation", "decisions", "balanced accuracy %",
                 "chance %", "accuracy %", "largest class %", "recall per class %"]


def decoding_rows(decoded: dict) -> list[list]:
    """The decoding table: per engine its protocols (headline first), or why it has none."""
    rows = []
    for e, d in decoded.items():
        if not d.rows:
            rows.append([e, d.reason, "", d.n_samples, "-", "-", "-", "-", "-"])
            continue
        for r in d.rows:
            rec = ", ".join(f"{c} {_pct(v, 0)}" for c, v in r.recall.items())
            chance = _pct(r.chance_balanced, 0)
            if r.null:
                chance += (f" (permutations: mean {_pct(r.null['mean'])}, 95th pct "
                           f"{_pct(r.null['p95'])}, p = {r.null['p_value']:.3f})")
            rows.append([e, r.name, r.cv, f"{r.n_samples} {r.unit}s",
                         _pct(r.balanced_accuracy), chance, _pct(r.accuracy),
                         _pct(r.chance), rec])
    return rows


def files_html(files: dict) -> str:
    """The report's list of spike and waveform files."""
    items = [f'<li>spikes of {html.escape(e)}: <a href="{html.escape(f)}">{html.escape(f)}</a>'
             f'</li>' for e, f in files.get("spikes", {}).items()]
    w = files.get("waves")
    if w:
        for e, x in w["files"].items():
            items.append(f'<li>waveform of {html.escape(e)}: <a href="{html.escape(x["dump"])}">'
                         f'{html.escape(x["dump"])}</a> (GTKWave: <a href="'
                         f'{html.escape(x["gtkw"])}">{html.escape(x["gtkw"])}</a>; '
                         f'{html.escape(x.get("time_axis", ""))})</li>')
        items.append(f"<li>waveform window: ticks {w['start_tick']} to "
                     f"{w['start_tick'] + w['ticks'] - 1}{html.escape(w.get('note', ''))}</li>")
    if not items:
        return ""
    return ("<h2>Files</h2><ul>" + "".join(items) + "</ul><p>Spike files: NPZ "
            "(<code>cuneate.sim.spikes.load_spikes</code>; format in docs/scenes.md).</p>")


def write_report(run, out: Path) -> Path:
    """Write figures, ``run.json`` and ``index.html`` into ``out``; returns the HTML path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with prog.step(f"writing figures ({len(figure_names(run))}) and the report"):
        plt = pyplot()
        _fig_traces(run, out, plt)
        for e in run.spikes:
            engine_figures(run, e, out, plt)
        summ = summary_dict(run)
        (out / "run.json").write_text(json.dumps(summ, indent=2, default=float))
    cur_rows = [[r["class"], fmt(r["peak_min"], 1), fmt(r["peak_max"], 1), fmt(r["min"], 1)]
                for r in summ["current_per_class"]]
    s = run.saturations
    n_sat = s.get("format_low", 0) + s.get("format_high", 0)
    n_range = s.get("range_low", 0) + s.get("range_high", 0)
    dec = run.scene["decoder"]
    noun = run.scene.trial_noun
    published = any(d.row("published") for d in run.decoded.values())
    reports = "".join(
        f"<details><summary>{html.escape(e)}: scikit-learn classification report "
        f"(per {noun})</summary><pre>{html.escape(d.headline.report_text)}</pre></details>"
        for e, d in run.decoded.items() if d.rows)
    prov = summ["provenance"]
    body = f"""<p>Scene: {html.escape(run.scene.source)}. {len(run.trial_class)} trials of
{len(run.classes)} classes, {len(run.neurons)} neurons, {run.n_ticks} ticks of
{run.dt_ms:g} ms.</p>
<h2>Decoding: what the system decides per {noun}</h2>
<p>Headline (first row per engine): every {noun} decided by pooling its samples
({html.escape(dec['decision'])} vote) under <b>{noun}-grouped</b> cross-validation (no {noun} in
its own training set); <b>balanced accuracy</b> = mean per-class recall, chance = 1/classes.
{_published_note(noun) if published else ""}Decoder: {html.escape(dec['kind'])} on {html.escape(dec['features'])}
features of {html.escape(summ['decoded_population'])}.</p>
{html_table(decoding_rows(run.decoded), DECODING_HEAD)}
<p>{html.escape("; ".join(
    f"{k}: headline differs by {100 * v['difference']:.1f} points, tolerance "
    f"{100 * v['tolerance']:.1f}: {'within' if v['within'] else 'OUTSIDE'}"
    for k, v in run.decode_agreement.items()))}</p>
{reports}
{agreement_html(run)}
<h2>Currents per class (mV/ms) and saturation</h2>
{html_table(cur_rows, ["class", "lowest peak", "highest peak", "minimum"])}
<p>Format {html.escape(str(s.get('format')))}: {n_sat} of {s.get('values')} values saturated by
the driver; {n_range} outside the accepted range; {s.get('gaps_held', 0)} missing samples held;
{s.get('samples_past_end', 0)} of {s.get('samples', '-')} samples past the run's end (latency),
never applied.</p>
{ran_html(run, prov, [["decode", fmt(run.timing["decode_s"], 2)]])}
{files_html(getattr(run, "files", {}))}"""
    return write_page(out, run.scene.name, body, figure_names(run))


def agreement_html(run) -> str:
    """The engine agreement of an afferent run (and the board's link, when it ran)."""
    rows = [[k, v["spikes_a"], v["spikes_b"], f"{v['identical_trains']}/{v['neurons']}",
             fmt_distinct(v["mean_abs_count_diff"]), v["max_abs_count_diff"],
             fmt_distinct(v["mean_victor_purpura"]),
             fmt_distinct(v["fraction_within_1_tick"])]
            for k, v in run.agreement.items()]
    return f"""<h2>Engine agreement</h2>
{html_table(rows, ["pair", "spikes A", "spikes B", "identical trains", "mean |count diff|",
                   "max |count diff|", "mean VP (q = 5/s)", "within 1 tick"])}
{board_link_html(run.counters.get("board"))}"""


def ran_html(run, prov: dict, more_stages=()) -> str:
    """What an afferent run ran (stimulus, effects, front end, blocks, engines, version) and
    the wall time of each stage (``more_stages``: rows after the engines')."""
    ran, t = run.ran, run.timing
    git = prov["git"]
    stages = [["stimulus", fmt(t["stimulus_s"], 2)], ["front end", fmt(t["front_end_s"], 2)]]
    for e, v in t["engines_s"].items():
        sim_ms = run.counters.get(e, {}).get("simulate_ms")
        note = f" (simulation {sim_ms / 1000:.2f} s, rest generate + build)" if sim_ms else ""
        stages.append([f"engine {e}{note}", fmt(v, 2)])
    if "engines_wall_s" in t:
        stages.append(["all engines (HDL simulators overlapped with the others)",
                       fmt(t["engines_wall_s"], 2)])
    blocks = "; ".join(block_line(b) for b in ran["blocks"])
    return f"""<h2>What ran</h2>
<ul><li>stimulus: {html.escape(ran['stimulus'])}</li>
<li>effects: {html.escape(', '.join(ran['effects']) or 'none')}</li>
<li>front end: {html.escape('; '.join(ran.get('front_end_detail', ran['front_end'])))}</li>
<li>blocks: {html.escape(blocks)}</li>
<li>engines: {html.escape(', '.join(ran['engines']))}</li>
<li>cuneate {html.escape(prov['cuneate'])}{html.escape(
    f", commit {git['commit'][:12]}{' (modified)' if git['dirty'] else ''}" if git else "")}
(tools and seeds in run.json)</li></ul>
{html_table(stages + list(more_stages), ["stage", "wall s"])}"""


def board_link_line(c: dict) -> str:
    """The ``board`` engine's counters (``board_*`` keys of a run's counters) in one sentence:
    frames and bytes each way, frames lost, the cycles simulated, their rate and the device's
    time against its sweeps at the tick rate."""
    return (f"board link: {c['board_frames_to_device']} frames ({c['board_bytes_to_device']:,} "
            f"bytes) to the device, {c['board_frames_from_device']} frames "
            f"({c['board_bytes_from_device']:,} bytes) back, {c['frames_lost']} lost; "
            f"{c['board_cycles']:,} cycles at {c['board_cycles_per_s']:,}/s, "
            f"{c['board_cycles_per_sweep_rate']:.3f} x the sweeps' time")


def board_link_html(board: dict | None) -> str:
    """The board engine's line: frames, bytes and cycles, and the link budget table."""
    if not board or "link_budget" not in board:
        return ""
    b = board["link_budget"]
    rows = []
    for what, budget in (("measured (this run)", b["measured"]),
                         ("worst case (every current every sample)", b["worst_case"])):
        for r in budget["rows"]:
            rows.append([what, f"{r['baud']:,.0f}", f"{budget['in_bytes_per_s']:,.0f}",
                         f"{100 * r['in_load']:.0f} %", f"{budget['out_bytes_per_s']:,.0f}",
                         f"{100 * r['out_load']:.0f} %",
                         "yes" if r["real_time"] else "NO"])
    if "line_port" in board:
        where = (f"a programmed board on {html.escape(str(board['line_port']))} at "
                 f"{board['line_baud']:,} baud")
        sim = ""
    else:
        where = "the board top (UART link and core, Verilator) through a simulated serial line"
        sim = (f"; {board['line_cycles']:,} cycles at {board['line_cycles_per_s']:,} cycles/s "
               f"(simulated bit time {board['line_clocks_per_bit']} clocks a bit at both ends, "
               f"{board['line_baud_equivalent']:,} baud at the board's clock); the device took "
               f"{board['line_cycles_per_sweep_rate']:.3f} times its sweeps' time at the tick "
               f"rate (1: it never waited for the host; writes sent "
               f"{'ahead' if board.get('line_ahead') else 'in lockstep'})")
    return f"""<h2>The board's link</h2>
<p>The <code>board</code> engine ran {where} with the host stack a board uses:
{board['frames_sent']} frames to the device and {board['frames_received']} back,
{board['line_bytes_to_device']:,} and {board['line_bytes_from_device']:,} bytes,
{board['frames_lost']} lost{sim}. Real time on a board needs the traffic below within the line
rate, each way:</p>
{html_table(rows, ["traffic", "baud", "to device B/s", "load", "from device B/s", "load",
                   "real time"])}"""


def _published_note(noun: str) -> str:
    return (f"The last row is the <b>published protocol</b> (ISIs of one {noun} in training and "
            f"test folds), kept for comparison; its plain accuracy favours the classes with most "
            f"ISIs (largest class given beside it). ")


def format_run(run) -> str:
    """The lines ``cuneate run`` prints for an afferent scene run (its summary on the terminal)."""
    scene = run.scene
    out = [f"{scene.name}: {len(run.trial_class)} trials, {len(run.neurons)} neurons, "
           f"engines {', '.join(run.spikes)}"]
    first = next((d for d in run.decoded.values() if d.rows), None)
    if first is not None:
        h = first.headline
        out.append(f"  decoding {scene['decoder']['population'] or 'every afferent'}: "
                   f"balanced accuracy of the per-{scene.trial_noun} decision ({first.decision} "
                   f"vote), {h.cv} (chance {100 * h.chance_balanced:.0f} %)"
                   + ("; published protocol (per ISI, shuffled k-fold) beside it"
                      if first.row("published") else ""))
    for e, t in run.timing["engines_s"].items():
        d = run.decoded.get(e)
        if d is None:
            out.append(f"  {e:10s} not decoded  ({t:.1f} s)")
            continue
        if d.accuracy is None:
            out.append(f"  {e:10s} {d.reason}  ({t:.1f} s)")
            continue
        rec = ", ".join(f"{c} {'-' if v is None else f'{100 * v:.0f}'}"
                        for c, v in d.headline.recall.items())
        pub = d.row("published")
        pub = (f"; published {100 * pub.accuracy:.1f} % (balanced "
               f"{100 * pub.balanced_accuracy:.1f} %)") if pub else ""
        out.append(f"  {e:10s} balanced accuracy {100 * d.accuracy:5.1f} %  recall % "
                   f"{rec}{pub}  ({t:.1f} s)")
    if run.ran.get("in_turn"):
        out.append(in_turn_line(run.ran["in_turn"]))
    for k, v in run.decode_agreement.items():
        out.append(f"  balanced accuracy {k}: differs by {100 * v['difference']:.1f} points "
                   f"(tolerance {100 * v['tolerance']:.1f}): "
                   f"{'within' if v['within'] else 'OUTSIDE'}")
    s = run.saturations
    if s.get("samples_past_end"):
        out.append(f"  warning: {s['samples_past_end']} of {s['samples']} samples fall past the "
                   f"run's end (frontend.latency_ticks = "
                   f"{scene['frontend']['latency_ticks']}) and never reach the core")
    for e, sp in run.spikes.items():
        if s.get("samples_past_end") == s.get("samples"):
            out.append(f"  warning: {e}: no sample reached the core, so no spike is expected")
        elif not any(len(x) for x in sp):
            out.append(f"  warning: {e}: no neuron spiked (currents peak at "
                       f"{s['max_mV_per_ms']:.2f} mV/ms; an RS neuron needs about 3.8)")
    n_sat = s.get("format_low", 0) + s.get("format_high", 0)
    if n_sat:
        out.append(f"  warning: {n_sat} of {s['values']} currents saturated to {s['format']} "
                   f"(range {s['min_mV_per_ms']:.1f} .. {s['max_mV_per_ms']:.1f} mV/ms)")
    lay = _layer_summary(getattr(run, "layer", {}))
    if lay:
        out.append(f"  cuneate layer {lay['population']}: {lay['neurons']} neurons; spikes "
                   + ", ".join(f"{e} {n}" for e, n in lay["spike_counts"].items())
                   + (f"; decoded: {scene['decoder']['population']}"
                      if scene["decoder"]["population"] else ""))
    for k, v in run.agreement.items():
        out.append(f"  {k}: {v['identical_trains']}/{v['neurons']} identical trains, mean "
                   f"|spike count diff| {fmt_distinct(v['mean_abs_count_diff'])}")
    board = run.counters.get("board") or {}
    if "link_budget" in board:
        from .host.uart import format_budget
        sim = (f"; {board['line_cycles']:,} cycles at {board['line_cycles_per_s']:,}/s, "
               f"{board['line_cycles_per_sweep_rate']:.3f} x the sweeps' time"
               if "line_cycles" in board else f" on {board.get('line_port')}")
        out.append(f"  board link: {board['frames_sent']} frames to the device, "
                   f"{board['frames_received']} back, {board['frames_lost']} lost{sim}; "
                   f"line load:")
        out += [f"    {line}" for line in format_budget(board["link_budget"]["measured"])]
    return "\n".join(out)


def in_turn_line(turn: dict) -> str:
    """What ``cuneate run`` prints of trials played in turn (a run's ``ran["in_turn"]``)."""
    return (f"  trials in turn: {turn['trials_at_a_time']} at a time on the board's core, "
            f"{turn['groups']} groups of {turn['ticks_a_group']} ticks, each from the state "
            f"the last left")


def front_end_detail(scene, neurons) -> list[str]:
    """The front end of an afferent scene's encodings, one line each, and its timing."""
    fe, out = scene["frontend"], []
    for e in dict.fromkeys(neurons.encoding):
        if e.mode == "FA":
            filt = (f"b = {fe['filter_b']}, a = {fe['filter_a']}" if fe["filter_b"] is not None
                    else f"{fe['filter_kind']} band-pass {fe['filter_low_hz']:g}-"
                         f"{fe['filter_high_hz']:g} Hz, order {fe['filter_order']}")
            out.append(f"FA: {filt}; gain {e.gain:g} per {e.unit_pm:g} pm of shift; rectify "
                       f"{e.rectify}; window {fe['window']}")
        else:
            out.append(f"SA: gain {e.gain:g} per {e.unit_pm:g} pm of shift above "
                       f"{e.threshold_pm:g} pm")
    hold = int(scene["hardware"]["update_hz"] // scene["sensor"]["sample_rate_hz"])
    out.append(f"samples held {hold} ticks each, latency {fe['latency_ticks']} ticks")
    return out


def block_line(b: dict) -> str:
    """One block of a run, as the report lists it."""
    if b["block"] == "channel_fanout":
        return (f"channel_fanout ({b['n_channels']} channels: {b['channels_shift']} shift, "
                f"{b['channels_band']} band-passed, to {b['n_neurons']} afferents; samples "
                f"{b['sample_format']['format']} pm, table {b['table_bits']} bits, "
                f"{b['cycles_per_run']} cycles a run)")
    if b["block"] == "coincidence_detector" and "per_trial" in b:
        return (f"cuneate layer {b['population']} ({b['neurons']} cuneate neurons, "
                f"{b['per_trial']} a trial with fields of {len(b['fields'][0])}.."
                f"{len(b['fields'][-1])} gratings, {b['synapses']} synapses, fan-in "
                f"{'/'.join(map(str, b['fan_in']))}, delays {b['delays_ms']} ms, J w "
                f"{b['weights_mV_per_ms']} mV/ms in {b['weight_format']})")
    return (f"{b['block']} ({b['neurons']} neurons on a core of {b['core_neurons']}, sets "
            f"{', '.join(b['param_sets'])}, current {b['current_format']}, dt "
            f"{b['dt_ms']:g} ms)")
