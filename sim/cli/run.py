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

from .options import CliError, CommandGroups, add_max_minutes, output_dir

__all__ = ["register", "cmd_run", "resolve_scene"]


def resolve_scene(arg: str | None):
    from ..scenes.scene import SceneError, default_scene, example_path, load_scene
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
    from ..engines.registry import UnknownEngine, check_engine
    from ..scenes.registry import KINDS, kind_module
    from ..scenes.scene import example_names
    if args.list_examples:
        for n in example_names():
            print(f"examples/{n}")
        return 0
    scene = resolve_scene(args.scene)
    engines = None
    if args.engines:
        engines = [e.strip() for e in args.engines.split(",") if e.strip()]
        for e in engines:
            try:
                check_engine(KINDS[scene.kind].block, e)
            except UnknownEngine as exc:
                raise CliError(f"cuneate run: --engines: {exc}") from None
    out = output_dir(args.out)
    from ..host.driver import GapError
    from ..host.traces import TraceError
    from ..host.transport import TransportError
    from ..scenes.runner import run_scene
    log = (lambda m: print(m, file=sys.stderr)) if args.verbose else None
    try:
        run = run_scene(scene, engines, build_dir=out / "build",
                        progress=sys.stderr.isatty(), log=log)
    except (TraceError, GapError, TransportError) as exc:
        raise CliError(f"cuneate run: {exc}") from None
    except ValueError as exc:
        raise CliError(f"cuneate run: {scene.source}: {exc}") from None
    kind = kind_module(run.kind)
    page = kind.write_report(run, out)
    if args.json:
        print(json.dumps(kind.summary(run), default=float))
        return 0
    print(kind.format_run(run))
    print(f"report: {page}")
    return 0


def register(groups: CommandGroups) -> None:
    p = groups.root.add_parser("run", help="run a scene (default: the four-material grasp) "
                                           "and write its report")
    p.add_argument("scene", nargs="?", default=None,
                   help="scene file or shipped example name (default: embedded grasp scene)")
    p.add_argument("--out", default="out/run", help="report directory (default out/run)")
    p.add_argument("--engines", default=None,
                   help="comma-separated engines overriding the scene's run.engines")
    p.add_argument("--list-examples", action="store_true", help="list the shipped scenes")
    p.add_argument("--json", action="store_true", help="print the run summary as JSON")
    add_max_minutes(p, 60.0)
    p.add_argument("-v", "--verbose", action="store_true", help="log each stage")
    p.set_defaults(func=cmd_run)
