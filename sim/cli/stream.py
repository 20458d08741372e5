"""``cuneate stream BOARD --port PORT [SCENE]``: run an afferent scene on a programmed board.

The scene runs as ``cuneate run --engines fixed,board`` does, with one difference: the
``board`` engine's transport talks to the board on ``PORT`` (a serial device such as
``/dev/ttyUSB0``, or any pyserial URL) instead of the board top in Verilator. The driver path is
the same (the host front end, :class:`~cuneate.sim.host.uart.UartTransport` in lockstep, every
counter of the transport contract checked), and so is the report (``--out``): spikes per engine,
the board's counters, frames and bytes each way and wall time (``line_*``), and the board's
agreement with the bit-exact twin (``board vs fixed``). A board that is not programmed with the
scene's core (its neurons, parameter sets and current format) disagrees with the twin.

``SCENE`` is resolved as ``cuneate run`` resolves it (a file, a shipped example, the default
scene); a fan-out scene (``hardware.fanout``) streams its channels; a scene with a cuneate
layer gets both populations back; a scene whose board holds only some of its trials
(``hardware.board_trials``) is played in turn (:mod:`cuneate.sim.scenes.in_turn`). Refused in
one line (exit 2): an unknown board, a scene that is not an afferent scene or does not fit the
board (its sizing: cycles per sweep, block RAM, multipliers, the link's 65 536 neuron ids; a
fan-out or layered scene's as ``cuneate build`` sizes it), no ``--port`` or a port that cannot
be opened, and any loss on the link. Exit 1 when the board's spike trains (afferent or
cuneate) differ from the twin's.
"""

from __future__ import annotations

import json
import sys

from ...hdl.lib.config import ConfigError
from .options import (CliError, CommandGroups, add_max_minutes, add_quiet_option, output_dir,
                      positive_float, positive_int, start_progress)
from .run import resolve_scene

__all__ = ["register", "cmd_stream"]

COMMAND = "cuneate stream"


def _board(name: str) -> dict:
    from ...boards.targets import TARGETS
    if name not in TARGETS:
        raise CliError(f"{COMMAND}: unknown board {name!r}; known: {', '.join(TARGETS)}")
    return TARGETS[name]


def _check_fits(target: dict, scene, cfg, baud: int | None) -> dict:
    """The board's sizing of the scene's core (:func:`cuneate.boards.sizing.size_core`), or
    of its fan-out core or its network (a cuneate layer) as ``cuneate build`` sizes them, at
    the line rate ``baud`` (``None``: the board's), or a one-line refusal naming the limit the
    scene exceeds."""
    from ...boards.sizing import size_core
    try:
        if scene["hardware"]["fanout"] or any(p["model"] == "cuneate"
                                              for p in scene.populations):
            from ...boards.build import size_blocks
            from ...boards.scene import scene_request
            return size_blocks(target, scene_request(scene, target, real_time=False, baud=baud),
                               None, cfg.pipeline_stages, baud)
        return size_core(target, n_neurons=cfg.n_neurons, update_hz=cfg.update_hz,
                         pipeline_stages=cfg.pipeline_stages, baud=baud)
    except ConfigError as exc:
        raise CliError(f"{COMMAND}: {scene.source}: its core of {cfg.n_neurons} neurons at "
                       f"{cfg.update_hz:g} Hz does not fit the board: {exc}") from None


def _board_lines(args, run, baud: int) -> list[str]:
    """What the board did: its spikes and contract counters, the line's frames and bytes each
    way, wall time, and its agreement with the twin."""
    from ..host.transport import COUNTERS
    c = run.counters["board"]
    agree = run.agreement["board vs fixed"]
    return [
        f"board {args.board} on {c['line_port']} ({baud} baud): {c['spikes']} spikes; "
        + ", ".join(f"{k} {c[k]}" for k in COUNTERS),
        f"  line: {c['line_frames_to_device']} frames ({c['line_bytes_to_device']} bytes) to "
        f"the board, {c['line_frames_from_device']} frames ({c['line_bytes_from_device']} "
        f"bytes) from it; {c['line_wall_s']:.2f} s",
        f"  board vs fixed: {agree['identical_trains']}/{agree['neurons']} identical trains "
        f"({agree['spikes_a']} and {agree['spikes_b']} spikes)"]


