"""Board top: PLL clock, the blocks behind the UART host link, status LEDs.

A target (one file per board in this package) supplies the platform, its oscillator and a
:class:`ClockPlan`: the PLL output frequency, chosen so that the cycles per sweep
(``clock_hz / update_hz``) are an integer and the UART divider (``clock_hz / baud``, rounded)
within :data:`MAX_BAUD_ERROR` of the rate asked for (the boards' default rates are exact). The top
holds the core in reset until the PLL locks.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.build import ResourceError
from amaranth.lib import io
from amaranth import ClockDomain, ClockSignal, Elaboratable, Module, ResetSignal

from ..hdl.izhikevich.config import ConfigError
from ..hdl.link import LinkedTop

__all__ = ["xilinx_estimate_target", "open_flow_target", "oscillator_plans", "ClockPlan",
           "BoardTop", "MAX_BAUD_ERROR", "BRAM18_SHAPES"]


#: the largest relative error of a board's line rate against the rate asked for (the UART
#: samples mid-bit: the two ends' errors together must stay well inside half a bit over a
#: 10-bit character; the FT231X adds its own)
MAX_BAUD_ERROR = 0.01
#: the fewest clocks a UART bit may take (:class:`~cuneate.hdl.lib.uart.UartRx` samples mid-bit)
MIN_CLOCKS_PER_BIT = 4


@dataclass(frozen=True)
class ClockPlan:
    """Oscillator, PLL output and the integer ratios the design depends on."""

    osc_hz: float
    clock_hz: float
    update_hz: float
    baud: float

    def __post_init__(self):
        ratio = self.clock_hz / self.update_hz
        if abs(ratio - round(ratio)) > 1e-9:
            raise ConfigError(f"{self.clock_hz / 1e6:g} MHz gives {ratio:g} cycles per sweep: "
                              f"not an integer")
        if self.clocks_per_bit < MIN_CLOCKS_PER_BIT:
            raise ConfigError(f"{self.clock_hz / 1e6:g} MHz gives {self.clock_hz / self.baud:g} "
                              f"clocks per bit at {self.baud:g} baud: the UART needs at least "
                              f"{MIN_CLOCKS_PER_BIT} (baud limit)")
        if self.baud_error > MAX_BAUD_ERROR:
            raise ConfigError(f"{self.clock_hz / 1e6:g} MHz gives {self.clock_hz / self.baud:g} "
                              f"clocks per bit at {self.baud:g} baud: {self.clocks_per_bit} "
                              f"clocks are {100 * self.baud_error:.2f} % off, more than a UART's "
                              f"{100 * MAX_BAUD_ERROR:g} % (baud limit)")

    @property
    def baud_error(self) -> float:
        """The relative error of the line rate the whole clocks per bit give."""
        return abs(self.line_baud - self.baud) / self.baud

    @property
    def line_baud(self) -> float:
        """The line rate the board runs: the clock over the whole clocks per bit."""
        return self.clock_hz / max(self.clocks_per_bit, 1)

    @property
    def cycles_per_tick(self) -> int:
        return int(round(self.clock_hz / self.update_hz))

    @property
    def clocks_per_bit(self) -> int:
        return int(round(self.clock_hz / self.baud))


class BoardTop(Elaboratable):
    """``pll(m, platform) -> (clk, locked)`` builds the board's PLL; the rest is common:
    the block behind the UART face (:class:`~cuneate.hdl.link.LinkedTop` of the link
    configuration ``lcfg``), its pins on the board's UART, ``running``, ``overflow`` and
    ``clamped`` on three LEDs (as many as the board has, at most ``status_leds``: a board
    whose LED pins carry the UART has none)."""

    def __init__(self, lcfg, pll, uart_tx_enable: bool = False,
                 status_leds: int | None = None):
        self.linked = LinkedTop(lcfg)
        self.pll = pll
        self.uart_tx_enable = uart_tx_enable
        self.status_leds = status_leds

    def elaborate(self, platform):
        m = Module()
        clk, locked = self.pll(m, platform)
        m.domains.sync = ClockDomain("sync")
        m.d.comb += [ClockSignal("sync").eq(clk), ResetSignal("sync").eq(~locked)]
        m.submodules.linked = linked = self.linked
        res = platform.lookup("uart", 0)
        uart = platform.request("uart", 0, dir={sub.name: "-" for sub in res.ios})
        m.submodules.uart_rx = rx = io.Buffer("i", uart.rx)
        m.submodules.uart_tx = tx = io.Buffer("o", uart.tx)
        m.d.comb += [linked.rx.eq(rx.i), tx.o.eq(linked.tx)]
        if self.uart_tx_enable:
            m.submodules.uart_en = en = io.Buffer("o", platform.request("uart_tx_enable", 0,
                                                                         dir="-"))
            m.d.comb += en.o.eq(1)
        leds = [linked.running, linked.overflow, linked.clamped]
        n_leds = _led_count(platform)
        if self.status_leds is not None:
            n_leds = min(n_leds, self.status_leds)
        for i, sig in enumerate(leds[:n_leds]):
            m.submodules[f"led{i}"] = led = io.Buffer("o", platform.request("led", i, dir="-"))
            m.d.comb += led.o.eq(sig)
        return m


def _led_count(platform) -> int:
    """The LEDs ``platform`` names (``led`` 0, 1, ...)."""
    n = 0
    while True:
        try:
            platform.lookup("led", n)
        except ResourceError:
            return n
        n += 1


#: the aspect ratios of an 18 Kbit block RAM (ECP5 DP16KD, Gowin BSRAM, Nexus EBR, Spartan-6)
BRAM18_SHAPES = [(16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36)]

#: what a family's open flow (yosys, nextpnr) fixes: LUT RAM bits, multiplier width, nextpnr's
#: cell names for the build report, and whether nextpnr takes the clock as ``--freq``
_OPEN_FAMILIES = {
    "ecp5": {"lutram_bits": 512, "dsp_width": 18,
             "nextpnr_cells": {"LUT": "TRELLIS_COMB", "FF": "TRELLIS_FF", "BRAM": "DP16KD",
                               "DSP": "MULT18X18D"}},
    "gowin": {"lutram_bits": 64, "dsp_width": 18, "nextpnr_freq": True, "bitstream_ext": "fs",
              "nextpnr_cells": {"LUT": "LUT4", "ALU": "ALU", "FF": "DFF", "BRAM": "BSRAM",
                                "DSP": "MULT18X18"}},
    # a logic cell holds a LUT4 and a flip-flop: the netlist's counts of each, of the LCs
    "ice40": {"lutram_bits": 0, "dsp_width": 16, "bitstream_ext": "bin",
              "bram_shapes": [(256, 16), (512, 8), (1024, 4), (2048, 2)],
              "nextpnr_cells": {"LC": "ICESTORM_LC", "BRAM": "ICESTORM_RAM",
                                "DSP": "ICESTORM_DSP"},
              "netlist_cells": {"per": "ICESTORM_LC",
                                "count": {"LUT": "SB_LUT4", "FF": "SB_DFF"}}},
    "nexus": {"lutram_bits": 64, "dsp_width": 18,
              "nextpnr_cells": {"LUT": "OXIDE_COMB", "FF": "OXIDE_FF", "BRAM": "OXIDE_EBR",
                                "DSP": "MULT18_CORE"}},
}


def oscillator_plans(osc_mhz: float, *plans) -> list:
    """``(ClockPlan, pll)`` pairs from ``(clock_mhz, baud, pll)`` triples: an oscillator of
    ``osc_mhz`` and a 16 kHz sweep."""
    return [(ClockPlan(osc_hz=osc_mhz * 1e6, clock_hz=mhz * 1e6, update_hz=16e3, baud=baud), pll)
            for mhz, baud, pll in plans]


def open_flow_target(name: str, description: str, family: str, device: str, platform,
                     plans: list, resources: dict, **options) -> dict:
    """A target built by the open flow of ``family`` (:data:`_OPEN_FAMILIES`): ``plans`` its
    :func:`oscillator_plans`, the first the default; 18 Kbit block RAMs and a ``.bit``
    bitstream unless the family states its own, 2500 neurons by default; ``options`` add to or
    override any of these."""
    t = {"name": name, "description": description, "family": family, "device": device,
         "platform": platform, "clock_plan": plans[0][0], "pll": plans[0][1],
         "clock_plans": plans, "pll_clocks": [p.clock_hz for p, _ in plans],
         "resources": resources, "bram_shapes": BRAM18_SHAPES, "default_neurons": 2500,
         "bitstream": True, "bitstream_ext": "bit", **_OPEN_FAMILIES[family]}
    t.update(options)
    return t


def xilinx_estimate_target(name: str, description: str, family: str, device: str,
                           resources: dict, bram_shapes: list, synth_family: str,
                           bram_cells: dict, platform=None, pll=None, uart: str = "") -> dict:
    """A Verilog-plus-estimate target on a Xilinx device (no open bitstream flow): a 100 MHz
    oscillator, a 40 MHz core clock from the vendor's clock manager (2500 cycles per 16 kHz
    sweep, 20 clocks per bit at 2 Mbaud), 512-bit LUT RAM, 18-bit multipliers;
    ``resources`` with BRAM in 18 Kbit blocks, ``bram_cells`` the 18 Kbit blocks per cell.
    With ``platform`` (an amaranth ``XilinxPlatform``) and ``pll`` the build also writes a
    Vivado project of the board top (:mod:`~cuneate.boards.vivado`)."""
    t = {"name": name, "description": description, "family": family, "device": device,
         "clock_plan": ClockPlan(osc_hz=100e6, clock_hz=40e6, update_hz=16e3, baud=2e6),
         "pll_clocks": [40e6], "resources": resources, "bram_shapes": bram_shapes,
         "lutram_bits": 512, "dsp_width": 18, "default_neurons": 2400, "bitstream": False,
         "synth_family": synth_family, "bram_cells": bram_cells}
    if platform is not None:
        t.update(platform=platform, pll=pll, vivado=True, uart=uart)
    return t
