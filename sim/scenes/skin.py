"""Taxel-skin scenes: a grid of force sensors, one LIF neuron per taxel, a pressed taxel.

A scene with ``sensor.kind = "taxels"`` and ``stimulus.kind = "press"`` runs the brief's skin
experiment (:func:`cuneate.sim.lif.experiments.skin_grid`) through the scene machinery: the
taxel ``stimulus.press_taxel`` of a ``sensor.grid`` (rows, columns) is pressed with rectangular
force pulses of growing width (``press_widths_ms`` at ``press_base_amplitude_N``), then of
growing amplitude (``press_amplitudes_N`` for ``press_base_width_ms``), each followed by
``press_gap_ms`` of rest; the edge and diagonal neighbours feel ``press_spread`` of the force.
The force is sampled at ``sensor.sample_rate_hz`` and held per tick; each taxel's current is
``frontend.force_offset_mV + frontend.force_gain_mV_per_N * force``. Only the LIF core is
built (sized to the grid, state and current formats derived by :class:`~cuneate.hdl.lif.
LifConfig`); only the scene's engines run. The decoder ``winner`` names the taxel with the
most spikes; the run says whether counts grow monotonically with width and with amplitude,
which taxel wins, and the row and column sums, per engine, with the spike-train agreement
between engines.

:func:`validate` checks the scene's skin keys (called by
:func:`cuneate.sim.scenes.scene.parse_scene`); :func:`run` runs it; :func:`write_report` writes
``index.html``, ``run.json`` and figures.
"""

from __future__ import annotations

import html
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...golden.budget import BASE_BYTES, array_bytes
from ...hdl.lib.fixed import QFormat
from ..engines.registry import ENGINES, check_engine, estimate_seconds
from ..lif.engines import engine_config
from ..lif.experiments import skin_grid, skin_protocol
from ..report import (DPI, board_link_line, files_html, fmt, fmt_distinct, html_table, pyplot,
                      write_page)
from ..spikes import write_spikes
from .runner import EngineRuns, engines_agreement, run_engines

__all__ = ["LIF_PRESETS", "validate", "SkinSceneRun", "run", "summary", "write_report",
           "format_run", "estimate"]

#: LIF parameter sets a skin population may name (the brief's two cells).
LIF_PRESETS = {
    "excitatory": {"tau_m_ms": 20.0, "t_ref_ms": 2.0},
    "inhibitory": {"tau_m_ms": 10.0, "t_ref_ms": 1.0},
}
LIF_CURRENT_FORMAT = (8, 8)
MAX_GRID = 64


def _increasing(xs) -> bool:
    return all(b > a for a, b in zip(xs, xs[1:]))


