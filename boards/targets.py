"""The registry of board targets: one module per board, each defining ``TARGET`` (its device,
clock plans, resources and build options). Adding a board: write its module and add it to
:data:`BOARD_MODULES`."""

from __future__ import annotations

from . import arty, atlys, icebreaker, ulx3s

__all__ = ["TARGETS", "BOARD_MODULES"]

#: Board modules, in the order ``cuneate boards`` lists them.
BOARD_MODULES = (ulx3s, icebreaker, atlys, arty)
TARGETS = {m.TARGET["name"]: m.TARGET for m in BOARD_MODULES}
