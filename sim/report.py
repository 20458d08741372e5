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
import json
import re
from pathlib import Path

import numpy as np

__all__ = ["write_report", "summary_dict", "figure_names", "page_head", "figures_html",
           "pyplot", "html_table", "fmt", "write_page", "printable"]


def pyplot():
    """matplotlib's pyplot on the non-interactive Agg backend."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _first_trials(run) -> list[int]:
    seen, out = set(), []
    for t, c in enumerate(run.trial_class):
        if c not in seen:
            seen.add(c)
            out.append(t)
    return out


def figure_names(run) -> list[str]:
    names = ["traces.png", "currents.png"]
    for e in run.spikes:
        names += [f"raster_{e}.png", f"isi_{e}.png"]
        if e in run.decoded and run.decoded[e].accuracy is not None:
            names.append(f"confusion_{e}.png")
    return names


def _fig_traces(run, out: Path, plt):
    firsts = _first_trials(run)
    fs = run.scene["sensor"]["sample_rate_hz"]
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.6))
    for t in firsts:
        x = run.traces[t]
        tm = np.arange(x.shape[0]) * 1000.0 / fs
        for g in range(x.shape[1]):
            ax[0].plot(tm, x[:, g] * 1e3, lw=1, label=f"{run.trial_class[t]} g{g}")
    ax[0].set(xlabel="time (ms)", ylabel="Δλ (pm)", title="Bragg shift, first trial per class")
    ax[0].legend(fontsize=7)
    cols = [i for i, t in enumerate(run.neurons.trial) if t in firsts]
    tm = np.arange(run.currents.shape[0]) * 1000.0 / fs
    for i in cols:
        ax[1].plot(tm, run.currents[:, i], lw=1,
                   label=f"{run.trial_class[run.neurons.trial[i]]} "
                         f"{run.neurons.population[i]} g{run.neurons.grating[i]}")
    ax[1].set(xlabel="time (ms)", ylabel="current (mV/ms)", title="front-end currents")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    # two files so that each figure can be linked on its own
    ext = ax[1].get_tightbbox(fig.canvas.get_renderer()).transformed(
        fig.dpi_scale_trans.inverted())
    fig.savefig(out / "currents.png", dpi=90, bbox_inches=ext.expanded(1.02, 1.04))
    ext = ax[0].get_tightbbox(fig.canvas.get_renderer()).transformed(
        fig.dpi_scale_trans.inverted())
    fig.savefig(out / "traces.png", dpi=90, bbox_inches=ext.expanded(1.02, 1.04))
    plt.close(fig)


def _fig_engine(run, e, out: Path, plt):
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
    fig.savefig(out / f"raster_{e}.png", dpi=90)
    plt.close(fig)
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
    fig.savefig(out / f"isi_{e}.png", dpi=90)
    plt.close(fig)
    d = run.decoded.get(e)
    if d is not None and d.accuracy is not None:
        fig, ax = plt.subplots(figsize=(4.6, 4))
        ax.imshow(d.confusion, cmap="Blues")
        ax.set_xticks(range(len(d.classes)), d.classes, rotation=45, ha="right", fontsize=7)
        ax.set_yticks(range(len(d.classes)), d.classes, fontsize=7)
        top = max(1, int(np.max(d.confusion)))
        for i in range(len(d.classes)):
            for j in range(len(d.classes)):
                c = int(d.confusion[i, j])
                ax.text(j, i, c, ha="center", va="center", fontsize=7,
                        color="white" if c > top / 2 else "black")
        ax.set(xlabel="predicted", ylabel="true", title=f"{e}: {100 * d.accuracy:.1f} %")
        fig.tight_layout()
        fig.savefig(out / f"confusion_{e}.png", dpi=90)
        plt.close(fig)


def class_currents(run) -> list[dict]:
    rows = []
    for c in run.classes:
        cols = [i for i, t in enumerate(run.neurons.trial) if run.trial_class[t] == c]
        peaks = run.currents[:, cols].max(axis=0)
        rows.append({"class": c, "peak_min": float(peaks.min()), "peak_max": float(peaks.max()),
                     "min": float(run.currents[:, cols].min())})
    return rows


def summary_dict(run) -> dict:
    return {
        "scene": run.scene.name, "source": run.scene.source, "classes": run.classes,
        "trials": len(run.trial_class), "neurons": len(run.neurons), "ticks": run.n_ticks,
        "dt_ms": run.dt_ms,
        "accuracy": {e: d.accuracy for e, d in run.decoded.items()},
        "decoded": {e: d.to_dict() for e, d in run.decoded.items()},
        "agreement": run.agreement, "decode_agreement": run.decode_agreement,
        "saturations": run.saturations,
        "current_per_class": class_currents(run), "ran": run.ran, "timing": run.timing,
        "counters": run.counters,
        "spike_counts": {e: int(sum(len(s) for s in sp)) for e, sp in run.spikes.items()},
        "resolved_scene": run.scene.to_dict(),
    }


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
<style>body{{font-family:sans-serif;max-width:1100px;margin:1em auto;}}
table{{border-collapse:collapse;margin:.5em 0;}}td,th{{border:1px solid #bbb;padding:2px 8px;}}
figure{{display:inline-block;margin:4px;}}img{{max-width:520px;}}</style></head><body>
<h1>{html.escape(name)}</h1>"""


