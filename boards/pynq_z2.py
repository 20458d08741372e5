"""TUL PYNQ-Z2 (Xilinx Zynq-7020, XC7Z020-1CLG400C): as the Arty Z7-20
(:mod:`~cuneate.boards.arty_z7`), the block behind the AXI face as Vivado IP, its block design
with the PS and an AXI DMA, the PYNQ driver and a yosys estimate. Vivado's board file
``tul.com.tw:pynq-z2:part0:1.0`` (TUL's) gives the PS its DDR and MIO preset when installed.
"""

from __future__ import annotations

from .zynq import zynq_target

__all__ = ["TARGET"]

TARGET = zynq_target(
    "pynq_z2", "TUL PYNQ-Z2, Xilinx Zynq-7020: Vivado IP, block design, PYNQ driver and "
    "yosys estimate", "XC7Z020-1CLG400C", "xc7z020clg400-1",
    {"LUT": 53200, "FF": 106400, "BRAM": 280, "DSP": 220},
    "tul.com.tw:pynq-z2:part0:1.0", "FCLK_CLK0 40 MHz; AXI DMA on HP0, registers on GP0")
