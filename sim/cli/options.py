"""Shared pieces of the ``cuneate`` command line: the one-line error, argument types, paths,
and the run-time limit every simulation command applies.

Every command family lives in its own module (``cuneate.sim.cli.<command>`` or
``cuneate.sim.<block>.cli``) with a ``register(groups)`` function; :mod:`cuneate.sim.cli`
assembles them. A user error raises :class:`CliError` (one line
on stderr, exit status 2); nothing else should reach the user as a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import re
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ...golden import budget
from ...golden.budget import fmt_count, fmt_time
from ...hdl.lib.config import ConfigError
from ..engines.registry import BLOCKS, ENGINES, block_engines, estimate_seconds
from ..engines.waves import DEFAULT_TICKS, Waves

__all__ = ["CliError", "Parser", "one_line", "anticipated", "ANTICIPATED", "environment_failure",
           "engine_list", "claim_output", "LOCK_NAME", "INCOMPLETE_NAME", "CommandGroups",
           "finite_float", "positive_float", "positive_int", "nonneg_int", "seed_int",
           "probability", "verilog_name", "output_dir", "input_file", "run_budget",
           "check_estimate", "fmt_time", "engine_choices", "EngineChoices",
           "add_run_options", "add_max_minutes", "add_generate_options",
           "run_ticks", "print_run", "clamp_summary", "build_config", "add_rate_options",
           "add_block_commands", "HelpFormatter", "add_quiet_option", "start_progress",
           "add_waves_options", "waves_from_args", "add_spikes_option", "write_simulate_spikes"]


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


#: The errors every command maps to exit status 2 and one line (module -> class names): what
#: bad input, a configuration the hardware cannot hold, a run over budget, a diverging golden
#: model, a loss on a transport or a refusing tool raise. Their messages name the input; where
#: a command knows more (the scene file, the option) it says so itself.
ANTICIPATED = {
    "golden.budget": ("BudgetError",),
    "golden.izhikevich": ("DivergenceError",),
    "golden.lif": ("LIFDivergenceError",),
    "golden.fbg": ("UnstableFilterError",),
    "hdl.izhikevich.range": ("RangeSearchError",),
    "hdl.lib.config": ("ConfigError",),
    "hdl.izhikevich.formal": ("FormalError",),
    "sim.scenes.schema": ("SceneError",),
    "sim.host.traces": ("TraceError",),
    "sim.host.transport": ("TransportError",),
    "sim.host.driver": ("GapError",),
    "sim.engines.registry": ("UnknownEngine",),
    "hdl.flow.tools": ("ToolError",),
    "boards.build": ("BuildError",),
}


def anticipated(exc: BaseException) -> bool:
    """True for the errors of :data:`ANTICIPATED` (of modules already loaded: an error of a
    module never imported cannot have been raised) and for undecodable text input."""
    if isinstance(exc, UnicodeDecodeError):
        return True
    root = __package__.split(".")[0]
    for mod, names in ANTICIPATED.items():
        m = sys.modules.get(f"{root}.{mod}")
        if m is not None and isinstance(exc, tuple(getattr(m, n) for n in names)):
            return True
    return False


def engine_list(text: str, where: str) -> list[str]:
    """A comma-separated engine list as names, refused in one line (``where`` names the option)
    when it names none (``''``, ``',,,'``) or one twice (``fixed,fixed``)."""
    names = [e.strip() for e in text.split(",")]
    if not all(names):
        raise CliError(f"{where}: {text!r} names an empty engine; give engine names separated "
                       f"by commas")
    twice = sorted({e for e in names if names.count(e) > 1})
    if twice:
        raise CliError(f"{where}: {text!r} names {twice[0]} twice")
    return names


def environment_failure(exc: BaseException) -> str | None:
    """One line for what the environment refused, or None: an :class:`OSError` naming a file
    (disk full, no permission, a read-only file system, a name too long, a file where a
    folder should be ...) says what failed on which path; a :class:`MemoryError` says that
    memory ran out and how much this process may still use."""
    if isinstance(exc, MemoryError):
        detail = f" ({one_line(str(exc), 160)})" if str(exc) else ""
        return (f"out of memory{detail}: this process can get about "
                f"{budget.fmt_bytes(budget.available_memory())} more; free memory or ask for less")
    if isinstance(exc, OSError) and getattr(exc, "filename", None) is not None:
        what = exc.strerror or type(exc).__name__
        name = str(exc.filename)
        name = name if len(name) <= 120 else name[:117] + "..."
        other = f" -> {exc.filename2!r}" if getattr(exc, "filename2", None) else ""
        return f"{what}: {name!r}{other}"
    return None


def one_line(text: str, limit: int = 600) -> str:
    """``text`` on one line (line breaks and runs of blanks become one space), at most
    ``limit`` characters."""
    out = " ".join(str(text).split())
    return out if len(out) <= limit else out[:limit - 3] + "..."


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Help with every option's default, unless its help already states it or it has none
    worth stating (``None``, a flag's ``False``)."""

    def _get_help_string(self, action):
        text = action.help or ""
        d = action.default
        if "default" in text.lower() or d is None or d is False or d is argparse.SUPPRESS:
            return text
        return super()._get_help_string(action)


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (no usage dump), whose help states the
    defaults, and which reads every argument that starts with ``-`` and a digit or a point
    (``-5``, ``-1e3``, ``-1,2``, ``-.5;3``) as a value, never as an option."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message):
        raise CliError(f"{self.prog}: {message}")

    def parse_known_args(self, args=None, namespace=None):
        """argparse's parse, then the arguments it left over that are no option given to the
        optional positionals (``nargs="?"``, no type or choices) it left empty, in order:
        argparse settles a required and an optional positional together when only the first
        comes before an option (``cuneate stream BOARD --port PORT SCENE``) and would refuse
        the second."""
        ns, extras = super().parse_known_args(args, namespace)
        for action in self._actions:
            if not extras or extras[0].startswith("-"):
                break
            if (not action.option_strings and action.nargs == "?" and action.type is None
                    and action.choices is None
                    and getattr(ns, action.dest, None) == action.default):
                setattr(ns, action.dest, extras.pop(0))
        return ns, extras


