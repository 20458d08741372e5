"""The Gowin boards' shared base: clock plans from a 27 MHz oscillator through an ``rPLL`` and
the target of a Gowin board built by yosys ``synth_gowin``, nextpnr-himbaechel and apycula's
``gowin_pack`` (a ``.fs`` bitstream). Each board stays in its own file."""

from __future__ import annotations

from .platforms import amaranth_board, himbaechel_gowin
from .pll import gowin_rpll
from .top import open_flow_target, oscillator_plans

__all__ = ["RPLL_27", "rpll_plans", "gowin_target"]


#: the 27 MHz oscillator's rPLL dividers (IDIV_SEL, FBDIV_SEL, ODIV_SEL) by output clock (MHz)
RPLL_27 = {48: (8, 15, 16), 54: (0, 1, 16), 72: (2, 7, 8), 90: (2, 9, 8)}


def rpll_plans(family: str, *mhz: int) -> list:
    """The clock plans at ``mhz`` from a Gowin ``family``'s 27 MHz oscillator (3 Mbaud)."""
    return oscillator_plans(27.0, *((f, 3e6, gowin_rpll(family, 27.0, *RPLL_27[f]))
                                    for f in mhz))


def gowin_target(name: str, board: str, device: str, platform: str, plans: list,
                 resources: dict, **options) -> dict:
    """The open-flow target of the Gowin board ``name`` (``board``: its description before
    the flow; ``platform``: its class in ``amaranth_boards.<name>``, placed and routed by
    nextpnr-himbaechel); ``options`` as :func:`~cuneate.boards.top.open_flow_target`'s."""
    return open_flow_target(
        name, f"{board}: bitstream (yosys, nextpnr-himbaechel, gowin_pack)", "gowin", device,
        amaranth_board(name, platform, himbaechel_gowin), plans, resources, **options)
