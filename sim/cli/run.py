"""``cuneate run [SCENE] --out DIR``: run a scene and write its report.

``SCENE`` is a scene file, or the name of a shipped example (``examples/NAME.toml``,
``NAME.toml`` or ``NAME``); without it the embedded default scene (the four-material grasp)
runs. ``--engines`` overrides the scene's engine list; ``--list-examples`` prints the shipped
scenes with what each asks (the default marked). ``--waves DIR`` dumps the RTL engines'
waveforms (a window of ticks). Prints the decoding per engine and the report's path; the
report directory also holds one spike file per engine (``spikes_<engine>.npz``).
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

from ..engines.registry import UnknownEngine, check_engine
from .options import (CliError, CommandGroups, add_max_minutes, add_quiet_option, add_waves_options,
                      claim_output, engine_list, output_dir, start_progress, waves_from_args)

__all__ = ["register", "cmd_run", "resolve_scene"]


def resolve_scene(arg: str | None, command: str = "cuneate run"):
    """The scene ``arg`` names (a file or a shipped example; the default scene for None);
    :class:`CliError` in one line, prefixed with ``command``, otherwise."""
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
        raise CliError(f"{command}: scene {arg!r}: no such file or shipped example "
                       f"(see cuneate run --list-examples)")
    except SceneError as exc:
        raise CliError(f"{command}: {exc}") from None


def _description(text: str) -> str:
    """A scene's ``scene.description``, or its leading comment, as one line."""
    import tomllib                  # not at `cuneate --help` (measured 6 ms)
    try:
        desc = tomllib.loads(text).get("scene", {}).get("description", "")
    except tomllib.TOMLDecodeError:
        desc = ""
    if not desc:
        lead = []
        for line in text.splitlines():
            if not line.startswith("#"):
                break
            lead.append(line.lstrip("# ").strip())
        desc = " ".join(lead)
    return " ".join(desc.split())


def list_examples() -> list[str]:
    """The lines of ``--list-examples``: the default scene (marked) and every shipped one,
    each with its name and description."""
    from ..scenes.scene import (DEFAULT_SCENE_TOML, default_scene, example_names, example_path,
                                load_scene)

    def wrap(text):
        return textwrap.wrap(text, 96, initial_indent="    ", subsequent_indent="    ")
    lines = [f"(default: run without SCENE) {default_scene().name}",
             *wrap(_description(DEFAULT_SCENE_TOML))]
    for n in example_names():
        p = example_path(n)
        lines += [f"examples/{n}: {load_scene(p).name}", *wrap(_description(p.read_text()))]
    return lines


def cmd_run(args) -> int:
    from ..scenes.registry import KINDS, kind_module
    if args.list_examples:
        print("\n".join(list_examples()))
        return 0
    scene = resolve_scene(args.scene)
    engines = None
    if args.engines is not None:
        engines = engine_list(args.engines, "cuneate run: --engines")
        for e in engines:
            try:
                check_engine(KINDS[scene.kind].block, e)
            except UnknownEngine as exc:
                raise CliError(f"cuneate run: --engines: {exc}") from None
    out = output_dir(args.out)
    waves = waves_from_args(args)
    if waves is None and scene["run"]["waves"]:
        from ..engines.waves import Waves
        r = scene["run"]
        waves = Waves(output_dir(out / r["waves"], "run.waves"), r["waves_start_tick"],
                      r["waves_ticks"])
    if waves is not None and scene.kind not in ("afferent", "texture"):
        raise CliError(f"cuneate run: --waves: waveforms are written for afferent and texture "
                       f"scenes (the Izhikevich core); {scene.source} is a {scene.kind} scene")
    in_turn = None
    if args.in_turn:
        k = scene["hardware"]["board_trials"] if scene.kind in ("afferent", "texture") \
            else None
        if k is None:
            raise CliError(f"cuneate run: --in-turn: {scene.source} names no "
                           f"hardware.board_trials (the trials a board holds at a time)")
        in_turn = k
    from ..host.driver import GapError
    from ..host.traces import TraceError
    from ..host.transport import TransportError
    from ..scenes.runner import run_scene
    start_progress(args)
    with claim_output(out, "cuneate run"):
        try:
            run = run_scene(scene, engines, build_dir=out / "build", waves=waves,
                            in_turn=in_turn)
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
    p.add_argument("--out", default="out/run",
                   help="report directory (index.html, run.json, figures, spike files)")
    p.add_argument("--engines", default=None,
                   help="comma-separated engines overriding the scene's run.engines")
    p.add_argument("--list-examples", action="store_true",
                   help="list the shipped scenes with their descriptions (default marked)")
    p.add_argument("--json", action="store_true", help="print the run summary as JSON")
    p.add_argument("--in-turn", action="store_true",
                   help="play the trials as a board built for the scene does: "
                        "hardware.board_trials at a time, group after group")
    add_waves_options(p)
    add_quiet_option(p)
    p.add_argument("-v", "--verbose", action="store_true",
                   help="in a terminal, also print the end of each stage above the bars")
    add_max_minutes(p, 60.0)
    p.set_defaults(func=cmd_run)