def validate(V, raw: dict, sections: dict, pops: list, projs: list) -> None:
    """Check and complete a taxel-skin scene in place; ``V.err`` raises the scene error."""
    sen, st, sc = sections["sensor"], sections["stimulus"], sections["scene"]
    fe, hw, dec = sections["frontend"], sections["hardware"], sections["decoder"]
    if sen["kind"] != "taxels":
        V.err("stimulus.kind", "a press stimulus needs sensor.kind = \"taxels\"")
    if st["kind"] != "press":
        V.err("stimulus.kind", f"a taxel sensor takes a press stimulus in this build, got "
                               f"{st['kind']!r}")
    grid = sen["grid"] if sen["grid"] is not None else [3, 3]
    if len(grid) != 2 or not all(1 <= g <= MAX_GRID for g in grid):
        V.err("sensor.grid", f"must be [rows, columns], each in 1..{MAX_GRID}, got {grid}")
    rows, cols = grid
    if "channels" in raw.get("sensor", {}) and sen["channels"] != rows * cols:
        V.err("sensor.channels", f"a {rows}x{cols} grid has {rows * cols} taxels, got "
                                 f"{sen['channels']}")
    sen["grid"], sen["channels"] = [rows, cols], rows * cols
    if not st["press_taxel"] < rows * cols:
        V.err("stimulus.press_taxel", f"out of range: {st['press_taxel']} (the grid has taxels "
                                      f"0..{rows * cols - 1}, row-major)")
    for key, unit in (("press_widths_ms", "widths"), ("press_amplitudes_N", "amplitudes")):
        xs = st[key]
        if len(xs) < 2 or any(x <= 0 for x in xs) or not _increasing(xs):
            V.err(f"stimulus.{key}", f"must list at least two growing {unit} > 0, got {xs}")
    sp = st["press_spread"]
    if len(sp) != 2 or not all(0 <= x <= 1 for x in sp):
        V.err("stimulus.press_spread", f"must be [edge, diagonal] fractions in 0..1, got {sp}")
    # deterministic protocol: one trial
    if raw.get("scene", {}).get("trials", 1) != 1:
        V.err("scene.trials", "a press stimulus is deterministic: one trial")
    sc["trials"] = 1
    hold = int(round(hw["update_hz"] / sen["sample_rate_hz"]))
    force, _ = skin_protocol(st["press_widths_ms"], st["press_amplitudes_N"],
                             st["press_base_amplitude_N"], st["press_base_width_ms"],
                             st["press_gap_ms"], dt_ms=1000.0 / sen["sample_rate_hz"])
    proto_ms = force.size * hold * 1000.0 / hw["update_hz"]
    if "duration_ms" in raw.get("scene", {}):
        if sc["duration_ms"] < proto_ms:
            V.err("scene.duration_ms", f"shorter than the press protocol ({proto_ms:g} ms)")
    else:
        sc["duration_ms"] = proto_ms
    # one LIF population, force-encoded, one neuron per taxel
    if len(pops) != 1:
        V.err("population", "a taxel skin has exactly one population (one LIF neuron per "
                            "taxel)")
    p = pops[0]
    if p["model"] != "lif":
        V.err("population[0].model", f"a taxel skin drives LIF neurons in this build, got "
                                     f"{p['model']!r}")
    if p["encoding"] not in (None, "force"):
        V.err("population[0].encoding", f"a taxel skin encodes force, got {p['encoding']!r}")
    p["encoding"] = "force"
    if p["preset"] is None:
        p["preset"] = "excitatory"
    if p["preset"] not in LIF_PRESETS:
        V.err("population[0].preset", f"unknown LIF preset {p['preset']!r} (known: "
                                      f"{', '.join(LIF_PRESETS)})")
    if p["gratings"] is not None:
        V.err("population[0].gratings", "a taxel skin drives every taxel (leave gratings out)")
    if p["size"] is not None and p["size"] != rows * cols:
        V.err("population[0].size", f"one neuron per taxel ({rows * cols}), got {p['size']}")
    if p["inputs"]:
        V.err("population[0].inputs", "a force-encoded population takes no spike inputs")
    # the LIF core's current format: the hardware keys if given, else the core's own default
    raw_hw = raw.get("hardware", {})
    hw["current_int_bits"] = raw_hw.get("current_int_bits", LIF_CURRENT_FORMAT[0])
    hw["current_frac_bits"] = raw_hw.get("current_frac_bits", LIF_CURRENT_FORMAT[1])
    fmt = QFormat(hw["current_int_bits"], hw["current_frac_bits"])
    f_max = max(st["press_amplitudes_N"] + [st["press_base_amplitude_N"]])
    ends = [fe["force_offset_mV"], fe["force_offset_mV"] + fe["force_gain_mV_per_N"] * f_max]
    if min(ends) < fmt.min_value or max(ends) > fmt.max_value:
        V.err("frontend.force_gain_mV_per_N",
              f"currents {min(ends):g}..{max(ends):g} mV leave the LIF core's input format "
              f"{fmt} [{fmt.min_value:g}, {fmt.max_value:g}]: lower the gain or widen "
              f"hardware.current_int_bits")
    if rows * cols > hw["clock_hz"] / hw["update_hz"]:
        V.err("hardware.clock_hz", f"{rows * cols} taxels do not fit one LIF core at "
                                   f"{hw['clock_hz']:g} Hz / {hw['update_hz']:g} Hz")
    if "kind" not in raw.get("decoder", {}):
        dec["kind"] = "winner"
    elif dec["kind"] not in ("winner", "none"):
        V.err("decoder.kind", f"a taxel skin decodes the pressed taxel (kind = \"winner\" or "
                              f"\"none\"), got {dec['kind']!r}")


