"""``cuneate hardcases summary``: the hard-case suite's record (:mod:`cuneate.sim.hardcases`)."""

from __future__ import annotations

from .options import CliError, CommandGroups

__all__ = ["register", "cmd_hardcases"]


def cmd_hardcases(args) -> int:
    from ..hardcases import format_summary, summary
    try:
        rows = summary(args.dir)
    except FileNotFoundError as exc:
        raise CliError(f"cuneate hardcases: {exc}") from None
    print(format_summary(rows))
    return 1 if any(r["mismatches"] for r in rows) else 0


def register(groups: CommandGroups) -> None:
    h = groups.root.add_parser("hardcases", help="the hard-case suite's record")
    hs = h.add_subparsers(dest="hardcases_command", required=True, parser_class=type(h))
    s = hs.add_parser("summary", help="cases tried, updates checked and mismatches per case")
    s.add_argument("--dir", default=None, help="records (default build/hardcases)")
    s.set_defaults(func=cmd_hardcases)
