"""Verilog-plus-estimate targets: Atlys (Spartan-6 LX45, the
reference device; ISE flow) and Arty A7-35T (Vivado). ``cuneate build`` writes their Verilog
and the sizing estimate; the refusals name the limit the device sets."""

from __future__ import annotations

from .top import ClockPlan

__all__ = ["ATLYS", "ARTY"]

ATLYS = {
    "name": "atlys",
    "description": "Digilent Atlys, Xilinx Spartan-6 LX45 (reference device): Verilog and "
                   "estimate (ISE flow)",
    "family": "spartan6", "device": "XC6SLX45-3CSG324",
    # 100 MHz oscillator -> 40 MHz DCM: 2500 cycles per sweep, 20 clocks per bit at 2 Mbaud
    "clock_plan": ClockPlan(osc_hz=100e6, clock_hz=40e6, update_hz=16e3, baud=2e6),
    "pll_clocks": [40e6],
    "resources": {"LUT": 27288, "FF": 54576, "BRAM": 116, "DSP": 58},  # BRAM: 18 Kbit
    "bram_shapes": [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    "lutram_bits": 512, "dsp_width": 18,
    "default_neurons": 2400,
    "bitstream": False,
    "synth_family": "xc6s",
    "bram_cells": {"RAMB16BWER": 1, "RAMB8BWER": 0.5},   # in 18 Kbit blocks
}

ARTY = {
    "name": "arty",
    "description": "Digilent Arty A7-35T, Xilinx Artix-7: Verilog and estimate (Vivado flow)",
    "family": "artix7", "device": "XC7A35TICSG324-1L",
    "clock_plan": ClockPlan(osc_hz=100e6, clock_hz=40e6, update_hz=16e3, baud=2e6),
    "pll_clocks": [40e6],
    "resources": {"LUT": 20800, "FF": 41600, "BRAM": 100, "DSP": 90},  # BRAM: 18 Kbit
    "bram_shapes": [(32768, 1), (16384, 2), (8192, 4), (4096, 9), (2048, 18), (1024, 36)],
    "lutram_bits": 512, "dsp_width": 18,
    "default_neurons": 2400,
    "bitstream": False,
    "synth_family": "xc7",
    "bram_cells": {"RAMB36E1": 2, "RAMB18E1": 1},         # in 18 Kbit blocks
}
