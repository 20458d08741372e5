"""``cuneate doctor`` (the toolchain) and ``cuneate filter check`` (an FBG filter's stability)."""

from __future__ import annotations

import json

from .options import CliError, CommandGroups, finite_float

__all__ = ["register", "cmd_doctor", "cmd_filter_check"]


def cmd_doctor(args) -> int:
    from ..engines.toolchain import doctor, doctor_ok, format_doctor
    statuses = doctor()
    ok = doctor_ok(statuses)
    if args.json:
        print(json.dumps({"ok": ok, "tools": {s.name: s.to_dict() for s in statuses}}, indent=2))
    else:
        print(format_doctor(statuses))
    return 0 if ok else 1


def cmd_filter_check(args) -> int:
    from ...golden.fbg import filter_check_report
    try:
        report = filter_check_report(args.b, args.a)
    except ValueError as exc:
        raise CliError(f"cuneate filter check: {exc}") from None
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        print(report.to_text())
    if not report.stable:       # a bad filter is bad input: exit 2, one line naming it
        raise CliError(f"cuneate filter check: the filter b = "
                       f"[{', '.join(f'{x:g}' for x in report.b)}], a = "
                       f"[{', '.join(f'{x:g}' for x in report.a)}] is unstable: "
                       f"{report.message}")
    return 0


def register(groups: CommandGroups) -> None:
    d = groups.root.add_parser("doctor", help="check the toolchain (exit 0 when usable)")
    d.add_argument("--json", action="store_true", help="print a JSON object")
    d.set_defaults(func=cmd_doctor)
    f = groups.root.add_parser("filter", help="FBG pre-processing filters")
    fsub = f.add_subparsers(dest="filter_command", required=True, parser_class=type(f))
    fc = fsub.add_parser("check", help="print poles, radii and the stability verdict")
    fc.add_argument("--b", type=finite_float, nargs="+", required=True)
    fc.add_argument("--a", type=finite_float, nargs="+", required=True)
    fc.add_argument("--json", action="store_true")
    fc.set_defaults(func=cmd_filter_check)
