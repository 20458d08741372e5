"""Digilent Arty A7-100T (Xilinx Artix-7 XC7A100TICSG324-1L): the Arty A7-35T's board
(:mod:`.arty`: UART, clock plan, LEDs) with the larger device: a Vivado-ready project and a
yosys estimate."""

from __future__ import annotations

from .arty import ARTIX7_100T, artix7_target
from .platforms import amaranth_board

__all__ = ["TARGET"]

TARGET = artix7_target(
    "arty100", "Digilent Arty A7-100T, Xilinx Artix-7: Vivado project and yosys estimate",
    "XC7A100TICSG324-1L", ARTIX7_100T, amaranth_board("arty_a7", "ArtyA7_100Platform"),
    "the board's FT2232HQ USB-serial (D10 out, A9 in)")
