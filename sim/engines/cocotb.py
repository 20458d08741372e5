"""The one cocotb runner: run a block's bench on its generated Verilog through
:mod:`cocotb_tools.runner`, on Icarus or Verilator.

Each (simulator, design, parameters) case gets its own build directory. A block's bench is the
module ``cuneate.sim.<block>.bench``, imported inside the simulator by its dotted name;
configuration goes in through environment variables (a JSON file path), and results come back as
JSON written by the bench (:mod:`cuneate.sim.engines.bench` is the bench side), so the caller
can print figures and assert on them. :func:`run_bench`
writes a block's Verilog and runs its bench in one call (in a scratch directory unless one is
given).

Verilator models are cached: a build is keyed by the Verilog's bytes, the top level, the build
arguments, waves, and the Verilator and cocotb versions, and kept under
``$CUNEATE_SIM_CACHE`` (default ``$XDG_CACHE_HOME/cuneate/sim`` or ``~/.cache/cuneate/sim``;
``CUNEATE_SIM_CACHE=off`` builds in the case's own directory every time). The same design is
compiled once and reused by every later run, whatever its build directory; concurrent runs
serialize on a lock per entry, and the least recently used entries beyond
:data:`CACHE_ENTRIES` are removed. Verilator's runtime library (:data:`RUNTIME_OBJECTS`),
the same for every design, is compiled by the first build and copied into the later ones.
"""

from __future__ import annotations

import fcntl
import hashlib
import importlib.util
import json
import os
import shutil
import tempfile
import threading
import time
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from .toolchain import SIMULATORS, apply_simulator_env

__all__ = ["CocotbRun", "run_cocotb", "run_bench", "run_engine_bench", "SimulatorFailed",
           "sim_cache_root", "CACHE_ENTRIES"]

#: Verilator builds kept in the cache (least recently used removed first).
CACHE_ENTRIES = 48


class SimulatorFailed(RuntimeError):
    """The cocotb run reported failures, ran no test, or produced no results."""


@dataclass
class CocotbRun:
    simulator: str
    build_dir: Path
    n_tests: int
    n_failed: int
    results_xml: Path
    report: dict | None


