"""Digilent Arty A7-35T (Xilinx Artix-7): a Verilog-plus-estimate target (the Vivado flow is
the vendor's). ``cuneate build arty`` writes its Verilog and the sizing estimate; the refusals
name the limit the device sets."""

from __future__ import annotations

from .top import xilinx_estimate_target

__all__ = ["TARGET"]

TARGET = xilinx_estimate_target(
    "arty", "Digilent Arty A7-35T, Xilinx Artix-7: Verilog and estimate (Vivado flow)",
    "artix7", "XC7A35TICSG324-1L",
    resources={"LUT": 20800, "FF": 41600, "BRAM": 100, "DSP": 90},
    bram_shapes=[(32768, 1), (16384, 2), (8192, 4), (4096, 9), (2048, 18), (1024, 36)],
    synth_family="xc7", bram_cells={"RAMB36E1": 2, "RAMB18E1": 1})