def add_quiet_option(p, root: bool = False) -> None:
    """``-q/--quiet``: no progress bars or progress lines (on the command or, with ``root``,
    before it: ``cuneate -q run``)."""
    p.add_argument("-q", "--quiet", action="store_true",
                   default=False if root else argparse.SUPPRESS,
                   help="no progress bars or progress lines on stderr")


def start_progress(args, verbose: bool = False) -> str:
    """Show what the command does (:mod:`cuneate.sim.progress`): bars in a terminal,
    timestamped lines otherwise, nothing with ``-q``; returns the mode."""
    from .. import progress
    if getattr(args, "quiet", False):
        return progress.configure("quiet")
    return progress.configure("auto", verbose=verbose or getattr(args, "verbose", False))


def add_waves_options(p) -> None:
    """``--waves DIR`` and its window (``--waves-start``, ``--waves-ticks``)."""
    p.add_argument("--waves", default=None, metavar="DIR",
                   help="write the RTL engines' waveforms (amaranth: VCD, icarus: FST, "
                        "verilator: VCD) and GTKWave save files into DIR")
    p.add_argument("--waves-start", type=nonneg_int, default=0, metavar="TICK",
                   help="first tick (sweep) of the waveform window")
    p.add_argument("--waves-ticks", type=positive_int, default=DEFAULT_TICKS, metavar="N",
                   help="ticks in the waveform window (a long run does not write gigabytes)")


def waves_from_args(args, relative_to: Path | None = None):
    """The :class:`~cuneate.sim.engines.waves.Waves` window of ``--waves``, or ``None``."""
    if not getattr(args, "waves", None):
        return None
    d = output_dir(args.waves, "--waves")
    return Waves(d, args.waves_start, args.waves_ticks)


def add_spikes_option(p) -> None:
    """``--spikes FILE``: the spikes in the spike-file format (:mod:`cuneate.sim.spikes`)."""
    p.add_argument("--spikes", default=None, metavar="FILE.npz",
                   help="also write the spikes as a spike file (NPZ; cuneate.sim.spikes)")


def write_simulate_spikes(args, trains, block: str, t_stop_ms: float, dt_ms: float | None,
                          populations=None) -> None:
    """``--spikes``: write a ``simulate`` command's trains (one neuron per train, population
    ``block`` unless ``populations`` names each) and say where."""
    if not getattr(args, "spikes", None):
        return
    from ..spikes import write_spikes
    path = Path(args.spikes)
    try:
        write_spikes(path, trains, args.engine, t_stop_ms,
                     populations or [block] * len(trains), dt_ms=dt_ms)
    except OSError as exc:
        raise CliError(f"--spikes {str(path)!r}: cannot write: {exc.strerror or exc}") from None


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


