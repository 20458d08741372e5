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

from .platforms import amaranth_board, without_commands
from .top import open_flow_target
from .ulx3s import PLANS as ULX3S_PLANS

__all__ = ["TARGET"]

TARGET = open_flow_target(
    "colorlight", "Colorlight 5A-75B v7.0, Lattice ECP5 LFE5U-25F speed grade 6: bitstream "
    "(yosys, nextpnr-ecp5, ecppack); UART through an adapter on J19", "ecp5",
    "LFE5U-25F-6BG256C",
    amaranth_board("colorlight_5a75b_r7_0", "Colorlight_5A75B_R70Platform",
                   lambda cls: without_commands(cls, ("openFPGALoader",))),
    ULX3S_PLANS, {"LUT": 24288, "FF": 24288, "BRAM": 56, "DSP": 28},
    # board-build fmax bound (MHz) for the sizing: the largest build's (3 cores of 3072 at
    # 60 MHz), lowest of seeds 1-3 (benchmarks/boards.md)
    link_fmax_mhz=89.02, status_leds=0, loader_board="colorlight",
    uart="no USB on the board: a 3.3 V USB-UART adapter on J19, the LED pin (FPGA P11, out) "
         "and the button pin (FPGA M13, in)")
