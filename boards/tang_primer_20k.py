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

from .platforms import himbaechel_gowin
from .pll import gowin_rpll
from .top import ClockPlan

__all__ = ["TARGET"]


def platform():
    from amaranth_boards.tang_primer_20k import TangPrimer20kDockPlatform
    return himbaechel_gowin(TangPrimer20kDockPlatform)()


def _plan(mhz, pll):
    return ClockPlan(osc_hz=27e6, clock_hz=mhz * 1e6, update_hz=16e3, baud=3e6), pll


PLANS = [_plan(48, gowin_rpll("gw2a", 27.0, 8, 15, 16)),
         _plan(54, gowin_rpll("gw2a", 27.0, 0, 1, 16)),
         _plan(72, gowin_rpll("gw2a", 27.0, 2, 7, 8)),
         _plan(90, gowin_rpll("gw2a", 27.0, 2, 9, 8))]

TARGET = {
    "name": "tang_primer_20k",
    "description": "Sipeed Tang Primer 20K (Dock), Gowin GW2A-18 C8/I7: bitstream (yosys, "
                   "nextpnr-himbaechel, gowin_pack)",
    "family": "gowin", "device": "GW2A-LV18PG256C8/I7",
    "platform": platform,
    "clock_plan": PLANS[0][0], "pll": PLANS[0][1],
    "clock_plans": PLANS, "pll_clocks": [p.clock_hz for p, _ in PLANS],
    # GW2A-18: 20736 LUT4, 15552 flip-flops, 46 BSRAM of 18 Kbit, 48 18x18 multipliers
    "resources": {"LUT": 20736, "FF": 15552, "BRAM": 46, "DSP": 48},
    "bram_shapes": [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    "lutram_bits": 64, "dsp_width": 18,
    # board-build fmax bound (MHz) for the sizing: provisional: the GW1NR-9's measured board-build fmax (the GW2A-18 C8 is the faster family member) until this board's largest build is measured
    "link_fmax_mhz": 57.3,
    "default_neurons": 2500,
    "nextpnr_freq": True,
    "nextpnr_cells": {"LUT": "LUT4", "ALU": "ALU", "FF": "DFF", "BRAM": "BSRAM",
                      "DSP": "MULT18X18"},
    "uart": "the Dock's USB debugger's serial port (pins M11 tx, T13 rx)",
    "bitstream": True, "loader_board": "tangprimer20k", "bitstream_ext": "fs",
}
