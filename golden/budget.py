"""Estimate before allocating: the one place that knows how much memory and time a run may take.

Every command, scene and search that can grow with its parameters estimates its memory (bytes)
and time (seconds) from those parameters *before* its first large allocation and calls
:func:`check`; what would exhaust the machine's memory or exceed the time limit is refused with
:class:`BudgetError`, one line naming the work, the estimate and the limit. Nothing here
measures a run after the fact.

Limits
------
* **Memory**: a fraction (:data:`MEMORY_FRACTION`) of what this process can still get: the
  smallest of the memory the kernel reports available (``MemAvailable``), the control group's
  limit less its usage, and the address-space and data limits (``ulimit -v``, ``ulimit -d``) less the
  address space already mapped.
* **Time**: none by default (library calls run as long as they need); the command line sets it
  from ``--max-minutes`` for the duration of a command with :func:`limited`.

Estimates are conservative rates and sizes (the engines' speeds are in
:mod:`cuneate.sim.engines.registry`); the figures a check refuses are printed so that a user can
see how far over the limit a request is.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import os
import resource
from dataclasses import dataclass

__all__ = ["BudgetError", "Limits", "limits", "limited", "check", "available_memory",
           "array_bytes", "fmt_bytes", "fmt_count", "fmt_time", "MEMORY_FRACTION", "BASE_BYTES"]

#: Share of the memory this process can still get that one estimated run may use.
MEMORY_FRACTION = 0.8
#: What a process of this package holds before any run (interpreter, NumPy, SciPy, numba).
BASE_BYTES = 200 << 20


class BudgetError(ValueError):
    """A run refused before it starts: its estimated memory or time exceeds the limit (one line:
    what, the estimate, the limit, what to change)."""


@dataclass(frozen=True)
class Limits:
    """The limits in force: ``max_seconds`` (``None``: no time limit) and ``memory_bytes``
    (``None``: a fraction of what the process can get, probed at each check)."""

    max_seconds: float | None = None
    memory_bytes: float | None = None


_LIMITS: contextvars.ContextVar[Limits] = contextvars.ContextVar("cuneate_budget",
                                                                 default=Limits())


def limits() -> Limits:
    """The limits in force here."""
    return _LIMITS.get()


@contextlib.contextmanager
def limited(max_minutes: float | None = None, memory_bytes: float | None = None):
    """Run a block under a time limit of ``max_minutes`` (and, for tests, a fixed memory limit)."""
    token = _LIMITS.set(Limits(None if max_minutes is None else 60.0 * float(max_minutes),
                               memory_bytes))
    try:
        yield _LIMITS.get()
    finally:
        _LIMITS.reset(token)


def _meminfo_available() -> float:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return float(8 << 30)


def _cgroup_room() -> float:
    try:
        with open("/sys/fs/cgroup/memory.max") as f:
            top = f.read().strip()
        if top == "max":
            return math.inf
        with open("/sys/fs/cgroup/memory.current") as f:
            used = float(f.read().strip())
        return max(float(top) - used, 0.0)
    except (OSError, ValueError):
        return math.inf


def _rlimit_room(limit: int, field: str) -> float:
    """What is left under the soft ``limit`` (``ulimit -v``: the address space, ``VmSize``;
    ``ulimit -d``: the data segment and private writable mappings, ``VmData``)."""
    soft, _ = resource.getrlimit(limit)
    if soft == resource.RLIM_INFINITY:
        return math.inf
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return max(float(soft) - float(line.split()[1]) * 1024, 0.0)
    except OSError:
        pass
    return float(soft)


def _address_space_room() -> float:
    return min(_rlimit_room(resource.RLIMIT_AS, "VmSize"),
               _rlimit_room(resource.RLIMIT_DATA, "VmData"))


def available_memory() -> float:
    """Bytes this process can still allocate (the smallest of the limits above)."""
    return min(_meminfo_available(), _cgroup_room(), _address_space_room())


def array_bytes(*shape, itemsize: int = 8) -> float:
    """Bytes of an array of ``shape`` (floats, so that huge shapes never overflow)."""
    n = float(itemsize)
    for s in shape:
        n *= float(s)
    return n


def fmt_bytes(n: float) -> str:
    """A size for people (``3.2 GiB``)."""
    if not math.isfinite(n):
        return "an unbounded amount"
    for unit, k in (("TiB", 40), ("GiB", 30), ("MiB", 20), ("KiB", 10)):
        if n >= 1 << k:
            return f"{n / (1 << k):.3g} {unit}"
    return f"{n:.0f} B"


def fmt_count(n: float) -> str:
    """A count for people: exact below a million, else three significant digits (never a
    300-digit number)."""
    return f"{int(n)}" if abs(n) < 1e6 else f"{float(n):.3g}"


def fmt_time(s: float) -> str:
    """A duration for people: seconds, minutes, hours, days or years."""
    if not math.isfinite(s):
        return "forever"
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    if s < 2 * 86400:
        return f"{s / 3600:.1f} h"
    if s < 2 * 365 * 86400:
        return f"{s / 86400:.0f} days"
    return f"{s / (365 * 86400):.3g} years"


def check(what: str, nbytes: float = 0.0, seconds: float = 0.0, hint: str = "") -> dict:
    """Refuse ``what`` (:class:`BudgetError`) when ``nbytes`` exceeds the memory limit or
    ``seconds`` the time limit in force; returns the estimate and the limits otherwise.

    ``hint`` says what to change (``"shorten scene.duration_ms"``)."""
    lim = limits()
    room = available_memory()
    mem_limit = lim.memory_bytes if lim.memory_bytes is not None else MEMORY_FRACTION * room
    over = []
    if not nbytes <= mem_limit:
        over.append(f"needs about {fmt_bytes(nbytes)} of memory, more than the "
                    f"{fmt_bytes(mem_limit)} this machine can give it now")
    if lim.max_seconds is not None and not seconds <= lim.max_seconds:
        over.append(f"would take about {fmt_time(seconds)}, more than the limit of "
                    f"{fmt_time(lim.max_seconds)} (--max-minutes {lim.max_seconds / 60:g})")
    if over:
        raise BudgetError(f"{what} {' and '.join(over)}" + (f"; {hint}" if hint else ""))
    return {"bytes": float(nbytes), "seconds": float(seconds), "memory_limit": mem_limit,
            "max_seconds": lim.max_seconds}
