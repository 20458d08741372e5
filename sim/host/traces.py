"""Recorded FBG traces: CSV, NPZ and MATLAB ``.mat`` (scipy.io).

Every format gives a time column and one column per grating:

CSV
    A header row, then rows ``time, g0, g1, ...`` (``time_key`` names the time column, default
    ``Time``; the other columns are the gratings in order). ``#`` starts a comment line.
NPZ
    Arrays ``time_key`` (n,) and ``data_key`` (n, gratings) (defaults ``Time`` /
    ``DeltaBraggW``).
MAT
    Variables ``time_key`` and ``data_key``, or the same fields inside a struct named
    ``struct`` (for interrogator exports like ``FBG.Time`` / ``FBG.DeltaBraggW``); field names
    are configurable.

Nothing is repaired: a NaN or infinite sample, a non-increasing time stamp, or a gap (a step
larger than 1.5 sample periods) raises :class:`TraceError` naming the file, the row (0-based
data row) and the column. Sample rates must be uniform within 1 %; ``expect_fs_hz`` refuses a
trace at another rate (resampling is a decision for the user, not the loader).
"""

from __future__ import annotations

import csv
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ...golden.tactile import Trace

__all__ = ["TraceError", "load_trace", "check_trace"]


class TraceError(ValueError):
    """A recorded trace cannot be used as is (one line: file, position, reason)."""


def check_trace(path, t, x, time_unit="s", shift_unit="nm", expect_fs_hz=None,
                channels=None) -> Trace:
    """Validate time stamps ``t`` (n,) and shifts ``x`` (n, g) and build a :class:`Trace`."""
    t = np.asarray(t, dtype=np.float64).ravel()
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2:
        raise TraceError(f"{path}: shifts must be 2-D (samples, gratings), got shape {x.shape}")
    if x.shape[0] != t.size:
        if x.shape[1] == t.size:
            x = x.T
        else:
            raise TraceError(f"{path}: {t.size} time stamps but {x.shape[0]} rows of shifts")
    if t.size < 2:
        raise TraceError(f"{path}: needs at least 2 samples, got {t.size}")
    bad = ~np.isfinite(t)
    if bad.any():
        raise TraceError(f"{path}: row {int(np.flatnonzero(bad)[0])}: time stamp is "
                         f"{float(t[bad][0])!r}")
    bad = ~np.isfinite(x)
    if bad.any():
        r, c = (int(v) for v in np.argwhere(bad)[0])
        raise TraceError(f"{path}: row {r}, grating {c}: sample is {float(x[r, c])!r} "
                         f"({int(bad.sum())} non-finite sample(s) in all)")
    dt = np.diff(t)
    if np.any(dt <= 0):
        r = int(np.flatnonzero(dt <= 0)[0]) + 1
        raise TraceError(f"{path}: row {r}: time stamp {float(t[r])!r} does not increase "
                         f"(previous {float(t[r - 1])!r})")
    step = float(np.median(dt))
    if np.any(dt > 1.5 * step):
        r = int(np.flatnonzero(dt > 1.5 * step)[0]) + 1
        raise TraceError(f"{path}: row {r}: gap of {dt[r - 1]:g} {time_unit} before time "
                         f"{t[r]:g} (sample period {step:g} {time_unit})")
    if np.any(np.abs(dt - step) > 0.01 * step):
        r = int(np.flatnonzero(np.abs(dt - step) > 0.01 * step)[0]) + 1
        raise TraceError(f"{path}: row {r}: non-uniform sampling (step {dt[r - 1]:g} vs "
                         f"{step:g} {time_unit})")
    fs = (1.0 if time_unit == "s" else 1000.0) / step
    if expect_fs_hz is not None and abs(fs - expect_fs_hz) > 0.01 * expect_fs_hz:
        raise TraceError(f"{path}: sampled at {fs:g} Hz but the scene's sensor samples at "
                         f"{expect_fs_hz:g} Hz")
    if channels is not None and x.shape[1] != channels:
        raise TraceError(f"{path}: {x.shape[1]} grating column(s) but the scene's sensor has "
                         f"{channels} channels")
    nm = x if shift_unit == "nm" else x * 1e-3
    return Trace(nm, float(expect_fs_hz or fs), {"file": str(path), "samples": int(t.size),
                                                 "fs_hz": fs})


