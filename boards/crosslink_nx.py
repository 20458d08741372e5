"""Lattice CrossLink-NX Evaluation Board (LIFCL-40-9BG400C, Nexus): bitstream with yosys
``synth_nexus``, nextpnr-nexus and prjoxide (all from PyPI). amaranth-boards has no board file
for it: the platform here states the pins this design uses (Lattice's EVN user guide,
FPGA-EB-02036; the same pins as LiteX-boards' ``lattice_crosslink_nx_evn`` and prjoxide's EVN
examples).

Two steps differ from the other open flows. yosys 0.70's ``synth_nexus`` ties the first carry
input of a chain to a ``VLO`` cell, which nextpnr-nexus refuses ("CIN net driven by non-CCU2
cell"): :mod:`cuneate.hdl.flow.nexus_carry` runs between yosys and nextpnr and disconnects it (a
chain root's carry-in is zero). The board clock's pad (L13) reaches its global buffer (DCC)
through general routing, an arc nextpnr-nexus 0.11's default router (router2) gives up on once
a core is placed ("Failed to route arc ... JPADDI_SEIO33_CORE_IOA to ... JCLKI_DCC"); router1
routes it, so this board's builds pass ``--router router1``.

UART: the FT2232H's second channel (the board's USB port), FPGA F18 (tx) and F16 (rx). As the
board ships, that channel is not wired to the FPGA: 0-ohm resistors on R15 and R17 connect it,
and the FT2232H's port B must be set to UART (virtual COM port) in its EEPROM.

Clock plan: the FT2232H's 12 MHz clock (L13, with jumper JP2 fitted) straight to the cores:
750 cycles per 16 kHz sweep, 8 clocks per bit at 1.5 Mbaud. No PLL: the Nexus PLL needs a
reference of at least 18 MHz (CrossLink-NX data sheet), the board's other clock (125 MHz,
LVDS, C12) is not a fabric input pin in nextpnr-nexus's device database, and the internal
oscillator (450 MHz, +-7 %) is too loose for a UART. At 12 MHz each core holds 734 neurons;
the device holds as many cores as its block RAMs and multipliers allow. Running, overflow and
clamp on LEDs D5-D7 (E17, F13, G13; active low).
"""

from __future__ import annotations

import sys

from .pll import direct
from .top import open_flow_target, oscillator_plans

__all__ = ["TARGET", "platform"]

_CARRY_FIX = r"""
{{invoke_tool("python")}} -m cuneate.hdl.flow.nexus_carry {{name}}.json
"""


def platform():
    from amaranth.build import Attrs, Clock, Pins, Resource
    from amaranth.vendor import LatticePlatform
    from amaranth_boards.resources import LEDResources, UARTResource

    class CrossLinkNXEvnPlatform(LatticePlatform):
        device, package, speed = "LIFCL-40", "BG400", "9"
        default_clk = "clk12"
        resources = [
            Resource("clk12", 0, Pins("L13", dir="i"), Clock(12e6),
                     Attrs(IO_TYPE="LVCMOS33")),
            UARTResource(0, rx="F16", tx="F18", attrs=Attrs(IO_TYPE="LVCMOS33")),
            *LEDResources(pins="E17 F13 G13 F14 L16 L15 L20 L19", invert=True,
                          attrs=Attrs(IO_TYPE="LVCMOS33")),
        ]
        connectors = []

        @property
        def required_tools(self):
            return super().required_tools + ["python"]

        @property
        def command_templates(self):
            yosys, *rest = super().command_templates
            return [yosys, _CARRY_FIX, *rest]
    return CrossLinkNXEvnPlatform()


# LIFCL-40: 39600 LUT4 and flip-flops, 84 EBR of 18 Kbit, 56 18x18 multipliers (the two
# 512 Kbit LRAMs are not counted by the sizing)
TARGET = open_flow_target(
    "crosslink_nx", "Lattice CrossLink-NX Evaluation Board, LIFCL-40-9BG400C: bitstream "
    "(nextpnr-nexus with router1, prjoxide), cores of 734 at 12 MHz", "nexus",
    "LIFCL-40-9BG400C", platform, oscillator_plans(12.0, (12, 1.5e6, direct())),
    {"LUT": 39600, "FF": 39600, "BRAM": 84, "DSP": 56},
    default_neurons=734, tool_env={"PYTHON": sys.executable}, loader_board=None,
    uart="the FT2232H's port B (the board's USB port) on F18 (out) and F16 (in), once R15 "
         "and R17 are fitted and port B is set to UART",
    # router2 finds no path from the clock's pad to its DCC (the module's text)
    nextpnr_extra="--router router1",
    # board-build fmax (MHz): the largest build's (11 cores of 734 at 12 MHz), lowest of seeds
    # 1-3 (benchmarks/boards.md); one plan, so it bounds no choice
    link_fmax_mhz=140.77)
