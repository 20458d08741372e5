"""Digilent Atlys (Xilinx Spartan-6 LX45, the reference device): a Verilog-plus-estimate target
(the ISE flow is the vendor's). ``cuneate build atlys`` writes its Verilog and the sizing
estimate; the refusals name the limit the device sets."""

from __future__ import annotations

from .top import ClockPlan

__all__ = ["TARGET"]

TARGET = {
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
