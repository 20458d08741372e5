"""Digilent Atlys (Xilinx Spartan-6 LX45, the reference device): a Verilog-plus-estimate target
(the ISE flow is the vendor's). ``cuneate build atlys`` writes its Verilog and the sizing
estimate; the refusals name the limit the device sets."""

from __future__ import annotations

from .top import xilinx_estimate_target

__all__ = ["TARGET"]

TARGET = xilinx_estimate_target(
    "atlys", "Digilent Atlys, Xilinx Spartan-6 LX45 (reference device): Verilog and estimate "
             "(ISE flow)", "spartan6", "XC6SLX45-3CSG324",
    resources={"LUT": 27288, "FF": 54576, "BRAM": 116, "DSP": 58},
    bram_shapes=[(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)],
    synth_family="xc6s", bram_cells={"RAMB16BWER": 1, "RAMB8BWER": 0.5})
