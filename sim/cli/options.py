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
           "fmt_time", "engine_choices"]


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
