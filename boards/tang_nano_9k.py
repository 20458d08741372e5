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

from .platforms import himbaechel_gowin
from .pll import gowin_rpll
from .top import ClockPlan

__all__ = ["TARGET"]


def platform():
    from amaranth_boards.tang_nano_9k import TangNano9kPlatform
    return himbaechel_gowin(TangNano9kPlatform)()


def _plan(mhz, pll):
    return ClockPlan(osc_hz=27e6, clock_hz=mhz * 1e6, update_hz=16e3, baud=3e6), pll


PLANS = [_plan(48, gowin_rpll("gw1n", 27.0, 8, 15, 16)),
         _plan(54, gowin_rpll("gw1n", 27.0, 0, 1, 16)),
         _plan(72, gowin_rpll("gw1n", 27.0, 2, 7, 8))]

TARGET = {
    "name": "tang_nano_9k",
    "description": "Sipeed Tang Nano 9K, Gowin GW1NR-9 C6/I5: bitstream (yosys, "
                   "nextpnr-himbaechel, gowin_pack)",
    "family": "gowin", "device": "GW1NR-LV9QN88PC6/I5",
    "platform": platform,
    "clock_plan": PLANS[0][0], "pll": PLANS[0][1],
    "clock_plans": PLANS, "pll_clocks": [p.clock_hz for p, _ in PLANS],
    # GW1NR-9: 8640 LUT4, 6480 flip-flops, 26 BSRAM of 18 Kbit, 20 18x18 multipliers
    "resources": {"LUT": 8640, "FF": 6480, "BRAM": 26, "DSP": 20},
    "bram_shapes": [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    "lutram_bits": 64, "dsp_width": 18,
    # board-build fmax bound (MHz) for the sizing: the 1000-neuron build at 48 MHz, seed 1 (measured; the largest build's three seeds are in benchmarks/boards.md)
    "link_fmax_mhz": 57.3,
    "default_neurons": 2500,
    "nextpnr_cells": {"LUT": "LUT4", "ALU": "ALU", "FF": "DFF", "BRAM": "BSRAM", "DSP": "MULT18X18"},
    "nextpnr_freq": True,
    "uart": "the BL702's USB serial port (pins 17 tx, 18 rx)",
    "bitstream": True, "loader_board": "tangnano9k", "bitstream_ext": "fs",
}
