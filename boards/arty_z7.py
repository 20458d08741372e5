"""Digilent Arty Z7-20 (Xilinx Zynq-7020, XC7Z020-1CLG400C): the block behind the AXI face as
Vivado IP with a block design that connects it to the PS through an AXI DMA, a PYNQ-style
driver and a yosys estimate (:mod:`~cuneate.boards.zynq`; no open place and route for the 7
series). The PL clock is the PS's FCLK_CLK0 at 40 MHz; the host is the ARM cores (no UART
link). Vivado's board file ``digilentinc.com:arty-z7-20:part0:1.1`` (Digilent's board files)
gives the PS its DDR and MIO preset when installed.
"""

from __future__ import annotations

from .zynq import zynq7020_target

__all__ = ["TARGET"]

TARGET = zynq7020_target(
    "arty_z7", "Digilent Arty Z7-20, Xilinx Zynq-7020: Vivado IP, block design, PYNQ driver "
    "and yosys estimate", "digilentinc.com:arty-z7-20:part0:1.1")