def estimate(scene, engines: list[str]) -> dict:
    """Memory (bytes) and time (s) of the skin scene on ``engines``: the force and current
    arrays per tick and taxel (and each engine's program), each engine's updates (or cycles)
    at the registry's speed."""
    rows, cols = scene["sensor"]["grid"]
    n = rows * cols
    n_ticks = scene["scene"]["duration_ms"] * scene["hardware"]["update_hz"] / 1000.0
    per_tick = array_bytes(n_ticks, n)
    nbytes = BASE_BYTES + 3 * per_tick + sum(3 * per_tick for _ in engines)
    seconds = sum(estimate_seconds("lif", e, n_ticks * (n + 8 if ENGINES[e].hdl else n))
                  for e in engines)
    return {"bytes": nbytes, "seconds": seconds,
            "what": f"a {rows}x{cols} skin, {n_ticks:.3g} ticks on {', '.join(engines)}"}


@dataclass
class SkinSceneRun(EngineRuns):
    """The result of a taxel-skin scene: one :class:`~cuneate.sim.lif.experiments.SkinResult`
    per engine, engine agreement, what ran and wall times."""

    agreement: dict
    block: dict
    kind: str = "skin"

    @property
    def engines(self) -> list[str]:
        return list(self.results)


def core_keywords(scene) -> dict:
    """The LIF core keywords of the scene (current format, rounding, its population's preset):
    what the engines and a board for the scene share."""
    hw, p = scene["hardware"], scene.populations[0]
    return {"current_format": QFormat(hw["current_int_bits"], hw["current_frac_bits"]),
            "rounding": hw["rounding"], "param_sets": [dict(LIF_PRESETS[p["preset"]])]}


def run(scene, engines: list[str] | None = None, build_dir: Path | None = None,
        progress: bool = False, log=None) -> SkinSceneRun:
    """Run a taxel-skin scene on its engines (or ``engines``)."""
    say = log or (lambda msg: None)
    st, sen, fe, hw = scene["stimulus"], scene["sensor"], scene["frontend"], scene["hardware"]
    rows, cols = sen["grid"]
    names = list(engines or scene.engines)
    for e in names:
        check_engine("lif", e)
    core = core_keywords(scene)
    cfg = engine_config({"update_hz": hw["update_hz"]} | core, rows * cols)
    block = {"block": "lif_core", "neurons": rows * cols, "core_neurons": cfg.n_neurons,
             "param_sets": [scene.populations[0]["preset"]], "current_format": str(cfg.I),
             "dt_ms": cfg.dt_ms, "decay": cfg.decay, "state_format": str(cfg.V)}
    protocol = {"widths_ms": st["press_widths_ms"], "amplitudes": st["press_amplitudes_N"],
                "base_amplitude": st["press_base_amplitude_N"],
                "base_width_ms": st["press_base_width_ms"], "gap_ms": st["press_gap_ms"]}
    t_all = time.perf_counter()
    results, seconds = run_engines(
        names, lambda e, bd: skin_grid(
            e, rows, cols, st["press_taxel"], fe["force_offset_mV"], fe["force_gain_mV_per_N"],
            hw["update_hz"], protocol, tuple(st["press_spread"]), core, build_dir=bd,
            sample_hz=sen["sample_rate_hz"], duration_ms=scene["scene"]["duration_ms"]),
        build_dir, lambda e, r, s: say(f"engine {e}: {int(r.counts.sum())} spikes ({s:.1f} s)"),
        progress)
    timing = {"engines_s": seconds, "engines_wall_s": time.perf_counter() - t_all}
    agreement = engines_agreement({e: results[e].spikes_ms for e in names}, {}, cfg.dt_ms)
    ran = {"stimulus": "press", "effects": [], "effect_counts": {},
           "front_end": ["force"],
           "front_end_detail": [f"force: I = {fe['force_offset_mV']:g} mV + "
                                f"{fe['force_gain_mV_per_N']:g} mV/N x force, sampled at "
                                f"{sen['sample_rate_hz']:g} Hz and held "
                                f"{int(round(hw['update_hz'] / sen['sample_rate_hz']))} "
                                f"tick(s)"],
           "blocks": [block], "engines": names}
    return SkinSceneRun(scene, results, ran, timing, agreement=agreement, block=block)