def run_cocotb(simulator: str, sources: list[Path], toplevel: str, test_module: str,
               build_dir: Path, config: dict | None = None, testcase: str | None = None,
               build_args: list[str] | None = None, waves=None,
               quiet: bool = True, progress=None) -> CocotbRun:
    """Build ``sources`` with ``simulator`` and run the cocotb ``test_module`` on ``toplevel``.

    ``config`` is written to ``build_dir/config.json`` and passed as ``CUNEATE_BENCH_CONFIG``;
    the bench writes ``build_dir/report.json`` (path in ``CUNEATE_BENCH_REPORT``), returned as
    :attr:`CocotbRun.report`. Raises :class:`SimulatorFailed` unless at least one test ran and none
    failed. ``progress``, if given, is called with the count a bench writes to
    ``build_dir/progress.json`` (``{"done": n}``) while the simulator runs. ``waves``: a
    :class:`~cuneate.sim.engines.waves.Waves` window, for sources instrumented by
    :func:`~cuneate.sim.engines.waves.instrument` (the dump goes to ``waves.path(simulator)``).
    Compiling and simulating are reported as steps (:mod:`cuneate.sim.progress`).
    """
    from .. import progress as prog
    if simulator not in SIMULATORS:
        raise ValueError(f"unknown simulator {simulator!r}; known: {', '.join(SIMULATORS)}")
    apply_simulator_env()
    from cocotb_tools.check_results import get_results
    from cocotb_tools.runner import get_runner

    build_dir = Path(build_dir).resolve()
    build_dir.mkdir(parents=True, exist_ok=True)
    cfg_path = build_dir / "config.json"
    report_path = build_dir / "report.json"
    progress_path = build_dir / "progress.json"
    cfg_path.write_text(json.dumps((config or {}) | {"progress_file": str(progress_path)}))
    for f in (report_path, progress_path):
        if f.exists():
            f.unlink()

    args = list(build_args or [])
    plusargs, test_waves = [], False
    if waves:
        from .waves import cocotb_options
        opts = cocotb_options(simulator, waves)
        args += opts["build_args"]
        plusargs, test_waves = opts["plusargs"], opts["test_waves"]
    if simulator == "verilator":
        # Amaranth's output is lint-clean in spirit but not width-pedantic.
        args += ["-Wno-fatal", "-Wno-WIDTHEXPAND", "-Wno-WIDTHTRUNC", "-O3"]
    runner = get_runner(simulator)
    log = build_dir / "build.log" if quiet else None
    sim_dir = build_dir
    cache = sim_cache_root() if simulator == "verilator" else None
    if cache is not None:
        try:
            cache.mkdir(parents=True, exist_ok=True)
        except OSError:
            cache = None                 # an unwritable cache: build in the case's directory
    trace = simulator == "verilator" and bool(waves)
    if cache is not None:
        sim_dir = _cached_build(runner, cache, sources, toplevel, args, trace, log)
    else:
        with prog.step(f"compiling {toplevel} with {simulator}"):
            runner.build(sources=[str(s) for s in sources], hdl_toplevel=toplevel,
                         build_dir=build_dir, timescale=("1ns", "1ps"), build_args=args,
                         always=True, waves=trace, log_file=log)
    env = {"CUNEATE_BENCH_CONFIG": str(cfg_path), "CUNEATE_BENCH_REPORT": str(report_path),
           "COCOTB_LOG_LEVEL": os.environ.get("COCOTB_LOG_LEVEL", "WARNING")}
    stop = threading.Event()
    poller = None
    if progress is not None:
        def poll():
            last = -1
            while not stop.wait(0.5):
                try:
                    done = int(json.loads(progress_path.read_text())["done"])
                except (OSError, ValueError, KeyError):
                    continue
                if done != last:
                    progress(done)
                    last = done
        poller = threading.Thread(target=poll, daemon=True)
        poller.start()
    results = build_dir.resolve() / "results.xml"
    if progress is not None:
        # the simulator, cocotb and the bench take seconds to start before the first count
        prog.say(f"{simulator}: starting the simulation of {toplevel} (cocotb)")
    try:
        results = runner.test(test_module=test_module, hdl_toplevel=toplevel,
                              hdl_toplevel_lang="verilog",
                              build_dir=sim_dir, test_dir=build_dir, extra_env=env,
                              testcase=testcase, waves=test_waves, plusargs=plusargs,
                              results_xml=str(results),
                              log_file=build_dir / "test.log" if quiet else None)
    except SystemExit:
        # under pytest the runner exits on a failed test; its results say which (below)
        if not results.exists():
            raise SimulatorFailed(f"{simulator}: the simulation ended without results "
                                  f"(build dir {build_dir})") from None
    finally:
        stop.set()
        if poller is not None:
            poller.join()
    n_tests, n_failed = get_results(Path(results))
    report = json.loads(report_path.read_text()) if report_path.exists() else None
    run = CocotbRun(simulator, build_dir, n_tests, n_failed, Path(results), report)
    if n_tests == 0 or n_failed:
        tail = ""
        logf = build_dir / "test.log"
        if logf.exists():
            tail = "\n".join(logf.read_text(errors="replace").splitlines()[-40:])
        raise SimulatorFailed(f"{simulator}: {n_failed} of {n_tests} cocotb tests failed "
                              f"(build dir {build_dir})\n{tail}")
    return run


