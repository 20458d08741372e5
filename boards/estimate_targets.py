"""Targets sized here but not yet built by ``cuneate build`` with the open toolchain: the
iCEBreaker (iCE40UP5K) and the Verilog-plus-estimate boards, Atlys (Spartan-6 LX45, the
reference device; ISE flow) and Arty A7-35T (Vivado). ``cuneate build`` writes their Verilog
and the sizing estimate; the refusals name the limit the device sets."""

from __future__ import annotations

from .top import ClockPlan

__all__ = ["ICEBREAKER", "ATLYS", "ARTY"]

ICEBREAKER = {
    "name": "icebreaker",
    "description": "iCEBreaker, Lattice iCE40UP5K: Verilog and estimate (bitstream flow not "
                   "yet wired; the default core does not fit)",
    "family": "ice40", "device": "iCE40UP5K-SG48",
    # 12 MHz oscillator -> 24 MHz: 1500 cycles per 16 kHz sweep, 8 clocks per bit at 3 Mbaud
    "clock_plan": ClockPlan(osc_hz=12e6, clock_hz=24e6, update_hz=16e3, baud=3e6),
    "pll_clocks": [24e6],
    "resources": {"LUT": 5280, "FF": 5280, "BRAM": 30, "DSP": 8},
    "bram_shapes": [(256, 16), (512, 8), (1024, 4), (2048, 2)],
    "lutram_bits": 0, "dsp_width": 16,
    "default_neurons": 1000,
    "core_defaults": {"operand_width": 16},
    "bitstream": False,
}

ATLYS = {
    "name": "atlys",
    "description": "Digilent Atlys, Xilinx Spartan-6 LX45 (reference device): Verilog and "
                   "estimate (ISE flow)",
    "family": "spartan6", "device": "XC6SLX45-3CSG324",
    # 100 MHz oscillator -> 40 MHz DCM: 2500 cycles per sweep, 20 clocks per bit at 2 Mbaud
    "clock_plan": ClockPlan(osc_hz=100e6, clock_hz=40e6, update_hz=16e3, baud=2e6),
    "pll_clocks": [40e6],
    "resources": {"LUT": 27288, "FF": 54576, "BRAM": 116, "DSP": 58},
    "bram_shapes": [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    "lutram_bits": 512, "dsp_width": 18,
    "default_neurons": 2400,
    "bitstream": False,
}

ARTY = {
    "name": "arty",
    "description": "Digilent Arty A7-35T, Xilinx Artix-7: Verilog and estimate (Vivado flow)",
    "family": "artix7", "device": "XC7A35TICSG324-1L",
    "clock_plan": ClockPlan(osc_hz=100e6, clock_hz=40e6, update_hz=16e3, baud=2e6),
    "pll_clocks": [40e6],
    "resources": {"LUT": 20800, "FF": 41600, "BRAM": 100, "DSP": 90},
    "bram_shapes": [(32768, 1), (16384, 2), (8192, 4), (4096, 9), (2048, 18), (1024, 36)],
    "lutram_bits": 512, "dsp_width": 18,
    "default_neurons": 2400,
    "bitstream": False,
}
