"""Clock builders per FPGA family: ``builder(m, platform) -> (clk, locked)`` for
:class:`~cuneate.boards.top.BoardTop`. Each takes the board's oscillator (its platform's default
clock) and fixed dividers; the board file states the dividers of each clock plan and the test
of each board checks them against the family's ranges (:data:`RANGES`) and the plan's clock.

Families: ECP5 ``EHXPLLL`` (feedback from CLKOP: out = osc / CLKI_DIV x CLKFB_DIV, VCO = out x
CLKOP_DIV), Gowin ``rPLL`` (out = osc / (IDIV_SEL + 1) x (FBDIV_SEL + 1), VCO = out x ODIV_SEL),
Xilinx 7-series ``MMCME2_BASE`` (VCO = osc / DIVCLK_DIVIDE x CLKFBOUT_MULT_F, out = VCO
/ CLKOUT0_DIVIDE_F; Vivado only), and the oscillator straight through (:func:`direct`).
No output net carries a constraint of its own: nextpnr derives the core clock's from the
oscillator's through the dividers where it models the PLL (ECP5), the build passes the
plan's clock as nextpnr's target where it does not (Gowin: ``--freq``), and the build report
checks the derived clock against the plan's.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth import Const, Instance, Signal
from amaranth.lib import io

__all__ = ["ecp5_pll", "gowin_rpll", "xilinx_mmcm", "direct", "RANGES", "PllPlan"]

#: (low, high) in MHz of each family's phase-detector input and VCO (the vendors' data sheets:
#: Lattice FPGA-DS-02012 (ECP5); Gowin DS117 (GW1NR-9), DS102
#: (GW2A-18); Xilinx DS181 (Artix-7 -1))
RANGES = {
    "ecp5": {"pfd": (3.125, 400.0), "vco": (400.0, 800.0)},
    "gw1n": {"pfd": (3.0, 400.0), "vco": (400.0, 1200.0)},
    "gw2a": {"pfd": (3.0, 500.0), "vco": (500.0, 1250.0)},
    "xc7": {"pfd": (10.0, 450.0), "vco": (600.0, 1200.0)},
}


@dataclass(frozen=True)
class PllPlan:
    """What a PLL builder makes: its family, oscillator and output (MHz), phase-detector input
    and VCO (MHz); :meth:`check` names a value outside the family's :data:`RANGES`."""

    family: str
    osc_mhz: float
    out_mhz: float
    pfd_mhz: float
    vco_mhz: float

    def check(self) -> list[str]:
        bad = []
        for what in ("pfd", "vco"):
            lo, hi = RANGES[self.family][what]
            v = getattr(self, f"{what}_mhz")
            if not lo <= v <= hi:
                bad.append(f"{what} {v:g} MHz outside {lo:g}-{hi:g} MHz")
        return bad


def _builder(build, plan: PllPlan):
    build.plan = plan
    return build


def _osc(platform):
    return platform.request(platform.default_clk, dir="-")


def ecp5_pll(osc_mhz: float, clki_div: int, clkfb_div: int, clkop_div: int):
    """ECP5 ``EHXPLLL`` with feedback from CLKOP."""
    out = osc_mhz / clki_div * clkfb_div

    def build(m, platform):
        osc = _osc(platform)
        clk, locked = Signal(name="pll_clk"), Signal(name="pll_locked")
        m.submodules.pll = Instance(
            "EHXPLLL",
            a_FREQUENCY_PIN_CLKI=f"{osc_mhz:g}", a_FREQUENCY_PIN_CLKOP=f"{out:g}",
            a_ICP_CURRENT="12", a_LPF_RESISTOR="8", a_MFG_ENABLE_FILTEROPAMP="1",
            a_MFG_GMCREF_SEL="2",
            p_PLLRST_ENA="DISABLED", p_INTFB_WAKE="DISABLED", p_STDBY_ENABLE="DISABLED",
            p_DPHASE_SOURCE="DISABLED", p_OUTDIVIDER_MUXA="DIVA", p_OUTDIVIDER_MUXB="DIVB",
            p_OUTDIVIDER_MUXC="DIVC", p_OUTDIVIDER_MUXD="DIVD",
            p_CLKI_DIV=clki_div, p_CLKOP_ENABLE="ENABLED", p_CLKOP_DIV=clkop_div,
            p_CLKOP_CPHASE=clkop_div // 2 - 1, p_CLKOP_FPHASE=0, p_FEEDBK_PATH="CLKOP",
            p_CLKFB_DIV=clkfb_div,
            i_RST=0, i_STDBY=0, i_CLKI=osc.io, o_CLKOP=clk, i_CLKFB=clk,
            i_PHASESEL0=0, i_PHASESEL1=0, i_PHASEDIR=1, i_PHASESTEP=1, i_PHASELOADREG=1,
            i_PLLWAKESYNC=0, i_ENCLKOP=0, o_LOCK=locked)
        return clk, locked
    return _builder(build, PllPlan("ecp5", osc_mhz, out, osc_mhz / clki_div, out * clkop_div))


