"""The ``cuneate`` command line.

Commands: ``doctor``, ``simulate BLOCK``, ``generate BLOCK``, ``filter check``, ``demo``, and
those registered by the command modules listed in :data:`COMMAND_MODULES` (each a ``cli_*.py``
module of this package with a ``register(groups)`` function). Bad arguments exit with status 2
and a one-line reason on stderr; a failed check exits 1.
"""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

from .cliutil import CliError, CommandGroups, Parser, finite_float

__all__ = ["main", "build_parser", "COMMAND_MODULES", "CliError"]

#: Command modules of this package; each adds its parsers through ``register(groups)``.
COMMAND_MODULES = [
    "cli_izhikevich",
    "cli_run",
    "cli_lif",
    "cli_boards",
    "cli_cuneate",
]


# --------------------------------------------------------------------------------------------
# doctor
def cmd_doctor(args) -> int:
    from .toolchain import doctor, doctor_ok, format_doctor
    statuses = doctor()
    ok = doctor_ok(statuses)
    if args.json:
        print(json.dumps({"ok": ok, "tools": {s.name: s.to_dict() for s in statuses}}, indent=2))
    else:
        print(format_doctor(statuses))
    return 0 if ok else 1


# --------------------------------------------------------------------------------------------
# filter check
def cmd_filter_check(args) -> int:
    from ..golden.fbg import filter_check_report
    try:
        report = filter_check_report(args.b, args.a)
    except ValueError as exc:
        raise CliError(f"cuneate filter check: {exc}") from None
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        print(report.to_text())
    return 0 if report.stable else 1


# --------------------------------------------------------------------------------------------
# demo
def cmd_demo(args) -> int:
    from .cliutil import output_dir
    from .demo import run_demo
    return run_demo(output_dir(args.out))


def build_parser() -> Parser:
    p = Parser(prog="cuneate", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

    d = sub.add_parser("doctor", help="check the toolchain (exit 0 when usable)")
    d.add_argument("--json", action="store_true", help="print a JSON object")
    d.set_defaults(func=cmd_doctor)

    s = sub.add_parser("simulate", help="simulate a hardware block on an engine")
    s_models = s.add_subparsers(dest="model", required=True, parser_class=Parser,
                                metavar="BLOCK")
    g = sub.add_parser("generate", help="generate Verilog and a JSON description of a block")
    g_models = g.add_subparsers(dest="block", required=True, parser_class=Parser,
                                metavar="BLOCK")

    f = sub.add_parser("filter", help="FBG pre-processing filters")
    fsub = f.add_subparsers(dest="filter_command", required=True, parser_class=Parser)
    fc = fsub.add_parser("check", help="print poles, radii and the stability verdict")
    fc.add_argument("--b", type=finite_float, nargs="+", required=True)
    fc.add_argument("--a", type=finite_float, nargs="+", required=True)
    fc.add_argument("--json", action="store_true")
    fc.set_defaults(func=cmd_filter_check)

    dm = sub.add_parser("demo", help="generate the hardware and print a golden-model summary")
    dm.add_argument("--out", default="out/demo")
    dm.set_defaults(func=cmd_demo)

    groups = CommandGroups(root=sub, simulate=s_models, generate=g_models)
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__package__}.{name}").register(groups)
    return p


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except CliError as exc:
        msg = str(exc)
        print(msg if msg.startswith("cuneate") else f"cuneate: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
