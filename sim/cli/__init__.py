"""The ``cuneate`` command line.

General commands live in this package, one module each: ``doctor`` and ``filter``
(:mod:`.doctor`), ``demo`` (:mod:`.demo`), ``run`` (:mod:`.run`), ``sweep`` (:mod:`.sweep`),
``prove`` (:mod:`.prove`), ``hardcases`` (:mod:`.hardcases`), ``boards``/``build``/``program``
(:mod:`.boards`), ``stream`` (:mod:`.stream`). Each block adds its own commands from
``cuneate.sim.<block>.cli`` (``simulate BLOCK``, ``generate BLOCK`` and block experiments).
Every command module has a ``register(groups)`` function.

Exit status and the one error path (:func:`main`):

* 0: done; 1: a check failed (the run's own verdict, e.g. a proof or an engine mismatch);
* 2: refused: bad arguments, a bad scene or trace file, a configuration the hardware cannot hold,
  a run estimated to exhaust memory or exceed ``--max-minutes`` (:mod:`cuneate.golden.budget`),
  a divergence of a golden model, a loss on a transport, a tool that refuses a user-given name:
  one line on stderr naming the input;
* 2 also: what the environment refused - a file or folder that cannot be written or read (disk
  full, no permission, a name too long), memory exhausted: one line naming the path or the
  resource (:func:`~cuneate.sim.cli.options.environment_failure`);
* 3: an unanticipated error: one line and "run with --debug for the traceback" (``--debug``,
  anywhere on the command line, or ``CUNEATE_DEBUG=1``, shows it);
* a closed stdout (``cuneate run --list-examples | head -1``) is not an error: exit 0, the rest
  of the output dropped;
* 130: interrupted.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import pkgutil
import sys
import warnings
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as dist_version

from ...golden import budget
from .options import (CliError, CommandGroups, Parser, add_quiet_option, anticipated,
                      environment_failure, one_line)

__all__ = ["main", "build_parser", "COMMAND_MODULES", "CliError", "block_command_modules"]

#: General command modules of this package, in the order ``cuneate --help`` lists them.
COMMAND_MODULES = ["doctor", "demo", "run", "sweep", "prove", "hardcases", "boards",
                   "stream"]


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
    try:
        return dist_version("cuneate")
    except PackageNotFoundError:             # pragma: no cover - running from a plain checkout
        return "unknown"


def build_parser() -> Parser:
    p = Parser(prog="cuneate", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"cuneate {version()}")
    add_quiet_option(p, root=True)
    p.add_argument("--debug", action="store_true",
                   help="show the traceback of an unexpected error (accepted anywhere on the "
                        "command line)")
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


def _split_debug(argv) -> tuple[list[str], bool]:
    """``argv`` without ``--debug`` (anywhere before a ``--``), and whether it was there."""
    argv = list(argv)
    end = argv.index("--") if "--" in argv else len(argv)
    debug = "--debug" in argv[:end]
    return [a for i, a in enumerate(argv) if not (i < end and a == "--debug")], debug


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    if issubclass(category, ResourceWarning):     # about the program, not the input: not shown
        return
    print(f"cuneate: warning: {one_line(str(message))}", file=sys.stderr)


def _command(args) -> str:
    """``cuneate`` and the (sub)command words of ``args`` (``cuneate lif quantization``)."""
    words = ["cuneate"]
    if args is not None:
        for attr in ("command", "model", "block", "lif_command", "coincidence_command",
                     "filter_command", "hardcases_command"):
            if isinstance(getattr(args, attr, None), str):
                words.append(getattr(args, attr))
    return " ".join(words)


def _close_stdout() -> None:
    """Point stdout at /dev/null (after a reader closed it), so flushing at exit cannot fail."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


#: options whose value is an output place (left out of the command a file records)
_OUTPUT_OPTIONS = ("--out", "--build-dir", "--work-dir", "--waves", "--spikes")


def command_line(argv) -> str:
    """``argv`` as the command a generated file records: ``cuneate`` and the arguments, without
    the output places' options and with input files by their name only (no paths: the same
    command gives the same bytes wherever it runs)."""
    from pathlib import Path
    words, skip = ["cuneate"], False
    for a in argv:
        if skip:
            skip = False
            continue
        if a in _OUTPUT_OPTIONS:
            skip = True
            continue
        if a.split("=", 1)[0] in _OUTPUT_OPTIONS:
            continue
        try:
            is_file = len(a) < 4096 and Path(a).is_file()
        except OSError:
            is_file = False
        words.append(Path(a).name if is_file else a)
    return " ".join(words)


def main(argv=None) -> int:
    """Run one command; see the module docstring for the exit status."""
    argv, debug = _split_debug(sys.argv[1:] if argv is None else argv)
    debug = debug or os.environ.get("CUNEATE_DEBUG", "") not in ("", "0")
    args = None
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            args = build_parser().parse_args(argv)
            minutes = None if getattr(args, "force", False) else getattr(args, "max_minutes",
                                                                         None)
            from ...hdl.flow.verilog import made_by
            # the command's time limit; a memory limit set around main (tests) stays
            with budget.limited(max_minutes=minutes, memory_bytes=budget.limits().memory_bytes), \
                    made_by(command_line(argv)):
                return args.func(args)
        except CliError as exc:
            msg = one_line(str(exc))
            print(msg if msg.startswith("cuneate") else f"cuneate: {msg}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            return 130
        except BrokenPipeError:
            # the reader closed stdout (``cuneate run --list-examples | head -1``): not an
            # error; what is left unwritten goes nowhere (also at the interpreter's exit)
            _close_stdout()
            return 0
        except Exception as exc:
            command = _command(args)
            env = environment_failure(exc)
            if env is not None and not debug:
                print(f"{command}: {env}", file=sys.stderr)
                return 2
            if anticipated(exc) and not debug:
                print(f"{command}: {one_line(str(exc))}", file=sys.stderr)
                return 2
            if debug:
                import traceback
                traceback.print_exc()
            else:
                print(f"{command}: internal error: {type(exc).__name__}: "
                      f"{one_line(str(exc)) or 'no message'} (run with --debug for the "
                      f"traceback)", file=sys.stderr)
            return 3
        finally:
            from .. import progress
            progress.configure("quiet")      # the library is quiet again once a command is over


if __name__ == "__main__":
    sys.exit(main())