def summary(run: SkinSceneRun) -> dict:
    """The run as a JSON-ready dictionary (``run.json``)."""
    return {"scene": run.scene.name, "source": run.scene.source, "kind": "skin",
            "grid": run.scene["sensor"]["grid"], "pressed": run.scene["stimulus"]["press_taxel"],
            "engines": {e: r.to_dict() for e, r in run.results.items()},
            "decoded": {e: {"winner": r.winner, "correct": r.pressed_wins}
                        for e, r in run.results.items()}
            if run.scene["decoder"]["kind"] == "winner" else {},
            "agreement": run.agreement, "ran": run.ran, "timing": run.timing,
            "spike_files": run.files.get("spikes", {}),
            "resolved_scene": run.scene.to_dict()}


def format_run(run: SkinSceneRun) -> str:
    """The lines ``cuneate run`` prints for a skin scene."""
    rows, cols = run.scene["sensor"]["grid"]
    out = [f"{run.scene.name}: {rows}x{cols} taxels, pressed taxel "
           f"{run.scene['stimulus']['press_taxel']}, engines {', '.join(run.results)}"]
    for e, r in run.results.items():
        out.append(f"  {e:10s} {int(r.counts.sum()):5d} spikes, winner taxel {r.winner} "
                   f"({'pressed' if r.pressed_wins else 'NOT the pressed one'}), grows with "
                   f"width {r.width_monotonic}, with amplitude {r.amplitude_monotonic}  "
                   f"({run.timing['engines_s'][e]:.1f} s)")
        out.append(f"  {'':10s} row sums {r.row_sums}, column sums {r.col_sums}")
        if "board_cycles" in r.counters:
            out.append(f"  {'':10s} {board_link_line(r.counters)}")
    for k, v in run.agreement.items():
        out.append(f"  {k}: {v['identical_trains']}/{v['neurons']} identical trains, mean "
                   f"|spike count diff| {v['mean_abs_count_diff']:.2f}")
    return "\n".join(out)


def _figures(run: SkinSceneRun, out: Path) -> list[str]:
    plt = pyplot()
    names = []
    first = next(iter(run.results.values()))
    dt = first.dt_ms
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.4))
    t = np.arange(first.force.size) * dt
    ax[0].plot(t, first.force, lw=1)
    ax[0].set(xlabel="time (ms)", ylabel="force (N)", title="force on the pressed taxel")
    for i in range(first.currents.shape[1]):
        ax[1].plot(t, first.currents[:, i], lw=1, label=f"taxel {i}")
    ax[1].set(xlabel="time (ms)", ylabel="current (mV)", title="taxel currents")
    ax[1].legend(fontsize=6, ncol=3)
    fig.tight_layout()
    fig.savefig(out / "press.png", dpi=DPI)
    plt.close(fig)
    names.append("press.png")
    for e, r in run.results.items():
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.6), gridspec_kw={"width_ratios": [1, 2]})
        ax[0].imshow(r.counts, cmap="Reds")
        top = max(1, int(r.counts.max()))
        for (i, j), c in np.ndenumerate(r.counts):
            ax[0].text(j, i, int(c), ha="center", va="center", fontsize=9,
                       color="white" if c > top / 2 else "black")
        ax[0].set(title=f"{e}: spikes per taxel", xticks=range(r.counts.shape[1]),
                  yticks=range(r.counts.shape[0]))
        for i, s in enumerate(r.spikes_ms):
            ax[1].plot(s, np.full(len(s), i), "|", ms=4,
                       color="C3" if i == r.pressed else "C0")
        for p in r.pulses:
            ax[1].axvspan(p["start_ms"], p["start_ms"] + p["width_ms"], color="0.9", zorder=0)
        ax[1].set(xlabel="time (ms)", ylabel="taxel", title=f"spikes: {e} (grey: pulses)")
        fig.tight_layout()
        fig.savefig(out / f"skin_{e}.png", dpi=DPI)
        plt.close(fig)
        names.append(f"skin_{e}.png")
    return names


