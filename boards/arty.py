"""Digilent Arty A7-35T (Xilinx Artix-7): a Verilog-plus-estimate target (the Vivado flow is
the vendor's). ``cuneate build arty`` writes its Verilog and the sizing estimate; the refusals
name the limit the device sets."""

from __future__ import annotations

from .top import ClockPlan

__all__ = ["TARGET"]

TARGET = {
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