def cmd_stream(args) -> int:
    from ..host.driver import GapError
    from ..host.traces import TraceError
    from ..host.transport import TransportError
    from ..host.uart import UartTransport
    from ..scenes import afferent
    from ..scenes.runner import check_budget
    target = _board(args.board)
    if not args.port:
        raise CliError(f"{COMMAND}: name the board's serial port: --port PORT (a device such "
                       f"as /dev/ttyUSB0, or a pyserial URL)")
    scene = resolve_scene(args.scene, COMMAND)
    if scene.kind != "afferent":
        raise CliError(f"{COMMAND}: {scene.source} is a {scene.kind} scene; a board streams "
                       f"afferent scenes (FBG traces into Izhikevich afferents)")
    on_board, trials = scene["hardware"]["board_trials"], afferent.n_driven(scene)[0]
    # a board holding some of the trials plays them in turn, as many at a time as it holds
    in_turn = on_board if on_board is not None and on_board < trials else None
    try:
        cfg = afferent.core_config(scene, in_turn)
    except ValueError as exc:
        raise CliError(f"{COMMAND}: {scene.source}: {exc}") from None
    sized = _check_fits(target, scene, cfg, args.baud)
    # the line rate of the plan the build chooses for this scene (a 70 MHz ULX3S build runs
    # its line at 2 Mbaud), or the one given
    baud = int(args.baud or sized["plan"]["baud"])
    board_baud = int(target["clock_plan"].baud)
    if args.baud and baud != board_baud:
        print(f"{COMMAND}: note: the line at {baud} baud, not the {args.board}'s default "
              f"{board_baud}: the board must be built for it (cuneate build {args.board} "
              f"--baud {baud})", file=sys.stderr)
    out = output_dir(args.out)
    check_budget(scene, ["fixed"])          # the board runs at the line's pace
    try:
        port = UartTransport.open_port(args.port, baud)
    except TransportError as exc:
        raise CliError(f"{COMMAND}: {str(exc).removeprefix('uart: ')}") from None
    start_progress(args)
    options = {"board": {"port": port, "baud": baud, "timeout_s": args.timeout_s}}
    try:
        run = afferent.run(scene, ["fixed", "board"], build_dir=out / "build",
                           engine_options=options, in_turn=in_turn)
    except (TraceError, GapError, TransportError) as exc:
        raise CliError(f"{COMMAND}: {exc}") from None
    except ValueError as exc:
        raise CliError(f"{COMMAND}: {scene.source}: {exc}") from None
    finally:
        port.close()
    page = afferent.write_report(run, out)
    differ = [k for k, a in run.agreement.items()      # the afferents and a cuneate layer
              if k.endswith("board vs fixed") and a["identical_trains"] != a["neurons"]]
    same = not differ
    if args.json:
        print(json.dumps(afferent.summary(run), default=float))
    else:
        print(afferent.format_run(run))
        print("\n".join(_board_lines(args, run, baud)))
        print(f"report: {page}")
    if not same:
        a = run.agreement[differ[0]]
        print(f"{COMMAND}: the board's spike trains differ from the bit-exact twin's "
              f"({differ[0]}: {a['identical_trains']}/{a['neurons']} identical): is it "
              f"programmed with this scene's blocks?", file=sys.stderr)
        return 1
    return 0


def register(groups: CommandGroups) -> None:
    p = groups.root.add_parser("stream", help="run an afferent scene on a programmed board "
                                              "through its serial port")
    p.add_argument("board", help="board target (see cuneate boards)")
    p.add_argument("scene", nargs="?", default=None,
                   help="scene file or shipped example name (default: embedded grasp scene)")
    p.add_argument("--port", default=None,
                   help="the board's serial port: a device (/dev/ttyUSB0) or a pyserial URL")
    p.add_argument("--baud", type=positive_int, default=None,
                   help="line rate (default: the board's, 3000000 on the ulx3s; a board built "
                        "with cuneate build --baud B runs B)")
    p.add_argument("--timeout-s", type=positive_float, default=5.0,
                   help="how long the host waits for the board before naming what it lost")
    p.add_argument("--out", default="out/stream",
                   help="report directory (index.html, run.json, figures, spike files)")
    p.add_argument("--json", action="store_true", help="print the run summary as JSON")
    add_quiet_option(p)
    add_max_minutes(p, 60.0)
    p.set_defaults(func=cmd_stream)
