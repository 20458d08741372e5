"""ULX3S (Lattice ECP5, LFE5U-85F/25F, speed grade 6): the main target, bitstream with the
open toolchain (yosys, nextpnr-ecp5, ecppack).

Clock plan: the 25 MHz oscillator through an EHXPLLL to 60 MHz (25 / 5 * 12, VCO 600 MHz,
phase detector at 5 MHz). 60 MHz is the nearest plan with integer ratios for both the sweep and
a UART rate the FT231X can produce: 3750 cycles per 16 kHz sweep (up to 3750 neurons) and 20
clocks per bit at 3 Mbaud. (48 MHz, which would give 3000 cycles and 16 clocks per bit, needs
an input divider of 25, below the PLL's 3.125 MHz phase-detector minimum.)

A second plan, 70 MHz (25 / 5 * 14, VCO 560 MHz), gives 4375 cycles per sweep (cores of 4096,
the 2048 x 9 block shape's depth: 10 of them, 40 960 neurons, fill the block RAM); 3 Mbaud
would be 23.3 clocks a bit, so its line runs at 2 Mbaud (35 clocks). A third, 90 MHz (25 / 5 *
18, VCO 540 MHz), gives 5625 cycles per sweep and 30 clocks per bit at 3 Mbaud: the sizing
takes a plan when the measured fmax allows (the core's out of context on the LFE5U-85F -6,
lowest of three placement seeds, and the filled board build's, less the sizing's 10 %
margin). The filled device rules 90 MHz out: the 40 960-neuron build reaches 80.8 MHz at its
lowest placement seed.
"""

from __future__ import annotations

from .pll import ecp5_pll
from .top import open_flow_target, oscillator_plans

__all__ = ["TARGET", "PLANS"]


def platform(device: str = "85F"):
    from amaranth_boards import ulx3s
    return {"12F": ulx3s.ULX3S_12F_Platform, "25F": ulx3s.ULX3S_25F_Platform,
            "45F": ulx3s.ULX3S_45F_Platform, "85F": ulx3s.ULX3S_85F_Platform}[device]()


#: 25 MHz / 5 x 14 (VCO 560 MHz): 4375 cycles per sweep; 3 Mbaud would be 23.3 clocks a bit, so
#: the 70 MHz plan's line runs at 2 Mbaud (35 clocks)
PLANS = oscillator_plans(25.0, (60, 3e6, ecp5_pll(25.0, 5, 12, 10)),
                         (70, 2e6, ecp5_pll(25.0, 5, 14, 8)), (90, 3e6, ecp5_pll(25.0, 5, 18, 6)))

TARGET = open_flow_target(
    "ulx3s", "ULX3S, Lattice ECP5 LFE5U-85F speed grade 6: bitstream (yosys, nextpnr-ecp5, "
    "ecppack)", "ecp5", "LFE5U-85F-6BG381C", platform, PLANS,
    # device resources for sizing and percentages (LFE5U-85F)
    {"LUT": 83640, "FF": 83640, "BRAM": 208, "DSP": 156},
    uart_tx_enable=True, loader_board="ulx3s",
    # fmax (MHz) of one core by pipeline depth: out of context with its block-RAM and
    # multiplier registers packed, lowest of seeds 1-3 (docs/architecture.md); the
    # TRELLIS_COMB cells of one core and of the link
    fmax_mhz={5: 109.4, 8: 134.6, 9: 163.4},
    # the fmax of a filled board build (the link and 10 cores of 4096 at depth 5, 194 of 208
    # block RAMs, lowest of seeds 1-3): the bound for any build, since the out-of-context core
    # fmax above does not see the block RAMs spread over the filled device
    link_fmax_mhz=80.8, logic_per_core=1900, logic_link=3000)
