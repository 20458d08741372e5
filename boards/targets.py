"""The registry of board targets (one module per board)."""

from __future__ import annotations

from . import ulx3s
from .estimate_targets import ARTY, ATLYS, ICEBREAKER

__all__ = ["TARGETS"]

TARGETS = {t["name"]: t for t in (ulx3s.TARGET, ICEBREAKER, ATLYS, ARTY)}
