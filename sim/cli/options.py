"""Shared pieces of the ``cuneate`` command line: the one-line error, argument types, paths,
and the run-time limit every simulation command applies.

Every command family lives in its own module (``cuneate.sim.cli.<command>`` or
``cuneate.sim.<block>.cli``) with a ``register(groups)`` function; :mod:`cuneate.sim.cli`
assembles them. A user error raises :class:`CliError` (one line
on stderr, exit status 2); nothing else should reach the user as a traceback.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path

__all__ = ["CliError", "Parser", "CommandGroups", "finite_float", "positive_float",
           "positive_int", "nonneg_int", "output_dir", "input_file", "refuse_long_run",
           "fmt_time", "engine_choices", "add_run_options", "add_generate_options",
           "run_ticks", "print_run", "clamp_summary", "build_config", "add_rate_options",
           "add_block_commands"]


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (no usage dump)."""

    def error(self, message):
        raise CliError(f"{self.prog}: {message}")


@dataclass
class CommandGroups:
    """Where command modules add their parsers.

    ``root`` holds top-level commands (``cuneate NAME``); ``simulate`` and ``generate`` hold one
    sub-command per hardware block (``cuneate simulate izhikevich``, ``cuneate generate lif``).
    """

    root: argparse._SubParsersAction
    simulate: argparse._SubParsersAction
    generate: argparse._SubParsersAction


def finite_float(text: str) -> float:
    try:
        val = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(val):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return val


def positive_float(text: str) -> float:
    val = finite_float(text)
    if val <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0: {text!r}")
    return val


def _int(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        try:
            val = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if not (math.isfinite(val) and val == int(val)):
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        return int(val)


def positive_int(text: str) -> int:
    val = _int(text)
    if val < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1: {text!r}")
    return val


def nonneg_int(text: str) -> int:
    val = _int(text)
    if val < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0: {text!r}")
    return val


def output_dir(path: str | Path, what: str = "--out") -> Path:
    """Create ``path`` as a directory (and parents) or refuse in one line."""
    p = Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"{what} {str(p)!r}: cannot create directory: "
                       f"{exc.strerror or exc}") from None
    if not p.is_dir():
        raise CliError(f"{what} {str(p)!r} is not a directory")
    probe = p / ".cuneate-write-test"
    try:
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise CliError(f"{what} {str(p)!r}: not writable: {exc.strerror or exc}") from None
    return p


def input_file(path: str | Path, what: str) -> Path:
    """``path`` as an existing readable file, or a one-line refusal."""
    p = Path(path)
    if not p.exists():
        raise CliError(f"{what} {str(p)!r}: no such file")
    if not p.is_file():
        raise CliError(f"{what} {str(p)!r} is not a file")
    try:
        with p.open("rb"):
            pass
    except OSError as exc:
        raise CliError(f"{what} {str(p)!r}: cannot read: {exc.strerror or exc}") from None
    return p


def engine_choices(block: str) -> tuple[str, ...]:
    """The engines ``block`` supports (the registry's list, for ``--engine``)."""
    from ..engines.registry import block_engines
    return block_engines(block)


def fmt_time(s: float) -> str:
    """A duration for people: seconds, minutes, hours or days."""
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    if s < 2 * 86400:
        return f"{s / 3600:.1f} h"
    return f"{s / 86400:.0f} days"


def refuse_long_run(command: str, block: str, engine: str, work: float, max_minutes: float,
                    what: str = "") -> float:
    """Refuse (one line) a run of ``work`` (the block's unit: updates, or cycles on an HDL
    simulator) that the engine registry estimates to take longer than ``max_minutes``;
    returns the estimate in seconds."""
    from ..engines.registry import BLOCKS, estimate_seconds
    secs = estimate_seconds(block, engine, work)
    if secs > max_minutes * 60:
        unit = BLOCKS[block].unit
        limit = BLOCKS[block].speed[engine] * max_minutes * 60
        raise CliError(f"{command}: {what or 'the run'} is too long for the {engine} engine "
                       f"(about {work:.3g} {unit}, ~{fmt_time(secs)}; limit {limit:.0e} "
                       f"{unit} = --max-minutes {max_minutes:g}); shorten --duration-ms")
    return secs


def add_run_options(p, max_minutes: bool = True) -> None:
    """The options every ``simulate`` command shares: ``--build-dir``, ``--max-minutes`` and
    ``--json``."""
    p.add_argument("--build-dir", default=None, help="HDL simulator build directory")
    if max_minutes:
        p.add_argument("--max-minutes", type=positive_float, default=10.0,
                       help="refuse runs estimated to take longer (default 10)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")


