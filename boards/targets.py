"""The registry of board targets: one module per board, each defining ``TARGET`` (its device,
clock plans, resources and build options). Adding a board: write its module and add it to
:data:`BOARD_MODULES`."""

from __future__ import annotations

from . import (arty, arty100, arty_z7, atlys, butterstick, colorlight, crosslink_nx, icebreaker,
               orangecrab, nexys4ddr, pynq_z2, tang_nano_9k, tang_primer_20k, ulx3s)

__all__ = ["TARGETS", "BOARD_MODULES"]

#: Board modules, in the order ``cuneate boards`` lists them.
BOARD_MODULES = (ulx3s, butterstick, orangecrab, colorlight, icebreaker, tang_primer_20k,
                 tang_nano_9k, crosslink_nx, atlys, arty, arty100, nexys4ddr, arty_z7, pynq_z2)
TARGETS = {m.TARGET["name"]: m.TARGET for m in BOARD_MODULES}
