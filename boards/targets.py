"""The registry of board targets (one module per board)."""

from __future__ import annotations

from . import icebreaker, ulx3s
from .estimate_targets import ARTY, ATLYS

__all__ = ["TARGETS"]

TARGETS = {t["name"]: t for t in (ulx3s.TARGET, icebreaker.TARGET, ATLYS, ARTY)}
