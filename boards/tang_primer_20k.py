"""Sipeed Tang Primer 20K on its Dock (Gowin GW2A-LV18PG256C8/I7): bitstream (``.fs``) with
yosys ``synth_gowin``, nextpnr-himbaechel (gowin) and apycula's ``gowin_pack``.

UART: the Dock's USB debugger (BL616: USB-JTAG and USB-serial on the Dock's USB-C "debug"
port), FPGA pins M11 (tx) and T13 (rx). Clock plans: the 27 MHz oscillator (pin H11) through
an ``rPLL``: 48 MHz (27 / 9 x 16, VCO 768 MHz; 3000 cycles per 16 kHz sweep, 16 clocks per
bit at 3 Mbaud), 54 MHz (27 x 2, VCO 864 MHz; 3375 cycles, 18 clocks a bit), 72 MHz (27 / 3 x 8, VCO 576 MHz; 4500 cycles, 24 clocks a bit) and 90 MHz (27 / 3 x
10, VCO 720 MHz; 5625 cycles, 30 clocks a bit). Running, overflow and clamp on the Dock's LEDs
0-2.
"""

from __future__ import annotations

from .gowin import gowin_target, rpll_plans

__all__ = ["TARGET"]


PLANS = rpll_plans("gw2a", 48, 54, 72, 90)

# GW2A-18: 20736 LUT4, 15552 flip-flops, 46 BSRAM of 18 Kbit, 48 18x18 multipliers
TARGET = gowin_target(
    "tang_primer_20k", "Sipeed Tang Primer 20K (Dock), Gowin GW2A-18 C8/I7",
    "GW2A-LV18PG256C8/I7", "TangPrimer20kDockPlatform", PLANS,
    {"LUT": 20736, "FF": 15552, "BRAM": 46, "DSP": 48},
    # board-build fmax bound (MHz) for the sizing: the largest build's (2 cores of 4096 at
    # 72 MHz), lowest of seeds 1-3 (benchmarks/boards.md)
    link_fmax_mhz=141.28, loader_board="tangprimer20k",
    uart="the Dock's USB debugger's serial port (pins M11 tx, T13 rx)")
