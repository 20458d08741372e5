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


def _output(t: dict) -> str:
    if t.get("bitstream"):
        return "bitstream"
    if t.get("zynq"):
        return "Vivado IP + block design + estimate"
    return "Vivado project + estimate" if t.get("vivado") else "Verilog + estimate"


def board_rows() -> list[dict]:
    """One row per board and pipeline depth where the depths' limits differ (one row where
    they do not): bounds and the largest build in neurons at the board's update rate."""
    from ...boards.sizing import limits
    from ...boards.targets import TARGETS
    rows = []
    for name, t in TARGETS.items():
        plans = [p.clock_hz / 1e6 for p, _ in t.get("clock_plans", [])] or \
            [t["clock_plan"].clock_hz / 1e6]
        per_depth = {d: limits(t, d) for d in (PIPELINE_STAGES[0], PIPELINE_STAGES[-1])}
        depths = list(per_depth)
        if per_depth[depths[0]] == per_depth[depths[-1]]:
            depths = [depths]
        else:
            depths = [[d] for d in depths]
        for ds in depths:
            lim = per_depth[ds[0]]
            rows.append({
                "name": name, "device": t["device"], "output": _output(t),
                "description": t["description"], "bitstream": bool(t.get("bitstream")),
                "depths": ds, "plans_mhz": plans, "update_khz": lim["update_hz"] / 1e3,
                "uart": t.get("uart", "USB-serial"), "default_neurons": t["default_neurons"],
                "bram_bound": lim["bram"], "multiplier_bound": lim["multiplier"],
                "logic_fmax_bound": lim["fmax"], "fmax_mhz": lim["fmax_mhz"],
                "largest": lim.get("largest"), "largest_cores": lim.get("cores"),
                "largest_per_core": lim.get("per_core"),
                "largest_clock_mhz": lim["clock_hz"] / 1e6 if lim.get("clock_hz") else None,
                "largest_bram": (lim.get("estimate") or {}).get("BRAM"),
                "resources": t["resources"]})
    return rows


_COLUMNS = [("board", lambda r: r["name"]), ("device", lambda r: r["device"]),
            ("output", lambda r: r["output"]),
            ("PLL plans (MHz)", lambda r: ", ".join(f"{c:g}" for c in r["plans_mhz"])),
            ("depth", lambda r: " or ".join(str(d) for d in r["depths"])),
            ("block-RAM bound (neurons)", lambda r: _n(r["bram_bound"])),
            ("multiplier bound (neurons)", lambda r: _n(r["multiplier_bound"])),
            ("logic x fmax bound (neurons)",
             lambda r: "-" if r["logic_fmax_bound"] is None else
             f"{_n(r['logic_fmax_bound'])} (at {r['fmax_mhz']:.4g} MHz)"),
            ("largest build (neurons)",
             lambda r: "-" if r["largest"] is None else
             f"{_n(r['largest'])} ({r['largest_cores']} x {_n(r['largest_per_core'])} at "
             f"{r['largest_clock_mhz']:g} MHz, {r['largest_bram']} block RAMs)"),
            ("default (neurons)", lambda r: _n(r["default_neurons"]))]


def _n(v) -> str:
    return "-" if v is None else f"{v:,}".replace(",", " ")


def format_board_table(rows: list[dict], markdown: bool = False) -> str:
    """The limit table: neurons at 16 kHz per board (and depth where depths differ)."""
    head = [h for h, _ in _COLUMNS]
    body = [[f(r) for _, f in _COLUMNS] for r in rows]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += ["| " + " | ".join(f"`{c}`" if i == 0 else c for i, c in enumerate(row))
                  + " |" for row in body]
        return "\n".join(lines) + "\n"
    widths = [max(len(x) for x in col) for col in zip(head, *body)]
    fmt = "  ".join(f"{{:{w}s}}" for w in widths)
    upd = {r["update_khz"] for r in rows}
    note = (f"neurons at {', '.join(f'{u:g}' for u in sorted(upd))} kHz updates; bounds: every "
            f"block-RAM bit at the best shapes' packing, every multiplier block at the fastest "
            f"plan's cycles per sweep, as many cores as the logic holds at the measured fmax")
    return "\n".join([fmt.format(*head)] + [fmt.format(*row) for row in body] + [note]) + "\n"


def cmd_boards(args) -> int:
    rows = board_rows()
    if args.json:
        print(json.dumps(rows, indent=2, default=str))
    else:
        print(format_board_table(rows, markdown=args.markdown), end="")
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
    b.add_argument("--markdown", action="store_true", help="the table as Markdown "
                                                            "(docs/boards.md)")
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