def _load_csv(p: Path, time_key: str):
    try:
        with p.open(newline="", encoding="utf-8") as f:
            rows = [r for r in csv.reader(f) if r and not r[0].lstrip().startswith("#")]
    except UnicodeDecodeError as exc:
        line = p.read_bytes()[:exc.start].count(b"\n") + 1
        raise TraceError(f"{p}: line {line}: not UTF-8 text (byte {exc.object[exc.start]:#04x} "
                         f"at offset {exc.start})") from None
    except csv.Error as exc:
        raise TraceError(f"{p}: not a CSV file: {exc}") from None
    if not rows:
        raise TraceError(f"{p}: empty file")
    head = [h.strip() for h in rows[0]]
    if time_key not in head:
        raise TraceError(f"{p}: row 0 (header): no time column {time_key!r} (columns: "
                         f"{', '.join(head)})")
    ti = head.index(time_key)
    data = []
    for i, r in enumerate(rows[1:]):
        if len(r) != len(head):
            raise TraceError(f"{p}: row {i}: {len(r)} columns, header has {len(head)}")
        vals = []
        for j, v in enumerate(r):
            v = v.strip()
            try:
                vals.append(float(v) if v else float("nan"))
            except ValueError:
                raise TraceError(f"{p}: row {i}, column {head[j]!r}: not a number: "
                                 f"{v!r}") from None
        data.append(vals)
    a = np.asarray(data, dtype=np.float64).reshape(-1, len(head))
    return a[:, ti], np.delete(a, ti, axis=1)


def _reason(exc: Exception, p: Path) -> str:
    """Why a file could not be read, in a few words (an empty file says so)."""
    try:
        if p.stat().st_size == 0:
            return "the file is empty"
    except OSError:
        pass
    return f"{type(exc).__name__}: {str(exc)[:160] or 'no detail'}"


def _numbers(p, a, what: str) -> np.ndarray:
    """``a`` as a real numeric array, or a :class:`TraceError` naming the file and the field
    (a struct, text, or complex values whose imaginary part would be lost)."""
    arr = np.asarray(a)
    if arr.dtype.kind == "c":
        raise TraceError(f"{p}: {what} holds complex values (the imaginary part would be "
                         f"lost); store real shifts")
    if arr.dtype.kind == "b":
        raise TraceError(f"{p}: {what} holds booleans (true/false), not numbers")
    if arr.dtype.kind not in "iuf":
        kind = type(a).__name__ if arr.dtype.kind == "O" and arr.ndim == 0 else \
            f"an array of {arr.dtype}"
        raise TraceError(f"{p}: {what} is not numeric (it is {kind})")
    return arr


def _get(obj, key, p, where):
    try:
        if isinstance(obj, dict):
            return obj[key]
        return obj[key] if hasattr(obj, "dtype") and obj.dtype.names else getattr(obj, key)
    except (KeyError, AttributeError, ValueError, IndexError):
        raise TraceError(f"{p}: no {key!r} in {where}") from None


def load_trace(path, time_key: str = "Time", data_key: str = "DeltaBraggW",
               struct: str | None = None, time_unit: str = "s", shift_unit: str = "nm",
               expect_fs_hz: float | None = None, channels: int | None = None) -> Trace:
    """Load and validate a recorded trace (see the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise TraceError(f"{p}: no such file")
    suf = p.suffix.lower()
    if suf == ".csv":
        t, x = _load_csv(p, time_key)
    elif suf == ".npz":
        try:
            with np.load(p, allow_pickle=False) as z:
                if time_key not in z or data_key not in z:
                    raise TraceError(f"{p}: needs arrays {time_key!r} and {data_key!r} (has "
                                     f"{', '.join(z.files)})")
                t, x = z[time_key], z[data_key]
        except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            if isinstance(exc, TraceError):
                raise
            raise TraceError(f"{p}: not a readable NPZ file ({_reason(exc, p)})") from None
    elif suf == ".mat":
        import scipy.io
        try:
            m = scipy.io.loadmat(p, squeeze_me=True, struct_as_record=False)
        except (OSError, ValueError, NotImplementedError, EOFError, TypeError,
                scipy.io.matlab.MatReadError) as exc:
            raise TraceError(f"{p}: not a readable MAT file ({_reason(exc, p)})") from None
        src, where = m, "the file"
        if struct:
            src = _get(m, struct, p, "the file")
            where = f"struct {struct!r}"
        t, x = _get(src, time_key, p, where), _get(src, data_key, p, where)
    else:
        raise TraceError(f"{p}: unknown trace format {suf!r} (use .csv, .npz or .mat)")
    where = f" in struct {struct!r}" if suf == ".mat" and struct else ""
    t = _numbers(p, t, f"the time field {time_key!r}{where}")
    x = _numbers(p, x, f"the data field {data_key!r}{where}")
    return check_trace(p, t, x, time_unit, shift_unit, expect_fs_hz, channels)
