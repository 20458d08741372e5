"""Digilent Arty A7-35T (Xilinx Artix-7 XC7A35TICSG324-1L): a Vivado-ready project and a yosys
estimate (no open place and route for the 7 series on PyPI). ``cuneate build arty`` writes the
board top's Verilog, its XDC (from amaranth-boards' Arty A7 file), amaranth's Vivado build TCL
and the ``synth_xilinx`` utilization; the refusals name the limit the device sets.

UART: the board's FT2232HQ (USB-serial on its USB port), FPGA D10 (tx) and A9 (rx). Clock
plan: the 100 MHz oscillator (E3) through an ``MMCME2_BASE`` (x 10, VCO 1000 MHz, / 25) to
40 MHz: 2500 cycles per 16 kHz sweep, 20 clocks per bit at 2 Mbaud. Running, overflow and
clamp on LD4-LD6.
"""

from __future__ import annotations

from .platforms import amaranth_board
from .pll import xilinx_mmcm
from .top import xilinx_estimate_target

__all__ = ["TARGET", "artix7_target", "ARTIX7_100T"]

ARTIX7_SHAPES = [(32768, 1), (16384, 2), (8192, 4), (4096, 9), (2048, 18), (1024, 36)]
#: the XC7A100T's resources (BRAM in 18 Kbit blocks)
ARTIX7_100T = {"LUT": 63400, "FF": 126800, "BRAM": 270, "DSP": 240}


def artix7_target(name: str, description: str, device: str, resources: dict, platform,
                  uart: str) -> dict:
    """An Artix-7 board with its 100 MHz oscillator (a Vivado project and a yosys estimate)."""
    return xilinx_estimate_target(
        name, description, "artix7", device, resources=resources, bram_shapes=ARTIX7_SHAPES,
        synth_family="xc7", bram_cells={"RAMB36E1": 2, "RAMB18E1": 1}, platform=platform,
        pll=xilinx_mmcm(100.0, 1, 10, 25), uart=uart)


TARGET = artix7_target(
    "arty", "Digilent Arty A7-35T, Xilinx Artix-7: Vivado project and yosys estimate",
    "XC7A35TICSG324-1L", {"LUT": 20800, "FF": 41600, "BRAM": 100, "DSP": 90},
    amaranth_board("arty_a7", "ArtyA7_35Platform"),
    "the board's FT2232HQ USB-serial (D10 out, A9 in)")
