"""Digilent Arty A7-100T (Xilinx Artix-7 XC7A100TICSG324-1L): the Arty A7-35T's board
(:mod:`.arty`: UART, clock plan, LEDs) with the larger device: a Vivado-ready project and a
yosys estimate."""

from __future__ import annotations

from .arty import artix7_target

__all__ = ["TARGET"]


def platform():
    from amaranth_boards.arty_a7 import ArtyA7_100Platform
    return ArtyA7_100Platform()


TARGET = artix7_target(
    "arty100", "Digilent Arty A7-100T, Xilinx Artix-7: Vivado project and yosys estimate",
    "XC7A100TICSG324-1L", {"LUT": 63400, "FF": 126800, "BRAM": 270, "DSP": 240}, platform,
    "the board's FT2232HQ USB-serial (D10 out, A9 in)")