def write_page(out: Path, head: str, body: str, figures) -> Path:
    """``out/index.html``: the page head (:func:`page_head` of ``head``), ``body`` and the
    figures section; returns its path."""
    path = Path(out) / "index.html"
    path.write_text(printable(f"{page_head(head)}\n{body}\n<h2>Figures</h2>\n"
                              f"{figures_html(figures)}\n</body></html>\n"))
    return path


def figures_html(names) -> str:
    """Linked figures; one that fails to load says so on the browser console."""
    return "".join(f'<figure><img src="{n}" alt="{n}" onerror="console.error(\'missing figure: '
                   f'\' + this.getAttribute(\'src\'))"><figcaption>{n}</figcaption></figure>'
                   for n in names)


def fmt(x, nd=3):
    """A number for a table: ``-`` for None, ``nd`` decimals for floats."""
    return "-" if x is None else (f"{x:.{nd}f}" if isinstance(x, float) else str(x))


def write_report(run, out: Path) -> Path:
    """Write figures, ``run.json`` and ``index.html`` into ``out``; returns the HTML path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    plt = pyplot()
    _fig_traces(run, out, plt)
    for e in run.spikes:
        _fig_engine(run, e, out, plt)
    summ = summary_dict(run)
    (out / "run.json").write_text(json.dumps(summ, indent=2, default=float))
    acc_rows = [[e, fmt(100 * d.accuracy, 1) if d.accuracy is not None else d.reason,
                 d.n_samples, d.folds, f"{d.kind} / {d.features}",
                 fmt(run.timing["engines_s"].get(e), 2)] for e, d in run.decoded.items()]
    agr_rows = [[k, v["spikes_a"], v["spikes_b"], f"{v['identical_trains']}/{v['neurons']}",
                 fmt(v["mean_abs_count_diff"]), v["max_abs_count_diff"],
                 fmt(v["mean_victor_purpura_q1"]), fmt(v["fraction_within_1_tick"])]
                for k, v in run.agreement.items()]
    cur_rows = [[r["class"], fmt(r["peak_min"], 1), fmt(r["peak_max"], 1), fmt(r["min"], 1)]
                for r in summ["current_per_class"]]
    s = run.saturations
    n_sat = s.get("format_low", 0) + s.get("format_high", 0)
    n_range = s.get("range_low", 0) + s.get("range_high", 0)
    ran = run.ran
    t = run.timing
    stage_rows = [["stimulus", fmt(t["stimulus_s"], 2)], ["front end", fmt(t["front_end_s"], 2)]]
    for e, v in t["engines_s"].items():
        sim_ms = run.counters.get(e, {}).get("simulate_ms")
        note = f" (simulation {sim_ms / 1000:.2f} s, rest generate + build)" if sim_ms else ""
        stage_rows.append([f"engine {e}{note}", fmt(v, 2)])
    if "engines_wall_s" in t:
        stage_rows.append(["all engines (HDL simulators overlapped with the others)",
                           fmt(t["engines_wall_s"], 2)])
    stage_rows += [["decode", fmt(t["decode_s"], 2)]]
    figs = figures_html(figure_names(run))
    blocks = "; ".join(f"{b['block']} ({b['neurons']} neurons on a core of "
                       f"{b['core_neurons']}, sets {', '.join(b['param_sets'])}, "
                       f"current {b['current_format']}, dt {b['dt_ms']:g} ms)"
                       for b in ran["blocks"])
    page = f"""{page_head(run.scene.name)}
<p>Scene: {html.escape(run.scene.source)}. {len(run.trial_class)} trials of {len(run.classes)}
classes, {len(run.neurons)} neurons, {run.n_ticks} ticks of {run.dt_ms:g} ms.</p>
<h2>Decoding accuracy (cross-validated)</h2>
{html_table(acc_rows, ["engine", "accuracy %", "samples", "folds", "decoder", "engine run s"])}
<p>{html.escape("; ".join(
    f"{k}: accuracies differ by {100 * v['difference']:.1f} points, tolerance "
    f"{100 * v['tolerance']:.1f}: {'within' if v['within'] else 'OUTSIDE'}"
    for k, v in run.decode_agreement.items()))}</p>
<h2>Engine agreement</h2>
{html_table(agr_rows, ["pair", "spikes A", "spikes B", "identical trains", "mean |count diff|",
                   "max |count diff|", "mean VP (q=1/ms)", "within 1 tick"])}
<h2>Currents per class (mV/ms) and saturation</h2>
{html_table(cur_rows, ["class", "lowest peak", "highest peak", "minimum"])}
<p>Format {html.escape(str(s.get('format')))}: {n_sat} of {s.get('values')} values saturated by
the driver; {n_range} outside the accepted range; {s.get('gaps_held', 0)} missing samples held;
{s.get('samples_past_end', 0)} of {s.get('samples', '-')} samples past the run's end (latency),
never applied.</p>
<h2>What ran</h2>
<ul><li>stimulus: {html.escape(ran['stimulus'])}</li>
<li>effects: {html.escape(', '.join(ran['effects']) or 'none')}</li>
<li>front end: {html.escape('; '.join(ran.get('front_end_detail', ran['front_end'])))}</li>
<li>blocks: {html.escape(blocks)}</li>
<li>engines: {html.escape(', '.join(ran['engines']))}</li></ul>
{html_table(stage_rows, ["stage", "wall s"])}
<h2>Figures</h2>
{figs}
</body></html>
"""
    path = out / "index.html"
    path.write_text(printable(page))
    return path
