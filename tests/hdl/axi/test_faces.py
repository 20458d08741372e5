"""``cuneate generate BLOCK --face axi|wishbone`` (hdl/axi/faces.py): the Verilog with the standard
port names opens with its register map; the register map as JSON and markdown beside it, its
offsets and constants as the map and the configuration state them."""

import json

import pytest

from cuneate.hdl.axi.faces import write_face
from cuneate.hdl.izhikevich import IzhikevichConfig
from learning_case import small_layer

CFG = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 64, update_hz=16e3, tick_source="external")


@pytest.mark.parametrize("face,ports", [("axi", ("s_axis_tdata", "m_axis_tlast", "s_axil_awaddr",
                                                  "s_axil_rresp")),
                                        ("wishbone", ("s_axis_tdata", "m_axis_tuser", "wb_cyc",
                                                      "wb_dat_r"))])
def test_a_bus_face_is_written_with_its_register_map(face, ports, tmp_path):
    out = write_face(tmp_path, CFG, face, f"izh_{face}")
    v = (tmp_path / f"izh_{face}.v").read_text()
    header, body = v.split("\nmodule ", 1)
    assert "register map" in header and "0x00 ID" in header and "0x60 WRITES" in header
    decl = body.split(";", 1)[0]
    assert all(p in decl for p in ports)
    regmap = json.loads((tmp_path / f"izh_{face}.regmap.json").read_text())
    regs = {r["name"]: r for r in regmap["registers"]}
    assert regs["ID"]["offset"] == 0 and regs["ID"]["value"] == int.from_bytes(b"cune", "little")
    assert regs["N_WRITTEN"]["value"] == 8 and regs["N_SPIKE_IDS"]["value"] == 8
    assert regs["CLOCK_HZ"]["value"] == 16e3 * 64 and regs["TICK_DIVIDER"]["reset"] == 64
    assert regs["CLAMP_FLAGS"]["access"] == "ro" and regs["STEP"]["access"] == "cmd"
    md = (tmp_path / f"izh_{face}.regmap.md").read_text().splitlines()
    assert sum(line.startswith("| `0x") for line in md) == len(regs)
    assert len(out["files"]) == 4


@pytest.mark.parametrize("face", ["axi", "uart"])
def test_the_learning_layers_write_map_is_stated_with_its_face(face, tmp_path):
    """The learning layer's write addresses (spikes, weights, the window's end, readout
    requests) in the Verilog header, and in the register map's JSON and markdown."""
    cfg, _ = small_layer()
    S, M, K = cfg.n_sources, cfg.n_targets, cfg.n_synapses
    write_face(tmp_path, cfg, face, f"learn_{face}")
    header = (tmp_path / f"learn_{face}.v").read_text().split("\nmodule ", 1)[0]
    for line in (f"write addresses 0 .. {S - 1}: spike",
                 f"write addresses {S} .. {S + M * K - 1}: weight",
                 f"write addresses {S + M * K} .. {S + M * K}: learn",
                 f"write addresses {S + M * K + 1} .. {S + M * K + M}: readout"):
        assert line in header
    if face == "axi":
        regmap = json.loads((tmp_path / f"learn_{face}.regmap.json").read_text())
        assert [(w["name"], w["first"], w["count"]) for w in regmap["write_map"]] == [
            ("spike", 0, S), ("weight", S, M * K), ("learn", S + M * K, 1),
            ("readout", S + M * K + 1, M)]
        regs = {r["name"]: r for r in regmap["registers"]}
        assert regs["N_WRITTEN"]["value"] == S + M * K + 1 + M
        assert regs["POPULATIONS"]["value"] == 2 | len(regmap["clamp_kinds"]) << 8
        md = (tmp_path / f"learn_{face}.regmap.md").read_text()
        assert "Write addresses:" in md and "readout" in md
