"""OrangeCrab r0.2 (Lattice ECP5 LFE5U-25F-8MG285): bitstream with yosys, nextpnr-ecp5 and
ecppack (amaranth-boards' DFU suffix step dropped: ``openFPGALoader -b orangecrab`` loads the
plain ``.bit`` through the board's DFU bootloader).

UART: the board has no USB-serial chip (its USB port goes to the FPGA): the host needs a 3.3 V
USB-UART adapter on the Feather header, the pins labelled TX (FPGA M18, the board's output) and
RX (FPGA N17), and GND. Clock plans: the 48 MHz oscillator through an ``EHXPLLL``: 60 MHz (48 /
4 x 5, VCO 600 MHz; 3750 cycles per 16 kHz sweep, 20 clocks per bit at 3 Mbaud), 72 MHz (48 /
2 x 3, VCO 576 MHz; 4500 cycles, 24 clocks a bit) and 96 MHz (48 x 2, VCO 576 MHz; 6000
cycles, 32 clocks a bit). Running, overflow and clamp on the RGB LED's red, green and blue.
"""

from __future__ import annotations

from .pll import ecp5_pll
from .top import ClockPlan

__all__ = ["TARGET"]


def platform():
    from amaranth.build import Attrs
    from amaranth_boards.orangecrab_r0_2 import OrangeCrabR0_2_25FPlatform
    from amaranth_boards.resources import LEDResources, UARTResource
    from .platforms import without_commands
    p = without_commands(OrangeCrabR0_2_25FPlatform, ("dfu-suffix",))()
    p.add_resources([
        UARTResource(0, rx="N17", tx="M18", attrs=Attrs(IO_TYPE="LVCMOS33", PULLMODE="UP")),
        *LEDResources(pins="K4 M3 J3", invert=True, attrs=Attrs(IO_TYPE="LVCMOS33"))])
    return p


def _plan(mhz, pll):
    return ClockPlan(osc_hz=48e6, clock_hz=mhz * 1e6, update_hz=16e3, baud=3e6), pll


PLANS = [_plan(60, ecp5_pll(48.0, 4, 5, 10)), _plan(72, ecp5_pll(48.0, 2, 3, 8)),
         _plan(96, ecp5_pll(48.0, 1, 2, 6))]

TARGET = {
    "name": "orangecrab",
    "description": "OrangeCrab r0.2, Lattice ECP5 LFE5U-25F speed grade 8: bitstream (yosys, "
                   "nextpnr-ecp5, ecppack); UART through an adapter on the Feather header",
    "family": "ecp5", "device": "LFE5U-25F-8MG285C",
    "platform": platform,
    "clock_plan": PLANS[0][0], "pll": PLANS[0][1],
    "clock_plans": PLANS, "pll_clocks": [p.clock_hz for p, _ in PLANS],
    "resources": {"LUT": 24288, "FF": 24288, "BRAM": 56, "DSP": 28},
    "bram_shapes": [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    "lutram_bits": 512, "dsp_width": 18,
    # board-build fmax bound (MHz) for the sizing: provisional: the ULX3S's filled board build (ECP5 speed grade 6; this board is grade 8) until this board's largest build is measured
    "link_fmax_mhz": 80.8,
    "default_neurons": 2500,
    "nextpnr_cells": {"LUT": "TRELLIS_COMB", "FF": "TRELLIS_FF", "BRAM": "DP16KD",
                      "DSP": "MULT18X18D"},
    "uart": "no USB-serial on the board: a 3.3 V USB-UART adapter on the Feather header's TX "
            "(FPGA M18, out) and RX (FPGA N17, in) pins",
    "bitstream": True, "loader_board": "orangecrab", "bitstream_ext": "bit",
}
