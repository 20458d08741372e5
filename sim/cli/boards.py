"""``cuneate boards`` (list the targets and their limits) and ``cuneate build BOARD``."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

from ...hdl.izhikevich.config import PIPELINE_STAGES
from ...hdl.lib.config import ConfigError
from ..izhikevich.cli import add_pipeline_option
from .options import (CliError, CommandGroups, add_quiet_option, claim_output, output_dir,
                      positive_float, positive_int, start_progress)

__all__ = ["register"]


def cmd_boards(args) -> int:
    from ...boards.sizing import limits
    from ...boards.targets import TARGETS
    rows = []
    for name, t in TARGETS.items():
        plan = t["clock_plan"]
        per_depth = {d: limits(t, d) for d in (PIPELINE_STAGES[0], PIPELINE_STAGES[-1])}
        rows.append({"name": name, "device": t["device"], "description": t["description"],
                     "bitstream": bool(t.get("bitstream")), "clock_mhz": plan.clock_hz / 1e6,
                     "plans_mhz": [p.clock_hz / 1e6 for p, _ in t.get("clock_plans", [])]
                     or [plan.clock_hz / 1e6],
                     "update_khz": plan.update_hz / 1e3, "baud": plan.baud,
                     "max_neurons_one_core": plan.cycles_per_tick - 16,
                     "largest": {str(d): lim for d, lim in per_depth.items()},
                     "default_neurons": t["default_neurons"], "resources": t["resources"]})
    if args.json:
        print(json.dumps(rows, indent=2, default=str))
    else:
        for r in rows:
            print(f"{r['name']:11s} {r['device']:20s} "
                  f"{'bitstream' if r['bitstream'] else 'Verilog + estimate'}, PLL plans "
                  f"{', '.join(f'{c:g}' for c in r['plans_mhz'])} MHz, "
                  f"{r['update_khz']:g} kHz updates")
            for d, lim in r["largest"].items():
                tight = min(x for x in (lim["bram"], lim["multiplier"], lim["fmax"]) if x)
                print(f"{'':11s} depth {d}: largest {lim['largest']} neurons "
                      f"({lim['cores']} x {lim['per_core']} at {lim['clock_hz'] / 1e6:g} MHz, "
                      f"{lim['estimate']['BRAM']} block RAMs); bounds in neurons: block RAM "
                      f"{lim['bram']}, multipliers {lim['multiplier']}"
                      + (f", logic at the measured fmax of {lim['fmax_mhz']:.1f} MHz "
                         f"{lim['fmax']}" if lim["fmax"] else "")
                      + f" ({100 * lim['largest'] / tight:.0f} % of the tightest)")
    return 0


def cmd_build(args) -> int:
    from ...boards.build import BuildError, build_target
    from ...boards.targets import TARGETS
    if args.board_option is not None:
        if args.board is not None and args.board != args.board_option and args.scene is None:
            args.board, args.scene = args.board_option, args.board    # --board B SCENE
        if args.board is not None and args.board != args.board_option:
            raise CliError(f"cuneate build: two boards given ({args.board!r} and --board "
                           f"{args.board_option!r})")
        args.board = args.board_option
    if args.board is None:
        raise CliError(f"cuneate build: name a board (cuneate build BOARD, or --board BOARD); "
                       f"known: {', '.join(TARGETS)}")
    start_progress(args)
    if args.board not in TARGETS:
        raise CliError(f"cuneate build: unknown board {args.board!r}; known: "
                       f"{', '.join(TARGETS)}")
    scene = None
    if args.scene is not None:
        from .run import resolve_scene
        if args.neurons is not None or args.update_hz is not None:
            raise CliError("cuneate build: a scene sets the neurons and the update rate; give "
                           "either SCENE or --neurons/--update-hz")
        scene = resolve_scene(args.scene, "cuneate build")
    out = output_dir(args.out)
    try:
        with claim_output(out, "cuneate build"):
            report = build_target(args.board, out, n_neurons=args.neurons,
                                  clock_hz=args.clock_hz, update_hz=args.update_hz,
                                  bitstream=not args.no_bitstream, seed=args.seed,
                                  pipeline_stages=args.pipeline_stages, scene=scene,
                                  baud=args.baud,
                                  pack_registers=not args.no_pack_registers)
    except ConfigError as exc:
        raise CliError(f"cuneate build: {exc}") from None
    except BuildError as exc:
        print(f"cuneate build: {exc}")
        return 1
    from ...boards.build import format_report
    print(json.dumps(report, indent=2) if args.json else format_report(report), end="")
    pr = report.get("place_route")
    return 0 if pr is None or pr["timing_met"] else 1


def cmd_program(args) -> int:
    from ...boards.targets import TARGETS
    t = TARGETS.get(args.board)
    if t is None or not t.get("loader_board"):
        known = ", ".join(k for k, v in TARGETS.items() if v.get("loader_board"))
        raise CliError(f"cuneate program: no bitstream flow for {args.board!r}; "
                       f"programmable: {known}")
    bit = Path(args.bitstream)
    if not bit.is_file():
        raise CliError(f"cuneate program: bitstream {str(bit)!r} not found (run cuneate build "
                       f"{args.board} first)")
    loader = shutil.which("openFPGALoader")
    if loader is None:
        raise CliError("cuneate program: openFPGALoader is not installed (apt install "
                       "openfpgaloader, or program the bitstream with your own tool)")
    r = subprocess.run([loader, "-b", t["loader_board"], str(bit)], capture_output=True,
                       text=True)
    if r.returncode != 0:
        last = (r.stderr or r.stdout).strip().splitlines()[-1:] or ["no output"]
        raise CliError(f"cuneate program: no {args.board} board programmed "
                       f"(openFPGALoader: {last[0]})")
    print(f"programmed {args.board} with {bit}")
    return 0


def register(groups: CommandGroups) -> None:
    p = groups.root.add_parser("program", help="load a bitstream with openFPGALoader")
    p.add_argument("board")
    p.add_argument("bitstream")
    p.set_defaults(func=cmd_program)

    b = groups.root.add_parser("boards", help="list the board targets and their limits")
    b.add_argument("--json", action="store_true")
    b.set_defaults(func=cmd_boards)

    c = groups.root.add_parser("build", help="Verilog, bitstream and resource/timing report "
                                             "for a board")
    c.add_argument("board", nargs="?", default=None, help="target name (see cuneate boards)")
    c.add_argument("scene", nargs="?", default=None,
                   help="a scene (file or shipped example): the board holds its blocks, sized "
                        "to it, and the report gives the link's budget for it")
    c.add_argument("--board", dest="board_option", default=None, metavar="BOARD",
                   help="the same as the positional BOARD")
    add_quiet_option(c)
    c.add_argument("--neurons", type=positive_int, default=None)
    c.add_argument("--clock-hz", type=positive_float, default=None,
                   help="core clock (must be one of the board's PLL plans)")
    c.add_argument("--update-hz", type=positive_float, default=None,
                   help="neuron update rate (default the board's, 16 kHz)")
    c.add_argument("--baud", type=positive_int, default=None,
                   help="UART line rate (default the chosen clock plan's: 3000000 on the ULX3S at "
                        "60 and 90 MHz, 2000000 at 70 MHz); the clock must divide it within "
                        "1 %% (115200 on the ULX3S at 60 MHz: 521 clocks a bit)")
    c.add_argument("--out", required=True)
    c.add_argument("--seed", type=positive_int, default=1, help="nextpnr placement seed")
    add_pipeline_option(c)
    c.add_argument("--no-bitstream", action="store_true",
                   help="Verilog and estimate only (no place and route)")
    c.add_argument("--no-pack-registers", action="store_true",
                   help="ECP5: leave the multipliers' and block RAMs' registers in the fabric "
                        "(by default they move into the MULT18X18D and DP16KD between yosys "
                        "and nextpnr)")
    c.add_argument("--json", action="store_true")
    c.set_defaults(func=cmd_build)
