"""Sipeed Tang Nano 9K (Gowin GW1NR-LV9QN88PC6/I5): bitstream (``.fs``) with yosys
``synth_gowin``, nextpnr-himbaechel (gowin) and apycula's ``gowin_pack``.

UART: the on-board BL702 (USB-JTAG and USB-serial, the second USB serial port on the host),
FPGA pins 17 (tx) and 18 (rx). Clock plans: the 27 MHz oscillator (pin 52) through an
``rPLL``: 48 MHz (27 / 9 x 16, VCO 768 MHz; 3000 cycles per 16 kHz sweep, 16 clocks per bit
at 3 Mbaud), 54 MHz (27 x 2, VCO 864 MHz; 3375 cycles, 18 clocks a bit) and 72 MHz (27 / 3 x
8, VCO 576 MHz; 4500 cycles, 24 clocks a bit). Running and overflow on LEDs 0 and 1 (active
low on the board).
"""

from __future__ import annotations

from .gowin import gowin_target, rpll_plans

__all__ = ["TARGET"]


PLANS = rpll_plans("gw1n", 48, 54, 72)

# GW1NR-9: 8640 LUT4, 6480 flip-flops, 26 BSRAM of 18 Kbit, 20 18x18 multipliers
TARGET = gowin_target(
    "tang_nano_9k", "Sipeed Tang Nano 9K, Gowin GW1NR-9 C6/I5", "GW1NR-LV9QN88PC6/I5",
    "TangNano9kPlatform", PLANS, {"LUT": 8640, "FF": 6480, "BRAM": 26, "DSP": 20},
    # board-build fmax bound (MHz) for the sizing: the 1000-neuron build at 48 MHz, seed 1
    # (the largest build, 26 of 26 block RAMs, did not finish place and route in an hour;
    # benchmarks/boards.md)
    link_fmax_mhz=57.3, loader_board="tangnano9k",
    uart="the BL702's USB serial port (pins 17 tx, 18 rx)")
