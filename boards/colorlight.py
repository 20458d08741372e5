"""Colorlight 5A-75B v7.0 (Lattice ECP5 LFE5U-25F-6BG256): bitstream with yosys, nextpnr-ecp5
and ecppack.

UART: the board has no USB at all: the host needs a 3.3 V USB-UART adapter on connector J19,
the pin wired to the status LED (FPGA P11, the board's TX) and the button's (FPGA M13, the
board's RX), and GND; the LED then carries the line, so no status LED is driven. Clock plans:
the 25 MHz oscillator through an ``EHXPLLL``, those of the ULX3S: 60 MHz (25 / 5 x 12; 3750
cycles per 16 kHz sweep, 20 clocks per bit at 3 Mbaud), 70 MHz (25 / 5 x 14; 4375 cycles, the
line at 2 Mbaud, 35 clocks) and 90 MHz (25 / 5 x 18; 5625 cycles, 30 clocks at 3 Mbaud).
"""

from __future__ import annotations

from .pll import ecp5_pll
from .top import ClockPlan

__all__ = ["TARGET"]


def platform():
    from amaranth_boards.colorlight_5a75b_r7_0 import Colorlight_5A75B_R70Platform
    from .platforms import without_commands
    return without_commands(Colorlight_5A75B_R70Platform, ("openFPGALoader",))()


PLANS = [(ClockPlan(osc_hz=25e6, clock_hz=60e6, update_hz=16e3, baud=3e6),
          ecp5_pll(25.0, 5, 12, 10)),
         (ClockPlan(osc_hz=25e6, clock_hz=70e6, update_hz=16e3, baud=2e6),
          ecp5_pll(25.0, 5, 14, 8)),
         (ClockPlan(osc_hz=25e6, clock_hz=90e6, update_hz=16e3, baud=3e6),
          ecp5_pll(25.0, 5, 18, 6))]

TARGET = {
    "name": "colorlight",
    "description": "Colorlight 5A-75B v7.0, Lattice ECP5 LFE5U-25F speed grade 6: bitstream "
                   "(yosys, nextpnr-ecp5, ecppack); UART through an adapter on J19",
    "family": "ecp5", "device": "LFE5U-25F-6BG256C",
    "platform": platform,
    "clock_plan": PLANS[0][0], "pll": PLANS[0][1],
    "clock_plans": PLANS, "pll_clocks": [p.clock_hz for p, _ in PLANS],
    "resources": {"LUT": 24288, "FF": 24288, "BRAM": 56, "DSP": 28},
    "bram_shapes": [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    "lutram_bits": 512, "dsp_width": 18,
    # board-build fmax bound (MHz) for the sizing: provisional: the ULX3S's filled board build (ECP5, the same speed grade 6) until this board's largest build is measured
    "link_fmax_mhz": 80.8,
    "default_neurons": 2500,
    "status_leds": 0,
    "nextpnr_cells": {"LUT": "TRELLIS_COMB", "FF": "TRELLIS_FF", "BRAM": "DP16KD",
                      "DSP": "MULT18X18D"},
    "uart": "no USB on the board: a 3.3 V USB-UART adapter on J19, the LED pin (FPGA P11, out) "
            "and the button pin (FPGA M13, in)",
    "bitstream": True, "loader_board": "colorlight", "bitstream_ext": "bit",
}
