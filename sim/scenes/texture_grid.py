"""A texture scene's grid of sensing conditions (``[grid]``): each condition its own run on a
Dask cluster (:func:`cuneate.sim.sweep.dask_map`), decoded alone (the heat map), then the
spatial VP across velocities and across forces; the grid's report."""

from __future__ import annotations

import html
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import progress as prog
from ..decode import decode_conditions
from ..provenance import provenance
from ..report import html_table, pyplot, save_figure, write_page
from ..sweep import dask_connect, dask_map
from .texture_trials import SEEDS, condition_scene, conditions
from .texture_trials import pct as _pct
from .texture_trials import run_single, trains_by_channel

__all__ = ["GridRun", "run_condition", "spatial_rows", "run_grid", "grid_table", "grid_notes",
           "format_grid", "write_grid", "grid_summary"]


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


def grid_summary(run) -> dict:
    """A grid's ``run.json``: each condition's decoding (not its trains), the spatial VP."""
    return {"scene": run.scene.name, "source": run.scene.source, "kind": "texture grid",
            "cells": [{k: v for k, v in c.items() if k != "trains"} for c in run.cells],
            "spatial": run.spatial, "timing": run.timing, "seeds": SEEDS,
            "resolved_scene": run.scene.to_dict(),
            "provenance": provenance(seeds={"scene.seed": run.scene["scene"]["seed"],
                                            "stimulus.texture_seed":
                                                run.scene["stimulus"]["texture_seed"]})}


def grid_table(run, engine: str) -> tuple[list, list, dict]:
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
    forces, vels, mats = grid_table(run, engine)
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


def format_grid(run) -> str:
    out = [f"{run.scene.name}: grid of {len(run.cells)} conditions "
           f"({run.timing['conditions_s']:.1f} s on {run.timing['workers']})"]
    for e in run.cells[0]["decoding"]:
        forces, vels, mats = grid_table(run, e)
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


def write_grid(run, out: Path) -> Path:
    plt = pyplot()
    figs = []
    for e in run.cells[0]["decoding"]:
        forces, vels, mats = grid_table(run, e)
        fig, axes = plt.subplots(1, 4, figsize=(16, 3.8), layout="constrained")
        for k, (ax, (key, m)) in enumerate(zip(axes, mats.items())):
            im = ax.imshow(100 * m, cmap="RdYlGn", vmin=0, vmax=100, origin="lower")
            for (i, j), x in np.ndenumerate(m):
                ax.text(j, i, "-" if x != x else f"{100 * x:.0f}", ha="center", va="center",
                        fontsize=8)
            ax.set_xticks(range(len(vels)), [f"{v:g}" for v in vels])
            ax.set_yticks(range(len(forces)), [f"{f:g}" for f in forces])
            ax.set(xlabel="velocity (mm/s)", ylabel="force (mN)" if k == 0 else "",
                   title=f"{e}: {key[0]}, {key[1]}")
        fig.colorbar(im, ax=axes, label="balanced accuracy %", shrink=0.9)
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
    (out / "run.json").write_text(json.dumps(grid_summary(run), indent=2, default=float))
    return write_page(out, run.scene.name, body, figs)