def run_bench(simulator: str, verilog: str, toplevel: str, block: str, config: dict,
              build_dir: Path | None = None, testcase: str | None = None,
              progress=None, waves=None) -> CocotbRun:
    """Write ``verilog`` as ``<toplevel>.v`` and run the bench of ``block``
    (``cuneate.sim.<block>.bench``) on it with ``config``, in ``build_dir`` or a scratch
    directory; returns the :class:`CocotbRun` (its ``report`` is the bench's JSON). With
    ``waves`` (a :class:`~cuneate.sim.engines.waves.Waves` window) the Verilog gets the
    window's control block and the run writes the dump and its GTKWave save file."""
    def go(bd: Path) -> CocotbRun:
        bd.mkdir(parents=True, exist_ok=True)
        src = bd / f"{toplevel}.v"
        if waves:
            from .waves import instrument
            src.write_text(instrument(verilog, toplevel))
        else:
            src.write_text(verilog)
        run = run_cocotb(simulator, [src], toplevel, f"cuneate.sim.{block}.bench", bd,
                         config=config, testcase=testcase, progress=progress, waves=waves)
        if waves:
            from .waves import write_gtkw
            dump = waves.path(simulator)
            write_gtkw(dump.with_suffix(".gtkw"), dump, simulator, verilog, toplevel)
        return run
    if build_dir is not None:
        return go(Path(build_dir))
    with tempfile.TemporaryDirectory(prefix=f"cuneate-{block}-{simulator}-") as tmp:
        return go(Path(tmp))


def run_engine_bench(simulator: str, verilog_of, toplevel: str, block: str, config: dict,
                     build_dir: Path | None = None) -> dict:
    """The ``engine`` test of a block's bench on its Verilog, ``verilog_of(lowered)``: Icarus
    runs the yosys-lowered netlist (see :func:`cuneate.hdl.flow.verilog.lowered_verilog`),
    Verilator the direct output. Returns the bench's report."""
    return run_bench(simulator, verilog_of(simulator == "icarus"), toplevel, block, config,
                     build_dir, testcase="engine").report


# ----------------------------------------------------------------------------------------------
# the build cache

def sim_cache_root() -> Path | None:
    """The Verilator build cache directory, or None when ``CUNEATE_SIM_CACHE=off``."""
    env = os.environ.get("CUNEATE_SIM_CACHE", "")
    if env.lower() in ("off", "0", "no"):
        return None
    if env:
        return Path(env).expanduser().resolve()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "cuneate" / "sim"


def _toolchain_hash():
    """A hash started with the Verilator and cocotb versions and cocotb's library path."""
    h = hashlib.sha256()
    for pkg in ("verilator", "cocotb"):
        try:
            h.update(f"{pkg}={version(pkg)};".encode())
        except PackageNotFoundError:
            h.update(f"{pkg}={shutil.which(pkg)};".encode())
    # the simulator binary loads cocotb's VPI library from this environment's path (RUNPATH):
    # a binary built from another environment may not find it
    spec = importlib.util.find_spec("cocotb")
    libs = Path(spec.origin).parent / "libs" if spec and spec.origin else None
    h.update(f"libs={libs};".encode())
    # the runtime library's sources as installed (a Verilator replaced in place, or one not
    # installed as a package, changes them)
    root = os.environ.get("VERILATOR_ROOT")
    for name in ("verilated.cpp", "verilated.h", "verilated.mk", "verilated_vpi.cpp"):
        f = Path(root) / "include" / name if root else None
        if f is not None and f.is_file():
            st = f.stat()
            h.update(f"{name}:{st.st_size}:{st.st_mtime_ns};".encode())
    return h


def _cache_key(sources, toplevel: str, args: list[str], waves: bool) -> str:
    h = _toolchain_hash()
    h.update(json.dumps([toplevel, args, bool(waves), "1ns/1ps"]).encode())
    for a in args:                       # files given as build arguments (a DPI source)
        if Path(a).is_file():
            h.update(Path(a).read_bytes())
    for src in sources:
        data = Path(src).read_bytes()
        h.update(f"{Path(src).name}:{len(data)};".encode())
        h.update(data)
    return h.hexdigest()[:20]


