"""Bookkeeping of the hard-case suite: what each case tried and checked, and a summary.

Every test of ``tests/hardcases`` calls :func:`record` with the cases it tried, the updates it
checked and the mismatches it found (0 when it passes); the records go to
``$CUNEATE_HARDCASES_DIR`` (default ``build/hardcases``), one JSON file per case, and
``cuneate hardcases summary`` prints them as a table.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

__all__ = ["record", "records_dir", "summary", "format_summary"]


def records_dir(path: str | Path | None = None) -> Path:
    return Path(path or os.environ.get("CUNEATE_HARDCASES_DIR", "build/hardcases"))


def record(name: str, cases: int, updates: int, mismatches: int, detail: str = "",
           path: str | Path | None = None) -> dict:
    """Write the record of one hard case; returns it."""
    d = records_dir(path)
    d.mkdir(parents=True, exist_ok=True)
    rec = {"case": name, "cases_tried": int(cases), "updates_checked": int(updates),
           "mismatches": int(mismatches), "detail": detail, "time": time.time()}
    (d / f"{name}.json").write_text(json.dumps(rec))
    return rec


def summary(path: str | Path | None = None) -> list[dict]:
    d = records_dir(path)
    if not d.is_dir():
        raise FileNotFoundError(f"no hard-case records in {d} (run the hard-case tests first: "
                                f"pytest tests/hardcases)")
    return sorted((json.loads(f.read_text()) for f in d.glob("*.json")),
                  key=lambda r: r["case"])


def format_summary(rows: list[dict]) -> str:
    w = max([len(r["case"]) for r in rows] + [4])
    out = [f"{'case':{w}s} {'cases':>8s} {'updates':>14s} {'mismatches':>10s}  detail"]
    for r in rows:
        out.append(f"{r['case']:{w}s} {r['cases_tried']:8d} {r['updates_checked']:14d} "
                   f"{r['mismatches']:10d}  {r['detail']}")
    out.append(f"{'total':{w}s} {sum(r['cases_tried'] for r in rows):8d} "
               f"{sum(r['updates_checked'] for r in rows):14d} "
               f"{sum(r['mismatches'] for r in rows):10d}")
    return "\n".join(out)