def seed_int(text: str) -> int:
    """A random seed: an integer in 0 .. 2**32 - 1 (what every generator here accepts)."""
    val = nonneg_int(text)
    if val > 2**32 - 1:
        raise argparse.ArgumentTypeError(f"a seed must be at most 2**32 - 1 = {2**32 - 1}: "
                                         f"{text!r}")
    return val


def probability(text: str) -> float:
    """A probability: a finite number in [0, 1]."""
    val = finite_float(text)
    if not 0.0 <= val <= 1.0:
        raise argparse.ArgumentTypeError(f"a probability must be in [0, 1]: {text!r}")
    return val


def verilog_name(text: str) -> str:
    """A Verilog module name (a simple identifier: a letter or ``_``, then letters, digits,
    ``_`` or ``$``; at most 1024 characters), else one line naming it."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_$]{0,1023}", text):
        raise argparse.ArgumentTypeError(f"not a Verilog module name: {text!r} (a letter or _, "
                                         f"then letters, digits, _ or $)")
    return text


def output_dir(path: str | Path, what: str = "--out") -> Path:
    """Create ``path`` as a directory (and parents) or refuse in one line (an empty name is
    refused: it would write into the current directory)."""
    if not str(path).strip():
        raise CliError(f"{what}: empty directory name (give a directory, e.g. {what} out)")
    p = Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"{what} {str(p)!r}: cannot create directory: "
                       f"{exc.strerror or exc}") from None
    if not p.is_dir():
        raise CliError(f"{what} {str(p)!r} is not a directory")
    probe = p / f".cuneate-write-test-{os.getpid()}"    # one a process: runs may share p
    try:
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise CliError(f"{what} {str(p)!r}: not writable: {exc.strerror or exc}") from None
    return p


#: the lock a run holds on its output folder, and the mark a run leaves until it has finished
LOCK_NAME, INCOMPLETE_NAME = ".cuneate-lock", "INCOMPLETE"


@contextlib.contextmanager
def claim_output(out: Path, command: str, what: str = "--out"):
    """Hold the folder ``out`` for one run: a second run into it while this one works is refused
    in one line naming the first (an advisory lock, ``fcntl.flock`` on ``out/.cuneate-lock``:
    released when the process ends, however it ends), and ``out/INCOMPLETE`` says that a run
    is writing; it is removed when the run finishes and stays, saying how the run stopped,
    when it fails: a report folder never silently mixes two runs, and partial output is
    marked."""
    import fcntl
    import sys
    import time
    out = Path(out)
    fd = os.open(out / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        holder = os.read(fd, 400).decode("utf-8", "replace").strip() or "another process"
        os.close(fd)
        raise CliError(f"{command}: {what} {str(out)!r} is in use by another run ({holder}); "
                       f"wait for it to finish or choose another folder") from None
    started = time.strftime("%Y-%m-%d %H:%M:%S")
    argv = " ".join(["cuneate", *sys.argv[1:]]) if sys.argv and sys.argv[0] else command
    os.ftruncate(fd, 0)
    os.write(fd, f"pid {os.getpid()}, since {started}: {one_line(argv, 200)}\n".encode())
    marker = out / INCOMPLETE_NAME
    marker.write_text(f"{command} started {started} (pid {os.getpid()}) is writing here; until "
                      f"this file is gone the folder may hold partial output.\n")
    try:
        yield out
    except BaseException as exc:
        reason = "interrupted" if isinstance(exc, KeyboardInterrupt) else \
            f"stopped by {type(exc).__name__}: {one_line(str(exc), 300)}"
        marker.write_text(f"{command} started {started} (pid {os.getpid()}) did not finish "
                          f"({reason}); the files here are partial or from an earlier run.\n")
        raise
    else:
        marker.unlink(missing_ok=True)
    finally:
        os.close(fd)


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


class EngineChoices(Sequence):
    """The engines ``block`` supports (the registry's list; ``hdl``: its RTL engines alone), as
    an option's choices: asked of the registry when first used (parsing, a command's help),
    not when the parser is built, so that ``cuneate --help`` loads no engine (measured 40 ms
    of 800). The option takes a ``metavar`` (argparse would list the choices as it is
    added) and its help names them with ``%(choices)s``."""

    def __init__(self, block: str, hdl: bool = False):
        self.block, self.hdl = block, hdl

    def _names(self) -> tuple[str, ...]:
        return tuple(e for e in block_engines(self.block) if not self.hdl or ENGINES[e].hdl)

    def __getitem__(self, i):
        return self._names()[i]

    def __len__(self) -> int:
        return len(self._names())


def engine_choices(block: str, hdl: bool = False) -> EngineChoices:
    """The engines ``block`` supports (the registry's list, for ``--engine``)."""
    return EngineChoices(block, hdl)


def run_budget(command: str, block: str, engine: str, work: float, nbytes: float = 0.0,
               what: str = "", hint: str = "shorten --duration-ms") -> dict:
    """Refuse (one line) a run of ``work`` (the block's unit: updates, or cycles on an HDL
    simulator) that the engine registry estimates to take longer than the time limit in force
    (``--max-minutes``), or whose ``nbytes`` exceed the memory this machine can give
    (:func:`cuneate.golden.budget.check`); returns the estimate."""
    secs = estimate_seconds(block, engine, work)
    unit = BLOCKS[block].unit
    try:
        return budget.check(f"{what or 'the run'} on the {engine} engine (about {work:.3g} "
                            f"{unit})", budget.BASE_BYTES + nbytes, secs, hint)
    except budget.BudgetError as exc:
        raise CliError(f"{command}: {exc}") from None


def check_estimate(command: str, est: dict, hint: str = "") -> dict:
    """An estimate ``{"what", "bytes", "seconds"}`` checked against the limits in force
    (:func:`cuneate.golden.budget.check`), refused as a one-line :class:`CliError`."""
    try:
        return budget.check(est["what"], est["bytes"], est["seconds"], hint)
    except budget.BudgetError as exc:
        raise CliError(f"{command}: {exc}") from None


def add_run_options(p, max_minutes: bool = True) -> None:
    """The options every ``simulate`` command shares: ``--build-dir``, ``--max-minutes`` and
    ``--json``."""
    p.add_argument("--build-dir", default=None, help="HDL simulator build directory")
    if max_minutes:
        add_max_minutes(p, 10.0)
    p.add_argument("--json", action="store_true", help="print the result as JSON")


def add_max_minutes(p, default: float) -> None:
    """``--max-minutes``: the time limit the command line sets for the command
    (:func:`cuneate.golden.budget.limited`); runs estimated to take longer are refused."""
    p.add_argument("--max-minutes", type=positive_float, default=default,
                   help=f"refuse work estimated to take longer (default {default:g})")


def add_generate_options(g) -> None:
    """The options every ``generate`` command shares: ``--tick-source`` and ``--out``."""
    g.add_argument("--tick-source", choices=("internal", "external"), default="internal",
                   help="internal divider (default) or the tick input")
    g.add_argument("--out", required=True, help="output directory")


def add_face_option(g) -> None:
    """``--face``: the block behind one of its faces (:data:`cuneate.hdl.axi.faces.FACES`)."""
    from ...hdl.axi.faces import FACES
    g.add_argument("--face", choices=("none",) + tuple(FACES), default="none",
                   help="none (default): the block alone; " + "; ".join(
                       f"{k}: {v}" for k, v in FACES.items()) + " (standard port names, the "
                   "register map in the header and in NAME.regmap.json/.md)")


def generate_faced(args, config, block: str, **spec_options) -> int:
    """``cuneate generate BLOCK --face F``: the block of ``config`` behind face ``F`` in
    ``--out`` (module ``<name>_<face>``, ``<name>`` the block's ``--name`` or ``block``);
    prints the files and the face's figures, one line each."""
    from ...hdl.axi.faces import write_face
    from ...hdl.lib.config import ConfigError
    name = f"{getattr(args, 'name', None) or block}_{args.face}"
    try:
        res = write_face(output_dir(args.out), config, args.face, name, **spec_options)
    except ConfigError as exc:
        raise CliError(f"cuneate generate {block} --face {args.face}: {exc}") from None
    for f in res["files"]:
        print(f)
    d = res["description"]
    line = (f"{d['payload']['block']} behind the {args.face} face: {d['face_summary']}; "
            f"{d['payload']['n_written']} values written, {d['payload']['n_spike_ids']} "
            f"spike ids")
    if "cycles_per_sweep" in d:
        line += (f"; a sweep takes {d['cycles_per_sweep']} cycles behind it, the divider "
                 f"{d['cycles_per_tick']}" + ("" if d["free_running_fits"] else
                                               f" (free running at {d['update_hz']:g} Hz "
                                               f"needs a clock of "
                                               f"{d['cycles_per_sweep'] * d['update_hz'] / 1e6:g}"
                                               f" MHz, or TICK_DIVIDER >= "
                                               f"{d['cycles_per_sweep']})"))
    print(line)
    return 0


def run_ticks(command: str, block: str, args, dt_ms: float, cycles: float, updates: float,
              unit: str = "tick", bytes_per_tick: float = 0.0) -> int:
    """The ticks of ``args.duration_ms`` at ``dt_ms``, refused in one line when shorter than
    one tick, or estimated to take longer than ``args.max_minutes`` on ``args.engine``
    (``cycles`` per tick on an HDL simulator, ``updates`` per tick otherwise) or to hold more
    memory (``bytes_per_tick``) than the machine can give."""
    n = int(round(args.duration_ms / dt_ms))
    if n < 1:
        raise CliError(f"--duration-ms {args.duration_ms:g} is shorter than one {unit} "
                       f"(dt = {dt_ms:g} ms)")
    per_tick = cycles if ENGINES[args.engine].hdl else updates
    run_budget(command, block, args.engine, float(n) * per_tick, float(n) * bytes_per_tick,
               f"{fmt_count(n)} {unit}s")
    return n


def clamp_summary(run, engine: str):
    """The ``saturation`` entry of a ``simulate --json`` result (``None`` for golden)."""
    return None if engine == "golden" else {"counts": run.clamp_counts,
                                            "sticky": run.clamp_sticky}


def print_run(args, out: dict, header: str, rows) -> None:
    """A ``simulate`` result: ``out`` as JSON with ``--json``, else ``header`` and one line per
    ``(label, spike times)`` row with the first six times; with ``--spikes`` also the spike
    file (population: ``out["populations"]`` when it names them, else the block)."""
    trains = out["spikes_ms"]
    pops = None
    for pop in out.get("populations", []):
        pops = (pops or [out["model"]] * len(trains))
        pops[pop["first"]:pop["first"] + pop["count"]] = [pop["name"]] * pop["count"]
    write_simulate_spikes(args, trains, out["model"], out["duration_ms"], out.get("dt_ms"),
                          pops)
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
                       resources_s: int | None = None, faces: bool = False):
    """``cuneate simulate BLOCK`` (``--engine`` from the engine registry, ``--duration-ms``
    and the run options) and ``cuneate generate BLOCK`` (the generate options, ``--name``
    when the block names its ``module``, ``--resources`` when it offers synthesis figures);
    ``options(parser)`` adds the block's own options to both, ``simulate``/``generate`` are
    the commands; ``faces``: ``generate`` takes ``--face`` (a block with a payload). Returns
    both parsers for more options."""
    s = groups.simulate.add_parser(block, help=help)
    s.add_argument("--engine", choices=engine_choices(block), metavar="ENGINE", default="golden",
                   help="%(choices)s (default golden)")
    s.add_argument("--duration-ms", type=positive_float, default=duration_ms,
                   help=f"biological time in ms (default {duration_ms:g})")
    add_run_options(s)
    g = groups.generate.add_parser(block, help=help)
    add_generate_options(g)
    if faces:
        add_face_option(g)
    if module:
        g.add_argument("--name", type=verilog_name, default=module,
                       help=f"Verilog module name (default {module})")
    if resources_s:
        g.add_argument("--resources", action="store_true",
                       help=f"also run yosys synth_ecp5 and synth_xilinx -family xc6s "
                            f"(~{resources_s} s)")
    add_quiet_option(s)
    add_spikes_option(s)
    for p, func in ((s, simulate), (g, generate)):
        if options is not None:
            options(p)
        if func is not None:
            p.set_defaults(func=_with_progress(func) if p is s else func)
    return s, g


def _with_progress(func):
    def run(args):
        start_progress(args)
        return func(args)
    run.__doc__ = func.__doc__
    return run
