"""TUL PYNQ-Z2 (Xilinx Zynq-7020, XC7Z020-1CLG400C): as the Arty Z7-20
(:mod:`~cuneate.boards.arty_z7`), the block behind the AXI face as Vivado IP, its block design
with the PS and an AXI DMA, the PYNQ driver and a yosys estimate. Vivado's board file
``tul.com.tw:pynq-z2:part0:1.0`` (TUL's) gives the PS its DDR and MIO preset when installed.
"""

from __future__ import annotations

from .zynq import zynq7020_target

__all__ = ["TARGET"]

TARGET = zynq7020_target(
    "pynq_z2", "TUL PYNQ-Z2, Xilinx Zynq-7020: Vivado IP, block design, PYNQ driver and "
    "yosys estimate", "tul.com.tw:pynq-z2:part0:1.0")