def gowin_rpll(family: str, osc_mhz: float, idiv_sel: int, fbdiv_sel: int, odiv_sel: int):
    """Gowin ``rPLL`` (``family`` ``gw1n`` or ``gw2a`` for the ranges); CLKOUT feeds the core."""
    out = osc_mhz / (idiv_sel + 1) * (fbdiv_sel + 1)

    def build(m, platform):
        osc = _osc(platform)
        m.submodules.osc_buf = buf = io.Buffer("i", osc)
        clk, locked = Signal(name="pll_clk"), Signal(name="pll_locked")
        m.submodules.pll = Instance(
            "rPLL",
            p_FCLKIN=f"{osc_mhz:g}", p_IDIV_SEL=idiv_sel, p_FBDIV_SEL=fbdiv_sel,
            p_ODIV_SEL=odiv_sel,
            i_CLKIN=buf.i, i_CLKFB=Const(0), i_RESET=Const(0), i_RESET_P=Const(0),
            i_FBDSEL=Const(0, 6), i_IDSEL=Const(0, 6), i_ODSEL=Const(0, 6),
            i_PSDA=Const(0, 4), i_DUTYDA=Const(0, 4), i_FDLY=Const(0, 4),
            o_CLKOUT=clk, o_LOCK=locked)
        return clk, locked
    return _builder(build, PllPlan(family, osc_mhz, out, osc_mhz / (idiv_sel + 1),
                                   out * odiv_sel))


def xilinx_mmcm(osc_mhz: float, divclk: int, mult: float, out_div: float):
    """Xilinx 7-series ``MMCME2_BASE`` through a ``BUFG`` (Vivado's flow)."""
    vco = osc_mhz / divclk * mult
    out = vco / out_div

    def build(m, platform):
        osc = _osc(platform)
        m.submodules.osc_buf = buf = io.Buffer("i", osc)
        clk, locked = Signal(name="pll_clk"), Signal(name="pll_locked")
        raw, fb = Signal(), Signal()
        m.submodules.pll = Instance(
            "MMCME2_BASE",
            p_CLKIN1_PERIOD=round(1e3 / osc_mhz, 3), p_DIVCLK_DIVIDE=divclk,
            p_CLKFBOUT_MULT_F=float(mult), p_CLKOUT0_DIVIDE_F=float(out_div),
            i_CLKIN1=buf.i, i_CLKFBIN=fb, o_CLKFBOUT=fb, i_RST=Const(0), i_PWRDWN=Const(0),
            o_CLKOUT0=raw, o_LOCKED=locked)
        m.submodules.bufg = Instance("BUFG", i_I=raw, o_O=clk)
        return clk, locked
    return _builder(build, PllPlan("xc7", osc_mhz, out, osc_mhz / divclk, vco))


def direct():
    """The oscillator straight to the core (no PLL: always locked)."""
    def build(m, platform):
        m.submodules.clk_buf = buf = io.Buffer("i", _osc(platform))
        return buf.i, Const(1)
    return _builder(build, None)
