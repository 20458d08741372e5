"""ButterStick r1.0 (Lattice ECP5 LFE5UM5G-85F-8BG381): bitstream with yosys, nextpnr-ecp5 and
ecppack.

UART: the board has no USB-serial chip (its USB port is a ULPI PHY for the bootloader): the host
needs a 3.3 V USB-UART adapter on SYZYGY port 0, single-ended pins S0 (FPGA G2, the board's TX)
and S1 (FPGA J3, the board's RX). The SYZYGY banks are powered by buck converters whose output
the FPGA sets through sigma-delta outputs (``vccio_ctrl``): :class:`VccioControl` holds all
three at 3.3 V and enables the converters 4 RC time constants after configuration. No status
LED is driven (the board's LEDs are a multiplexed RGB matrix). Clock plans: the 30 MHz
oscillator through an ``EHXPLLL``: 60 MHz (30 x 2, VCO 600 MHz; 3750 cycles per 16 kHz sweep,
20 clocks per bit at 3 Mbaud), 80 MHz (30 / 3 x 8, VCO 640 MHz; 5000 cycles, the line at
2 Mbaud, 40 clocks) and 90 MHz (30 x 3, VCO 540 MHz; 5625 cycles, 30 clocks at 3 Mbaud).
"""

from __future__ import annotations

import math

from amaranth import Elaboratable, Module, Signal
from amaranth.lib import io, wiring
from amaranth.lib.wiring import Out

from .pll import ecp5_pll
from .top import open_flow_target, oscillator_plans

__all__ = ["TARGET", "VccioControl", "VccioLogic", "vccio_duty", "BUTTERSTICK_IO"]

#: the SYZYGY regulators' feedback network (ButterStick r1.0 schematic, as amaranth-boards
#: documents it): feedback reference (V), injection, feedback and set resistors (ohm), and the
#: DAC's RC filter (68 kOhm, 100 nF)
VFB, RI, RF, RS, RC_S = 0.6, 68_000.0, 53_600.0, 13_000.0, 68_000.0 * 0.1e-6
#: the sigma-delta's output swing (V)
VDAC = 3.3


def vccio_duty(vccio: float) -> float:
    """The sigma-delta duty that holds a SYZYGY bank at ``vccio`` volts: the regulator keeps its
    feedback node at VFB, so the current the DAC injects through RI sets how much of the set
    resistor's current flows through RF."""
    vctl = VFB * (1 + RI / RF) + RI * VFB / RS - (RI / RF) * vccio
    if not 0 < vctl < VDAC:
        raise ValueError(f"{vccio} V needs a control voltage of {vctl:.3f} V, outside the DAC")
    return vctl / VDAC


class VccioLogic(wiring.Component):
    """The logic of :class:`VccioControl` without the pins (``sync`` domain): ``pdm``, three
    first-order sigma-delta outputs at :func:`vccio_duty` of ``vccio``, and ``en``, raised
    ``4 RC + 1 ms`` after the domain leaves reset (also the LiteX SoC's,
    :mod:`~cuneate.boards.litex_soc`)."""

    def __init__(self, clock_hz: float, vccio: float = 3.3):
        self.clock_hz, self.vccio = clock_hz, vccio
        super().__init__({"pdm": Out(3), "en": Out(1)})

    def elaborate(self, platform):
        m = Module()
        bits = 10
        step = round(vccio_duty(self.vccio) * (1 << bits))
        boot = int(self.clock_hz * (4 * RC_S + 1e-3))
        for i in range(3):
            acc = Signal(bits + 1, name=f"sd{i}")
            m.d.sync += acc.eq(acc[:bits] + step)
            m.d.comb += self.pdm[i].eq(acc[bits])
        count = Signal(range(boot + 1))
        with m.If(count < boot):
            m.d.sync += count.eq(count + 1)
        m.d.comb += self.en.eq(count == boot)
        return m


class VccioControl(Elaboratable):
    """:class:`VccioLogic` on the board's ``vccio_ctrl`` pins."""

    def __init__(self, pins, clock_hz: float, vccio: float = 3.3):
        self.pins, self.clock_hz, self.vccio = pins, clock_hz, vccio

    def elaborate(self, platform):
        m = Module()
        m.submodules.logic = logic = VccioLogic(self.clock_hz, self.vccio)
        m.submodules.pdm = pdm = io.Buffer("o", self.pins.pdm)
        m.submodules.en = en = io.Buffer("o", self.pins.en)
        m.d.comb += [pdm.o.eq(logic.pdm), en.o.eq(logic.en)]
        return m


def _with_vccio(pll, clock_hz):
    def build(m, platform):
        clk, locked = pll(m, platform)
        m.submodules.vccio = VccioControl(platform.request("vccio_ctrl", 0, dir="-"), clock_hz)
        return clk, locked
    build.plan = pll.plan
    return build


#: the pins a LiteX SoC takes (amaranth-boards' file and the adapter's pins above): the 30 MHz
#: oscillator, the UART on SYZYGY 0, the SYZYGY regulators' control
BUTTERSTICK_IO = {"clk30": "B12", "serial_tx": "G2", "serial_rx": "J3",
                  "vccio_pdm": "V1 E11 T2", "vccio_en": "E12"}


def platform():
    from amaranth.build import Attrs
    from amaranth_boards.butterstick import ButterStickPlatform
    from amaranth_boards.resources import UARTResource
    p = ButterStickPlatform()
    pins = BUTTERSTICK_IO
    p.add_resources([UARTResource(0, tx=pins["serial_tx"], rx=pins["serial_rx"],
                                  attrs=Attrs(IO_TYPE="LVCMOS33", PULLMODE="UP"))])
    return p


PLANS = oscillator_plans(30.0, (60, 3e6, _with_vccio(ecp5_pll(30.0, 1, 2, 10), 60e6)),
                         (80, 2e6, _with_vccio(ecp5_pll(30.0, 3, 8, 8), 80e6)),
                         (90, 3e6, _with_vccio(ecp5_pll(30.0, 1, 3, 6), 90e6)))

TARGET = open_flow_target(
    "butterstick", "ButterStick r1.0, Lattice ECP5 LFE5UM5G-85F speed grade 8: bitstream "
    "(yosys, nextpnr-ecp5, ecppack); UART through an adapter on SYZYGY 0", "ecp5",
    "LFE5UM5G-85F-8BG381C", platform, PLANS, {"LUT": 83640, "FF": 83640, "BRAM": 208, "DSP": 156},
    # board-build fmax bound (MHz) for the sizing: the largest build's (10 cores of 4096 at
    # 80 MHz), lowest of seeds 1-3 (benchmarks/boards.md)
    link_fmax_mhz=126.58, status_leds=0, loader_board=None,
    uart="no USB-serial on the board: a 3.3 V USB-UART adapter on SYZYGY port 0, S0 (FPGA "
         "G2, out) and S1 (FPGA J3, in); the board's gateware powers the bank at 3.3 V")
