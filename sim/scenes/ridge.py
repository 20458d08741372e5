"""Ridge-angle scenes: two stacked force sensors, SA and FA afferents, cuneate neurons.

A scene with ``stimulus.kind = "ridges"`` runs the brief's ridge experiment
(:mod:`cuneate.sim.coincidence.experiments`) through the scene machinery. Its shape is fixed by the
experiment and checked here: ``sensor.kind = "taxels"`` with ``grid = [2, 1]`` (an upper and a
lower sensor), one Izhikevich population with ``encoding = "SA"`` and one with ``"FA"`` (one
neuron per sensor; ``gain`` in mV/ms per N and per N/s), one ``model = "cuneate"`` population
(``encoding = "spikes"``, ``inputs`` the two afferent populations, one neuron per angle or per
row of given delays), and a ``[[projection]]`` from each afferent population to it: ``weight``
is the PSP amplitude ``J w`` (mV/ms); ``delays_ms`` either is left out (each cuneate neuron is
tuned to one angle: the earlier sensor's afferents are delayed by that angle's crossing lag) or
gives one ``[upper, lower]`` pair per cuneate neuron. The stimulus keys: ``ridge_angles_deg``
(the classes), ``speed_mm_per_s``, ``normal_force_N``, ``sensor_spacing_mm``,
``ridge_width_mm``, ``jitter_ms``, ``trial_ms``, ``onset_ms``, ``spread_speed``,
``spread_force``; ``scene.trials`` trials per angle. ``decoder.kind = "pattern"``: the set of
active cuneate neurons through a lookup table built on every other trial of each angle.

Only the afferent Izhikevich core (4 neurons) and the coincidence detector are built; the
engines are the scene's (golden: float64 afferents and detector; fixed and the simulators of
the detector: the core's twin for the afferents and the engine for the detector; ``board``:
the on-chip network, afferents and detector, behind the board's UART link, driven by the host
stack over a simulated serial line). The scene's block is the network
(:mod:`cuneate.sim.network`): every engine of the network runs it. The report compares each
engine's cuneate patterns and per-trial spike counts of both populations with the first
engine's.
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..coincidence.experiments import (RidgeSpec, detector_config, format_ridge, ridge_estimate,
                                       ridge_experiment, ridge_problem)
from ..engines.registry import block_engines, check_engine
from ..report import DPI, board_link_line, files_html, html_table, pyplot, write_page
from ..spikes import write_spikes
from .runner import EngineRuns, run_engines

__all__ = ["validate", "RidgeSceneRun", "run", "summary", "write_report", "format_run",
           "same_counts", "spec_of", "estimate"]


def validate(V, raw: dict, sections: dict, pops: list, projs: list) -> None:
    """Check and complete a ridge scene in place; ``V.err`` raises the scene error."""
    sen, st, sc, dec = (sections[k] for k in ("sensor", "stimulus", "scene", "decoder"))
    if sen["kind"] != "taxels" or (sen["grid"] or [2, 1]) != [2, 1]:
        V.err("sensor.grid", "a ridge scene has two stacked force sensors: sensor.kind = "
                             "\"taxels\", grid = [2, 1]")
    sen["grid"], sen["channels"] = [2, 1], 2
    angles = st["ridge_angles_deg"]
    if len(angles) < 2 or len(set(angles)) != len(angles) or any(abs(a) >= 80 for a in angles):
        V.err("stimulus.ridge_angles_deg", f"must list at least two different angles within "
                                           f"+-80 degrees, got {angles}")
    by_enc = {}
    for i, p in enumerate(pops):
        if p["model"] == "cuneate":
            by_enc.setdefault("cuneate", []).append((i, p))
        elif p["model"] == "izhikevich" and p["encoding"] in ("SA", "FA"):
            by_enc.setdefault(p["encoding"], []).append((i, p))
        else:
            V.err(f"population[{i}]", "a ridge scene has an SA and an FA Izhikevich population "
                                      "and one cuneate population")
    for k in ("SA", "FA", "cuneate"):
        if len(by_enc.get(k, [])) != 1:
            V.err("population", f"a ridge scene needs exactly one {k} population, got "
                                f"{len(by_enc.get(k, []))}")
    (ci, cn), = by_enc["cuneate"]
    aff = {by_enc["SA"][0][1]["name"]: "SA", by_enc["FA"][0][1]["name"]: "FA"}
    if cn["encoding"] not in (None, "spikes"):
        V.err(f"population[{ci}].encoding", "a cuneate population is driven by spikes")
    cn["encoding"] = "spikes"
    if cn["preset"] not in (None, "RS"):
        V.err(f"population[{ci}].preset", f"{cn['preset']!r}: a ridge scene's cuneate neurons "
                                          f"are the experiment's RS detector (a preset here "
                                          f"would not be applied); leave it out or write \"RS\"")
    cn["preset"] = "RS"
    if sorted(cn["inputs"]) != sorted(aff):
        V.err(f"population[{ci}].inputs", f"must name the two afferent populations "
                                          f"{sorted(aff)}")
    for j, p in ((j, p) for j, p in enumerate(pops) if p["model"] == "izhikevich"):
        if p["gratings"] not in (None, [0, 1]) or p["size"] not in (None, 2):
            V.err(f"population[{j}]", "an afferent population has one neuron per sensor "
                                      "(leave gratings and size out)")
    # projections: one per afferent population into the cuneate one
    pj = {}
    for i, q in enumerate(projs):
        if q["target"] != cn["name"] or q["source"] not in aff or q["source"] in pj:
            V.err(f"projection[{i}]", f"a ridge scene has one projection from each afferent "
                                      f"population ({', '.join(sorted(aff))}) to "
                                      f"{cn['name']!r}")
        if q["psp"] != "biexp":
            V.err(f"projection[{i}].psp", "the coincidence detector's PSP is \"biexp\"")
        if q["weight"] <= 0:
            V.err(f"projection[{i}].weight", "out of range: J w must be > 0 mV/ms")
        pj[q["source"]] = (i, q)
    if len(pj) != 2:
        V.err("projection", f"a ridge scene needs a projection from each of "
                            f"{', '.join(sorted(aff))} to {cn['name']!r}")
    rows = None
    given = [(i, q) for i, q in pj.values()
             if "delays_ms" in raw.get("projection", [{}] * len(projs))[i]]
    for i, q in given:
        d = q["delays_ms"]
        if len(d) % 2:
            V.err(f"projection[{i}].delays_ms", "give [upper, lower] delays per cuneate neuron "
                                                "(an even number of values)")
        r = [d[k:k + 2] for k in range(0, len(d), 2)]
        if rows is not None and r != rows:
            V.err(f"projection[{i}].delays_ms", "the SA and FA projections must use the same "
                                                "delays (one pair per cuneate neuron)")
        rows = r
    if given and len(given) != 2:
        V.err(f"projection[{given[0][0]}].delays_ms", "give the delays on both projections or "
                                                      "on neither")
    n_cn = len(rows) if rows is not None else len(angles)
    if cn["size"] is not None and cn["size"] != n_cn:
        V.err(f"population[{ci}].size", f"{n_cn} cuneate neurons (one per "
                                        f"{'delay pair' if rows else 'angle'}), got {cn['size']}")
    cn["size"] = n_cn
    dt = 1000.0 / sections["hardware"]["update_hz"]
    if rows is not None:
        for i, _ in given:
            for r in rows:
                for x in r:
                    if abs(x / dt - round(x / dt)) > 1e-9:
                        V.err(f"projection[{i}].delays_ms", f"{x:g} ms is not a whole number "
                                                            f"of ticks (dt = {dt:g} ms)")
    st["_delay_rows_ms"] = rows
    st["_afferents"] = aff
    if "kind" not in raw.get("decoder", {}):
        dec["kind"] = "pattern"
    elif dec["kind"] not in ("pattern", "none"):
        V.err("decoder.kind", f"a ridge scene decodes the pattern of active cuneate neurons "
                              f"(kind = \"pattern\" or \"none\"), got {dec['kind']!r}")
    if st["trial_ms"] <= st["onset_ms"]:
        V.err("stimulus.trial_ms", "must exceed onset_ms")
    if sc["trials"] < 2:
        V.err("scene.trials", "a ridge scene needs at least 2 trials per angle (half train "
                              "the lookup table)")
    bad = ridge_problem(spec_of(_Sections(sections, pops, projs)))
    if bad is not None:
        V.err(f"stimulus.{bad[0]}", bad[1])


class _Sections:
    """The parts of a scene :func:`spec_of` reads, while the scene is being validated."""

    def __init__(self, sections, populations, projections):
        self.sections, self.populations, self.projections = sections, populations, projections

    def __getitem__(self, key):
        return self.sections[key]


def spec_of(scene):
    """The :class:`~cuneate.sim.coincidence.experiments.RidgeSpec` of a ridge scene."""
    st, sc, hw = scene["stimulus"], scene["scene"], scene["hardware"]
    pops = {p["name"]: p for p in scene.populations}
    aff = st["_afferents"]
    gain = {enc: pops[n]["gain"] for n, enc in aff.items()}
    proj = {aff[q["source"]]: q for q in scene.projections}
    dt = 1000.0 / hw["update_hz"]
    rows = st["_delay_rows_ms"]
    delays = None if rows is None else [[int(round(u / dt))] * 2 + [int(round(lo / dt))] * 2
                                        for u, lo in rows]
    return RidgeSpec(angles_deg=tuple(st["ridge_angles_deg"]),
                     speed_mm_per_s=st["speed_mm_per_s"], force_N=st["normal_force_N"],
                     spacing_mm=st["sensor_spacing_mm"], ridge_width_mm=st["ridge_width_mm"],
                     sa_gain=gain["SA"] if gain["SA"] is not None else RidgeSpec.sa_gain,
                     # the scene's FA gain is per N/s, the experiment's per N/ms
                     fa_gain=gain["FA"] * 1000.0 if gain["FA"] is not None
                     else RidgeSpec.fa_gain,
                     weight=proj["SA"]["weight"], weight_fa=proj["FA"]["weight"],
                     trial_ms=st["trial_ms"], onset_ms=st["onset_ms"],
                     trials_per_angle=sc["trials"], spread_speed=st["spread_speed"],
                     spread_force=st["spread_force"], jitter_ms=st["jitter_ms"], seed=sc["seed"],
                     update_hz=hw["update_hz"], delays_ticks=delays)


def estimate(scene, engines: list[str]) -> dict:
    """Memory (bytes) and time (s) of the ridge scene on ``engines``
    (:func:`cuneate.sim.coincidence.experiments.ridge_estimate` of its experiment)."""
    return ridge_estimate(spec_of(scene), engines)


@dataclass
class RidgeSceneRun(EngineRuns):
    """The result of a ridge scene: one ridge experiment per engine."""

    kind: str = "ridge"


def run(scene, engines=None, build_dir=None, progress=False, log=None):
    """Run a ridge scene on its engines (or ``engines``)."""
    say = log or (lambda msg: None)
    names = list(engines or scene.engines)
    for e in names:
        check_engine("network", e)
    spec = spec_of(scene)
    cfg = detector_config(spec)
    results, seconds = run_engines(
        names, lambda e, bd: ridge_experiment(e, spec, build_dir=bd), build_dir,
        lambda e, r, s: say(f"engine {e}: accuracy {100 * r.accuracy:.1f} % ({s:.1f} s)"))
    timing = {"engines_s": seconds}
    ran = {"stimulus": "ridges", "effects": [], "engines": names,
           "blocks": [{"block": "izhikevich_core", "neurons": 4, "role": "SA and FA afferents"},
                      {"block": "coincidence_detector", "neurons": cfg.n_targets,
                       "sources": cfg.n_sources, "delays_ticks": cfg.delays.tolist(),
                       "delays_ms": (cfg.delays * cfg.dt_ms).tolist(), "dt_ms": cfg.dt_ms,
                       "weights_mV_per_ms": cfg.weights_real.tolist()}],
           # engines that run the afferents and the detector as one on-chip network
           "on_chip_engines": [e for e in names if e not in block_engines("coincidence")]}
    return RidgeSceneRun(scene, results, ran, timing)


def summary(run: RidgeSceneRun) -> dict:
    """The run as a JSON-ready dictionary (``run.json``)."""
    return {"scene": run.scene.name, "source": run.scene.source, "kind": "ridge",
            "accuracy": {e: r.accuracy for e, r in run.results.items()},
            "engines": {e: r.to_dict() for e, r in run.results.items()},
            "identical_patterns": {e: r.patterns == run.results[next(iter(run.results))]
                                   .patterns for e, r in run.results.items()},
            "identical_counts": {e: same_counts(r, next(iter(run.results.values())))
                                 for e, r in run.results.items()},
            "ran": run.ran, "timing": run.timing, "spike_files": run.files.get("spikes", {}),
            "resolved_scene": run.scene.to_dict()}


def same_counts(a, b) -> dict:
    """Whether two engines' results have the same spikes per trial: ``{"cuneate": bool,
    "afferent": bool}``."""
    return {"cuneate": bool(np.array_equal(a.counts, b.counts)),
            "afferent": bool(np.array_equal(a.afferent_counts, b.afferent_counts))}


def format_run(run: RidgeSceneRun) -> str:
    """The lines ``cuneate run`` prints for a ridge scene."""
    out = [f"{run.scene.name}: engines {', '.join(run.results)}"]
    first_e, first = next(iter(run.results.items()))
    for e, r in run.results.items():
        out.append(format_ridge(r) + f"  ({run.timing['engines_s'][e]:.1f} s)")
        if "board_cycles" in r.counters:
            out.append(f"  {board_link_line(r.counters)}")
        if e != first_e:
            same = same_counts(r, first)
            out.append(f"  {e} vs {first_e}: cuneate spikes per trial "
                       f"{'identical' if same['cuneate'] else 'DIFFER'}, afferent spikes per "
                       f"trial {'identical' if same['afferent'] else 'DIFFER'}")
    return "\n".join(out)


def write_spike_files(run: RidgeSceneRun, out: Path) -> dict:
    """``spikes_<engine>.npz`` per engine (:mod:`cuneate.sim.spikes`): per trial the four
    afferents (SA and FA of the upper sensor, then of the lower: gratings 0, 0, 1, 1) and the
    cuneate neurons (grating -1), times from the trial's start, its class the ridge angle;
    returns ``{engine: file}``."""
    sa, fa = (next(n for n, k in run.scene["stimulus"]["_afferents"].items() if k == kind)
              for kind in ("SA", "FA"))
    cn = next(p["name"] for p in run.scene.populations if p["model"] == "cuneate")
    files = {}
    for e, r in run.results.items():
        per, dt = r.ticks_per_trial, 1000.0 / run.scene["hardware"]["update_hz"]
        trains, pop, trial, grating, cls = [], [], [], [], []
        for j, angle in enumerate(r.trial_angle):
            for ticks, p, g in ([*zip(r.afferent_ticks, (sa, fa, sa, fa), (0, 0, 1, 1))]
                                + [(t, cn, -1) for t in r.cuneate_ticks]):
                t = np.asarray(ticks, dtype=np.int64)
                mine = t[(t - 1) // per == j] - j * per
                trains.append(mine * dt)
                pop.append(p)
                trial.append(j)
                grating.append(g)
                cls.append(f"{angle:+g} deg")
        name = f"spikes_{e}.npz"
        write_spikes(Path(out) / name, trains, e, per * dt, pop, trial, grating, cls, dt)
        files[e] = name
    return files


def write_report(run: RidgeSceneRun, out: Path) -> Path:
    """Write the spike files, ``index.html``, ``run.json`` and one figure per engine into
    ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    run.files = {"spikes": write_spike_files(run, out)}
    (out / "run.json").write_text(json.dumps(summary(run), indent=2, default=float))
    plt = pyplot()
    figs = []
    for e, r in run.results.items():
        mean = np.array([r.counts[[a == x for x in r.trial_angle]].mean(axis=0)
                         for a in r.angles])
        fig, ax = plt.subplots(figsize=(5, 3.4))
        ax.imshow(mean, cmap="Greens", aspect="auto")
        top = max(1e-9, float(mean.max()))
        for (i, j), c in np.ndenumerate(mean):
            ax.text(j, i, f"{c:.1f}", ha="center", va="center", fontsize=9,
                    color="white" if c > top / 2 else "black")
        ax.set(xticks=range(mean.shape[1]), xticklabels=[f"CN{j}" for j in
                                                         range(mean.shape[1])],
               yticks=range(len(r.angles)), yticklabels=[f"{a:+g} deg" for a in r.angles],
               title=f"{e}: mean spikes per trial ({100 * r.accuracy:.0f} % decoded)")
        fig.tight_layout()
        fig.savefig(out / f"ridge_{e}.png", dpi=DPI)
        plt.close(fig)
        figs.append(f"ridge_{e}.png")
    acc_rows = [[e, f"{100 * r.accuracy:.1f}", len(r.trial_angle),
                 "; ".join(f"{list(p) or '[]'} -> {a:+g}" for p, a in sorted(r.table.items())),
                 f"{run.timing['engines_s'][e]:.2f}"] for e, r in run.results.items()]
    first = next(iter(run.results.values()))
    same = [[e, "yes" if r.patterns == first.patterns else "NO",
             "yes" if np.array_equal(r.counts, first.counts) else "no",
             "yes" if same_counts(r, first)["afferent"] else "no"]
            for e, r in list(run.results.items())[1:]]
    cn = run.ran["blocks"][1]
    body = f"""
<p>Scene: {html.escape(run.scene.source)}. Two stacked force sensors, SA and FA afferents per
sensor, {cn['neurons']} cuneate neurons that differ only in their conduction delays.</p>
<h2>Decoding (lookup table from every other trial of each angle)</h2>
{html_table(acc_rows, ["engine", "accuracy %", "trials", "table", "run s"])}
<h2>Agreement with {html.escape(next(iter(run.results)))}</h2>
{html_table(same, ["engine", "same patterns", "same cuneate spike counts",
                   "same afferent spike counts"]) if same else
 "<p>(one engine ran: nothing to compare)</p>"}
<h2>What ran</h2>
<ul><li>stimulus: ridges at {html.escape(', '.join(f'{a:+g}' for a in first.angles))} degrees</li>
<li>effects: none (force sensors)</li>
{''.join(f"<li>{html.escape(e)}: {html.escape(board_link_line(r.counters))}</li>"
         for e, r in run.results.items() if "board_cycles" in r.counters)}
<li>blocks: Izhikevich core (4 afferents), coincidence detector ({cn['neurons']} x
{cn['sources']}, delays (ms, upper and lower sensor per cuneate neuron)
{html.escape(str([[round(x, 4) for x in row] for row in cn['delays_ms']]))}, ticks of
{cn['dt_ms']:g} ms)</li>
<li>engines: {html.escape(', '.join(run.results))}</li></ul>
"""
    return write_page(out, run.scene.name, body + files_html(run.files), figs)
