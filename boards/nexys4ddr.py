"""Digilent Nexys 4 DDR (Xilinx Artix-7 XC7A100TCSG324-1): a Vivado-ready project and a yosys
estimate. UART: the board's FT2232HQ USB-serial (FPGA D4 tx, C4 rx; RTS/CTS unused). Clock
plan: the 100 MHz oscillator (E3) through an ``MMCME2_BASE`` to 40 MHz (as the Arty,
:mod:`.arty`). Running, overflow and clamp on LD0-LD2."""

from __future__ import annotations

from .arty import ARTIX7_100T, artix7_target
from .platforms import amaranth_board

__all__ = ["TARGET"]

TARGET = artix7_target(
    "nexys4ddr", "Digilent Nexys 4 DDR, Xilinx Artix-7 100T: Vivado project and yosys estimate",
    "XC7A100TCSG324-1", ARTIX7_100T, amaranth_board("nexys4ddr", "Nexys4DDRPlatform"),
    "the board's FT2232HQ USB-serial (D4 out, C4 in)")
