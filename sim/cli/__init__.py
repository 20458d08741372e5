"""The ``cuneate`` command line.

General commands live in this package, one module each: ``doctor`` and ``filter``
(:mod:`.doctor`), ``demo`` (:mod:`.demo`), ``run`` (:mod:`.run`), ``sweep`` (:mod:`.sweep`),
``prove`` (:mod:`.prove`), ``hardcases`` (:mod:`.hardcases`), ``boards``/``build``/``program``
(:mod:`.boards`). Each block adds its own commands from ``cuneate.sim.<block>.cli``
(``simulate BLOCK``, ``generate BLOCK`` and block experiments). Every command module has a
``register(groups)`` function. Bad arguments exit with status 2 and a one-line reason on
stderr; a failed check exits 1.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import sys

from .options import CliError, CommandGroups, Parser, add_quiet_option

__all__ = ["main", "build_parser", "COMMAND_MODULES", "CliError", "block_command_modules"]

#: General command modules of this package, in the order ``cuneate --help`` lists them.
COMMAND_MODULES = ["doctor", "demo", "run", "sweep", "prove", "hardcases", "boards"]


def block_command_modules() -> list[str]:
    """``cuneate.sim.<block>.cli`` of every block that has one (found, not listed)."""
    root = importlib.import_module(__package__.rsplit(".", 1)[0])
    out = []
    for info in pkgutil.iter_modules(root.__path__):
        name = f"{root.__name__}.{info.name}.cli"
        if info.ispkg and info.name != "cli" and importlib.util.find_spec(name) is not None:
            out.append(name)
    return out


def version() -> str:
    """The installed cuneate version."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version("cuneate")
    except PackageNotFoundError:             # pragma: no cover - running from a plain checkout
        return "unknown"


def build_parser() -> Parser:
    p = Parser(prog="cuneate", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"cuneate {version()}")
    add_quiet_option(p, root=True)
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    s = sub.add_parser("simulate", help="simulate a hardware block on an engine")
    s_models = s.add_subparsers(dest="model", required=True, parser_class=Parser,
                                metavar="BLOCK")
    g = sub.add_parser("generate", help="generate Verilog and a JSON description of a block")
    g_models = g.add_subparsers(dest="block", required=True, parser_class=Parser,
                                metavar="BLOCK")
    groups = CommandGroups(root=sub, simulate=s_models, generate=g_models)
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__package__}.{name}").register(groups)
    for name in block_command_modules():
        importlib.import_module(name).register(groups)
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
    finally:
        from .. import progress
        progress.configure("quiet")      # the library is quiet again once a command is over


if __name__ == "__main__":
    sys.exit(main())
