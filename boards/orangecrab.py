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
from .top import open_flow_target, oscillator_plans

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


PLANS = oscillator_plans(48.0, (60, 3e6, ecp5_pll(48.0, 4, 5, 10)),
                         (72, 3e6, ecp5_pll(48.0, 2, 3, 8)),
                         (96, 3e6, ecp5_pll(48.0, 1, 2, 6)))

TARGET = open_flow_target(
    "orangecrab", "OrangeCrab r0.2, Lattice ECP5 LFE5U-25F speed grade 8: bitstream (yosys, "
    "nextpnr-ecp5, ecppack); UART through an adapter on the Feather header", "ecp5",
    "LFE5U-25F-8MG285C", platform, PLANS, {"LUT": 24288, "FF": 24288, "BRAM": 56, "DSP": 28},
    # board-build fmax bound (MHz) for the sizing: the largest build's (2 cores of 4608 at
    # 96 MHz), lowest of seeds 1-3 (benchmarks/boards.md)
    link_fmax_mhz=113.24, loader_board="orangecrab",
    uart="no USB-serial on the board: a 3.3 V USB-UART adapter on the Feather header's TX "
         "(FPGA M18, out) and RX (FPGA N17, in) pins")