def add_generate_options(g) -> None:
    """The options every ``generate`` command shares: ``--tick-source`` and ``--out``."""
    g.add_argument("--tick-source", choices=("internal", "external"), default="internal",
                   help="internal divider (default) or the tick input")
    g.add_argument("--out", required=True, help="output directory")


def run_ticks(command: str, block: str, args, dt_ms: float, cycles: float, updates: float,
              unit: str = "tick") -> int:
    """The ticks of ``args.duration_ms`` at ``dt_ms``, refused in one line when shorter than
    one tick or estimated longer than ``args.max_minutes`` on ``args.engine`` (``cycles`` per
    tick on an HDL simulator, ``updates`` per tick otherwise)."""
    from ..engines.registry import ENGINES
    n = int(round(args.duration_ms / dt_ms))
    if n < 1:
        raise CliError(f"--duration-ms {args.duration_ms:g} is shorter than one {unit} "
                       f"(dt = {dt_ms:g} ms)")
    per_tick = cycles if ENGINES[args.engine].hdl else updates
    refuse_long_run(command, block, args.engine, n * per_tick, args.max_minutes,
                    f"{n} {unit}s")
    return n


def clamp_summary(run, engine: str):
    """The ``saturation`` entry of a ``simulate --json`` result (``None`` for golden)."""
    return None if engine == "golden" else {"counts": run.clamp_counts,
                                            "sticky": run.clamp_sticky}


def print_run(args, out: dict, header: str, rows) -> None:
    """A ``simulate`` result: ``out`` as JSON with ``--json``, else ``header`` and one line per
    ``(label, spike times)`` row with the first six times."""
    import json
    if args.json:
        print(json.dumps(out))
        return
    print(header)
    for label, s in rows:
        head = ", ".join(f"{t:g}" for t in s[:6]) + (" ..." if len(s) > 6 else "")
        print(f"  {label}, {len(s)} spikes: {head}")


def build_config(cls, kwargs: dict, what: str = ""):
    """``cls(**kwargs)``, or the one-line refusal every command gives for a configuration the
    block cannot hold (``ConfigError``; ``what`` names the block for other errors)."""
    from ...hdl.lib.config import ConfigError
    try:
        return cls(**kwargs)
    except ConfigError as exc:
        raise CliError(f"cuneate: {exc}") from None
    except (TypeError, ValueError) as exc:
        if not what:
            raise
        raise CliError(f"cuneate: {what} refused: {exc}") from None


def add_rate_options(g, clock_default: float | None, clock_help: str = "") -> None:
    """``--clock-hz`` and ``--update-hz`` (the per-neuron update rate: dt = 1000/update_hz
    ms), in a block's option group."""
    g.add_argument("--clock-hz", type=positive_float, default=clock_default,
                   help=clock_help or f"core clock (default {clock_default:g})")
    g.add_argument("--update-hz", type=positive_float, default=16e3,
                   help="per-neuron update rate; dt = 1000/update_hz ms (default 16e3)")


def add_block_commands(groups, block: str, help: str, duration_ms: float, options=None,
                       simulate=None, generate=None, module: str | None = None,
                       resources_s: int | None = None):
    """``cuneate simulate BLOCK`` (``--engine`` from the engine registry, ``--duration-ms``
    and the run options) and ``cuneate generate BLOCK`` (the generate options, ``--name``
    when the block names its ``module``, ``--resources`` when it offers synthesis figures);
    ``options(parser)`` adds the block's own options to both, ``simulate``/``generate`` are
    the commands. Returns both parsers for more options."""
    s = groups.simulate.add_parser(block, help=help)
    engines = engine_choices(block)
    s.add_argument("--engine", choices=engines, default="golden",
                   help=f"{', '.join(engines)} (default golden)")
    s.add_argument("--duration-ms", type=positive_float, default=duration_ms,
                   help=f"biological time in ms (default {duration_ms:g})")
    add_run_options(s)
    g = groups.generate.add_parser(block, help=help)
    add_generate_options(g)
    if module:
        g.add_argument("--name", default=module, help=f"Verilog module name (default {module})")
    if resources_s:
        g.add_argument("--resources", action="store_true",
                       help=f"also run yosys synth_ecp5 and synth_xilinx -family xc6s "
                            f"(~{resources_s} s)")
    for p, func in ((s, simulate), (g, generate)):
        if options is not None:
            options(p)
        if func is not None:
            p.set_defaults(func=func)
    return s, g