def _cached_build(runner, root: Path, sources, toplevel: str, args: list[str], waves: bool,
                  log) -> Path:
    """Build in (or reuse) the cache entry of this design; returns its directory."""
    entry = root / f"verilator-{toplevel}-{_cache_key(sources, toplevel, args, waves)}"
    stamp = entry / "built.json"
    from .. import progress as prog
    if stamp.exists():
        prog.say(f"verilator: the model of {toplevel} is in the build cache ({entry.name})")
    else:
        entry.mkdir(parents=True, exist_ok=True)
        with open(entry / ".lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not stamp.exists():
                # fixed source paths inside the entry: the build does not depend on where the
                # caller wrote its Verilog
                src_dir = entry / "src"
                src_dir.mkdir(exist_ok=True)
                copies = []
                for src in sources:
                    dst = src_dir / Path(src).name
                    shutil.copyfile(src, dst)
                    copies.append(str(dst))
                runtime = _runtime_dir(root, args, waves)
                reused = _reuse_runtime(runtime, entry)
                with prog.step(f"compiling the Verilator model of {toplevel} (first build "
                               f"of this design; cached for later runs"
                               f"{'; runtime library reused' if reused else ''})"):
                    if reused:
                        runner = _runner_keeping_runtime()
                    runner.build(sources=copies, hdl_toplevel=toplevel, build_dir=entry,
                                 timescale=("1ns", "1ps"), build_args=args, always=True,
                                 waves=waves, log_file=log)
                if not reused:
                    _keep_runtime(runtime, entry)
                stamp.write_text(json.dumps({"toplevel": toplevel, "args": args,
                                             "sources": [Path(c).name for c in copies]}))
                _prune(root, keep=entry)
    os.utime(stamp)
    return entry


#: Verilator's runtime library objects: compiled from its include directory alone (their
#: dependency files name nothing in the build directory), the same for every design built with
#: the same Verilator, arguments and tracing, so compiled once and copied into later builds
#: (newer than their sources, so ``make`` leaves them be).
RUNTIME_OBJECTS = ("verilated", "verilated_dpi", "verilated_vpi", "verilated_threads")


def _runtime_dir(root: Path, args: list[str], waves: bool) -> Path:
    h = _toolchain_hash()
    h.update(json.dumps([args, bool(waves)]).encode())
    return root / f"runtime-{h.hexdigest()[:20]}"


def _reuse_runtime(runtime: Path, entry: Path) -> bool:
    """Copy the runtime objects into ``entry`` when a previous build left them."""
    files = [f"{o}.{ext}" for o in RUNTIME_OBJECTS for ext in ("o", "d")]
    if not all((runtime / f).is_file() for f in files):
        return False
    for f in files:
        shutil.copyfile(runtime / f, entry / f)
    return True


def _runner_keeping_runtime():
    """cocotb's Verilator runner whose ``make`` takes the copied runtime objects as they are
    (``--old-file``: they would otherwise look older than the makefile Verilator writes)."""
    from cocotb_tools.runner import Verilator

    class _Runner(Verilator):
        def _build_command(self):
            cmds = super()._build_command()
            if cmds and cmds[-1] and cmds[-1][0] == "make":
                cmds[-1] = cmds[-1] + [f"--old-file={o}.o" for o in RUNTIME_OBJECTS]
            return cmds

    return _Runner()


def _keep_runtime(runtime: Path, entry: Path) -> None:
    """Keep the runtime objects ``entry``'s build compiled (whole, or not at all)."""
    files = [f"{o}.{ext}" for o in RUNTIME_OBJECTS for ext in ("o", "d")]
    if runtime.exists() or not all((entry / f).is_file() for f in files):
        return
    tmp = Path(tempfile.mkdtemp(prefix=".runtime-", dir=runtime.parent))
    for f in files:
        shutil.copyfile(entry / f, tmp / f)
    try:
        tmp.rename(runtime)
    except OSError:                      # another run kept them first
        shutil.rmtree(tmp, ignore_errors=True)


def _prune(root: Path, keep: Path) -> None:
    entries = []
    for d in root.glob("verilator-*"):
        st = d / "built.json"
        if d != keep and st.exists():
            entries.append((st.stat().st_mtime, d))
    entries.sort()
    excess = len(entries) + 1 - CACHE_ENTRIES
    now = time.time()
    for mtime, d in entries[:max(0, excess)]:
        if now - mtime > 600:            # never remove an entry a run may still be using
            shutil.rmtree(d, ignore_errors=True)