def write_spike_files(run: SkinSceneRun, out: Path) -> dict:
    """``spikes_<engine>.npz`` per engine (:mod:`cuneate.sim.spikes`): one neuron per taxel,
    its grating the taxel index, the class the pressed taxel; returns ``{engine: file}``."""
    pop = run.scene.populations[0]["name"]
    files = {}
    for e, r in run.results.items():
        n = len(r.spikes_ms)
        steps = r.force.shape[0] if r.force is not None else None
        t_stop = steps * r.dt_ms if steps else max([max(s, default=0.0) for s in r.spikes_ms])
        name = f"spikes_{e}.npz"
        write_spikes(Path(out) / name, r.spikes_ms, e, t_stop, [pop] * n, [0] * n,
                     list(range(n)), [run.scene.classes()[0]] * n, r.dt_ms)
        files[e] = name
    return files


def write_report(run: SkinSceneRun, out: Path) -> Path:
    """Write ``index.html``, ``run.json`` and figures into ``out``; returns the HTML path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    run.files = {"spikes": write_spike_files(run, out)}
    (out / "run.json").write_text(json.dumps(summary(run), indent=2, default=float))
    figs = _figures(run, out)
    rows, cols = run.scene["sensor"]["grid"]
    pressed = run.scene["stimulus"]["press_taxel"]
    eng_rows = [[e, int(r.counts.sum()), r.winner, "yes" if r.pressed_wins else "NO",
                 r.width_monotonic, r.amplitude_monotonic, r.row_sums, r.col_sums,
                 sum(r.clamp_counts.values()) if r.clamp_counts else "-",
                 fmt(run.timing["engines_s"][e], 2)] for e, r in run.results.items()]
    first = next(iter(run.results))
    pulse_rows = [[p["kind"], fmt(p["width_ms"], 1), fmt(p["amplitude"], 2),
                   *[int(run.results[e].pulses[k]["counts"][pressed]) for e in run.results]]
                  for k, p in enumerate(run.results[first].pulses)]
    grids = "".join(f"<h3>{html.escape(e)}</h3>" + html_table(r.counts.tolist(),
                                                          [f"col {j}" for j in range(cols)])
                    for e, r in run.results.items())
    agr_rows = [[k, v["spikes_a"], v["spikes_b"], f"{v['identical_trains']}/{v['neurons']}",
                 fmt_distinct(v["mean_abs_count_diff"]), v["max_abs_count_diff"],
                 fmt_distinct(v["fraction_within_1_tick"])] for k, v in run.agreement.items()]
    b = run.block
    body = f"""
<p>Scene: {html.escape(run.scene.source)}. A {rows}x{cols} taxel skin, one LIF neuron per
taxel; taxel {pressed} (row-major) is pressed.</p>
<h2>Per engine</h2>
{html_table(eng_rows, ["engine", "spikes", "winner", "pressed wins", "grows with width",
                   "grows with amplitude", "row sums", "column sums", "clamps", "run s"])}
<h2>Spikes of the pressed taxel per pulse</h2>
{html_table(pulse_rows, ["pulse", "width ms", "force N", *run.results])}
<h2>Spike counts per taxel</h2>
{grids}
<h2>Engine agreement</h2>
{html_table(agr_rows, ["pair", "spikes A", "spikes B", "identical trains", "mean |count diff|",
                   "max |count diff|", "within 1 tick"])}
<h2>What ran</h2>
<ul><li>stimulus: press</li><li>effects: none (a taxel sensor)</li>
<li>front end: {html.escape('; '.join(run.ran['front_end_detail']))}</li>
<li>blocks: {html.escape(f"{b['block']} ({b['neurons']} neurons on a core of "
                         f"{b['core_neurons']}, preset {', '.join(b['param_sets'])}, current "
                         f"{b['current_format']}, state {b['state_format']}, decay "
                         f"{b['decay']}, dt {b['dt_ms']:g} ms)")}</li>
<li>engines: {html.escape(', '.join(run.engines))}</li>
{''.join(f"<li>{html.escape(e)}: {html.escape(board_link_line(r.counters))}</li>"
         for e, r in run.results.items() if "board_cycles" in r.counters)}</ul>
"""
    return write_page(out, run.scene.name, body + files_html(run.files), figs)
