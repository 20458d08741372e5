"""Shared helpers for the benchmarks (``make bench`` / ``pytest -m benchmark -s benchmarks``).

Benchmarks print what they measure and also write it as JSON to ``benchmarks/results/`` (created
at run time); they assert sanity only (figures positive, tools succeeded), never a speed.
Simulator and synthesis work happens under ``build/bench/``.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

import pytest

from cuneate.sim.engines.toolchain import apply_simulator_env

apply_simulator_env()

ROOT = Path(__file__).resolve().parents[1]
RESULTS_DIR = Path(__file__).resolve().parent / "results"


def host_info() -> dict:
    import numpy
    return {"python": platform.python_version(), "numpy": numpy.__version__,
            "machine": platform.machine(), "cpus": os.cpu_count(),
            "platform": platform.platform(), "when": time.strftime("%Y-%m-%dT%H:%M:%S")}


def format_table(rows: list[dict], columns: list[str] | None = None) -> str:
    """Plain fixed-width table of ``rows`` (dicts); floats get 4 significant digits."""
    if not rows:
        return "(no rows)"
    columns = columns or list(dict.fromkeys(k for r in rows for k in r))

    def fmt(x):
        if x is None:
            return "-"
        if isinstance(x, float):
            return f"{x:,.4g}" if abs(x) < 1e4 else f"{x:,.0f}"
        if isinstance(x, int) and not isinstance(x, bool):
            return f"{x:,}"
        return str(x)

    cells = [[fmt(r.get(c)) for c in columns] for r in rows]
    widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(columns)]
    line = "  ".join(c.ljust(w) for c, w in zip(columns, widths))
    sep = "  ".join("-" * w for w in widths)
    body = ["  ".join(v.rjust(w) if i else v.ljust(w) for i, (v, w) in
                      enumerate(zip(row, widths))) for row in cells]
    return "\n".join([line, sep, *body])


def write_result(name: str, data: dict) -> Path:
    """Write ``benchmarks/results/<name>.json`` (with host information) and return the path."""
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    path = RESULTS_DIR / f"{name}.json"
    path.write_text(json.dumps({"benchmark": name, "host": host_info(), **data}, indent=2,
                               sort_keys=False, default=str) + "\n")
    return path


def report(name: str, title: str, rows: list[dict], extra: dict | None = None,
           columns: list[str] | None = None) -> Path:
    """Print ``rows`` as a table under ``title`` and write them (plus ``extra``) as JSON."""
    path = write_result(name, {"title": title, "rows": rows, **(extra or {})})
    print(f"\n=== {title} ===\n{format_table(rows, columns)}\n(written to "
          f"{path.relative_to(ROOT)})", file=sys.stdout, flush=True)
    return path


@pytest.fixture(scope="session")
def bench_build() -> Path:
    """Root of benchmark build directories (``CUNEATE_BENCH_BUILD_DIR`` or ``build/bench``)."""
    root = Path(os.environ.get("CUNEATE_BENCH_BUILD_DIR", ROOT / "build" / "bench"))
    root.mkdir(parents=True, exist_ok=True)
    return root


class _Bench:
    """What the ``bench`` fixture gives a benchmark (test modules cannot import conftest)."""

    report = staticmethod(report)
    write_result = staticmethod(write_result)
    format_table = staticmethod(format_table)
    results_dir = RESULTS_DIR
    root = ROOT


@pytest.fixture(scope="session")
def bench() -> _Bench:
    return _Bench()
