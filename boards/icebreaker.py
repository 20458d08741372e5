"""iCEBreaker (Lattice iCE40UP5K): bitstream with yosys (``synth_ice40 -dsp``), nextpnr-ice40
and icepack, for a core sized to the device: 16-bit multiplier operands (one SB_MAC16 per
product), 16-bit saturating link counters, 734 neurons by default (the largest the sizing
accepts) at 12 MHz straight from the oscillator (750 cycles per 16 kHz sweep; 8 clocks per bit
at 1.5 Mbaud). The measured fmax of
this datapath on the UP5K (about 15 MHz) rules out the 24 MHz PLL plan (``_pll``: DIVR 0,
DIVF 63, DIVQ 5) that would allow 1484 neurons.
"""

from __future__ import annotations

from amaranth import Instance, Signal

from .platforms import amaranth_board
from .pll import direct
from .top import open_flow_target, oscillator_plans

__all__ = ["TARGET"]


def _pll(m, platform):
    clk12 = platform.request(platform.default_clk, dir="-")
    clk, locked = Signal(name="pll_clk"), Signal(name="pll_locked")
    m.submodules.pll = Instance(
        "SB_PLL40_PAD",
        p_FEEDBACK_PATH="SIMPLE", p_DIVR=0, p_DIVF=63, p_DIVQ=5, p_FILTER_RANGE=1,
        i_PACKAGEPIN=clk12.io, i_RESETB=1, i_BYPASS=0,
        o_PLLOUTGLOBAL=clk, o_LOCK=locked)
    # nextpnr derives the 24 MHz constraint through the PLL (the build report checks it)
    return clk, locked


TARGET = open_flow_target(
    "icebreaker", "iCEBreaker, Lattice iCE40UP5K: bitstream (yosys, nextpnr-ice40, icepack), "
    "16-bit operands, 734 neurons at 12 MHz", "ice40", "iCE40UP5K-SG48",
    amaranth_board("icebreaker", "ICEBreakerPlatform"),
    # the 16-bit datapath places at about 15 MHz on the UP5K: the 12 MHz oscillator clocks the
    # core directly (750 cycles per 16 kHz sweep, 8 clocks per bit at 1.5 Mbaud); the 24 MHz
    # PLL plan (_pll) stays available for a faster datapath
    oscillator_plans(12.0, (12, 1.5e6, direct())), {"LUT": 5280, "FF": 5280, "BRAM": 30, "DSP": 8},
    default_neurons=734, core_defaults={"operand_width": 16},
    # 16-bit saturating error counters and a 256-byte receive FIFO: logic cells are the limit
    link_defaults={"counter_width": 16, "rx_fifo_depth": 256},
    loader_board="ice40_generic",
    prepare_opts={"synth_opts": "-dsp"})      # map the products to SB_MAC16
