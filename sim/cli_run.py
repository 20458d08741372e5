"""``cuneate run [SCENE] --out DIR``: run a scene and write its report.

``SCENE`` is a scene file, or the name of a shipped example (``examples/NAME.toml``,
``NAME.toml`` or ``NAME``); without it the embedded default scene (the four-material grasp)
runs. ``--engines`` overrides the scene's engine list; ``--list-examples`` prints the shipped
examples. Prints the accuracy per engine and the report's path.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .cliutil import CliError, output_dir

__all__ = ["register", "cmd_run", "resolve_scene"]


def resolve_scene(arg: str | None):
    from .scenes import SceneError, default_scene, example_path, load_scene
    try:
        if arg is None:
            return default_scene()
        p = Path(arg)
        if p.is_file():
            return load_scene(p)
        ex = example_path(arg)
        if ex is not None:
            return load_scene(ex)
        raise CliError(f"cuneate run: scene {arg!r}: no such file or shipped example "
                       f"(see cuneate run --list-examples)")
    except SceneError as exc:
        raise CliError(f"cuneate run: {exc}") from None


def cmd_run(args) -> int:
    from .scenes import ENGINE_NAMES, example_names
    if args.list_examples:
        for n in example_names():
            print(f"examples/{n}")
        return 0
    scene = resolve_scene(args.scene)
    engines = None
    if args.engines:
        engines = [e.strip() for e in args.engines.split(",") if e.strip()]
        for e in engines:
            if e not in ENGINE_NAMES:
                raise CliError(f"cuneate run: --engines: unknown engine {e!r} (known: "
                               f"{', '.join(ENGINE_NAMES)})")
    out = output_dir(args.out)
    from .report import summary_dict, write_report
    from .scene_run import run_scene
    from .transport import TransportError
    from .driver import GapError
    from .traces import TraceError
    log = (lambda m: print(m, file=sys.stderr)) if args.verbose else None
    try:
        run = run_scene(scene, engines, build_dir=out / "build",
                        progress=sys.stderr.isatty(), log=log)
    except (TraceError, GapError, TransportError) as exc:
        raise CliError(f"cuneate run: {exc}") from None
    except ValueError as exc:
        raise CliError(f"cuneate run: {scene.source}: {exc}") from None
    kind = getattr(run, "kind", None)
    if kind in ("ridge", "skin"):
        # scenes of their own kind: their report, summary and printout
        from . import scene_ridge, scene_skin
        write, summary, fmt = {
            "ridge": (scene_ridge.write_ridge_report, scene_ridge.ridge_summary,
                      scene_ridge.format_ridge_run),
            "skin": (scene_skin.write_skin_report, scene_skin.skin_summary,
                     scene_skin.format_skin_run)}[kind]
        page = write(run, out)
        if args.json:
            print(json.dumps(summary(run), default=float))
            return 0
        print(fmt(run))
        print(f"report: {page}")
        return 0
    page = write_report(run, out)
    if args.json:
        print(json.dumps(summary_dict(run), default=float))
        return 0
    print(f"{scene.name}: {len(run.trial_class)} trials, {len(run.neurons)} neurons, "
          f"engines {', '.join(run.spikes)}")
    for e, t in run.timing["engines_s"].items():
        d = run.decoded.get(e)
        acc = "-" if d is None else (f"{100 * d.accuracy:.1f} %" if d.accuracy is not None
                                     else d.reason)
        print(f"  {e:10s} accuracy {acc:>8s}  ({t:.1f} s)")
    for k, v in run.decode_agreement.items():
        print(f"  accuracy {k}: differs by {100 * v['difference']:.1f} points (tolerance "
              f"{100 * v['tolerance']:.1f}): {'within' if v['within'] else 'OUTSIDE'}")
    s = run.saturations
    for e, sp in run.spikes.items():
        if not any(len(x) for x in sp):
            print(f"  warning: {e}: no neuron spiked (currents peak at "
                  f"{s['max_mV_per_ms']:.2f} mV/ms; an RS neuron needs about 3.8)")
    n_sat = s.get("format_low", 0) + s.get("format_high", 0)
    if n_sat:
        print(f"  warning: {n_sat} of {s['values']} currents saturated to {s['format']} "
              f"(range {s['min_mV_per_ms']:.1f} .. {s['max_mV_per_ms']:.1f} mV/ms)")
    for k, v in run.agreement.items():
        print(f"  {k}: {v['identical_trains']}/{v['neurons']} identical trains, mean "
              f"|spike count diff| {v['mean_abs_count_diff']:.2f}")
    print(f"report: {page}")
    return 0


def register(groups) -> None:
    p = groups.root.add_parser("run", help="run a scene (default: the four-material grasp) "
                                           "and write its report")
    p.add_argument("scene", nargs="?", default=None,
                   help="scene file or shipped example name (default: embedded grasp scene)")
    p.add_argument("--out", default="out/run", help="report directory (default out/run)")
    p.add_argument("--engines", default=None,
                   help="comma-separated engines overriding the scene's run.engines")
    p.add_argument("--list-examples", action="store_true", help="list the shipped scenes")
    p.add_argument("--json", action="store_true", help="print the run summary as JSON")
    p.add_argument("-v", "--verbose", action="store_true", help="log each stage")
    p.set_defaults(func=cmd_run)
