"""Every board target (boards/targets.py): its clock plans against its PLL's dividers and the
family's ranges, its board top elaborated on its platform with the UART and clock pins in the
constraints (one generic test over all boards, default lane); the Vivado projects' TCL and XDC
under tclsh; the limit table; one short bitstream per new open family (Gowin, Nexus: long
lane); the largest builds over three seeds and the default scene's core (release lane,
recorded in benchmarks/boards.md)."""

import json

import pytest

from cuneate.boards.build import board_platform, build_target
from cuneate.boards.sizing import clock_plans, limits, size_core
from cuneate.boards.targets import TARGETS
from cuneate.boards.top import BoardTop
from cuneate.hdl.flow.nexus_carry import free_carry_inputs
from cuneate.sim.cli import main

#: each board's constraint file and the pins its UART and oscillator must be bound to there
PINS = {
    "ulx3s": ("lpf", ["M1", "L4", "G2"]), "butterstick": ("lpf", ["G2", "J3", "B12"]),
    "orangecrab": ("lpf", ["M18", "N17", "A9"]), "colorlight": ("lpf", ["P11", "M13", "P6"]),
    "icebreaker": ("pcf", ["9", "6", "35"]), "tang_primer_20k": ("cst", ["M11", "T13", "H11"]),
    "tang_nano_9k": ("cst", ["17", "18", "52"]), "crosslink_nx": ("pdc", ["F18", "F16", "L13"]),
    "arty": ("xdc", ["D10", "A9", "E3"]), "arty100": ("xdc", ["D10", "A9", "E3"]),
    "nexys4ddr": ("xdc", ["D4", "C4", "E3"]),
}


def _text(data):
    return data.decode() if isinstance(data, bytes) else data


@pytest.mark.parametrize("board", [b for b, t in TARGETS.items() if t.get("platform")])
def test_every_board_top_elaborates_with_its_uart_and_clock_plans(board):
    """Each plan's PLL makes the plan's clock from the plan's oscillator within its family's
    phase-detector and VCO ranges; the board top (PLL, a 64-neuron core behind the link, UART,
    status LEDs) elaborates on the platform the build uses (ECP5: the packing one), its
    constraints binding the UART and the oscillator to the board's pins."""
    t = TARGETS[board]
    for plan, pll in clock_plans(t):
        p = pll.plan
        if p is None:                                   # the oscillator straight through
            assert plan.osc_hz == plan.clock_hz
            continue
        assert (p.osc_mhz * 1e6, p.out_mhz * 1e6) == pytest.approx((plan.osc_hz, plan.clock_hz))
        assert p.check() == [], (plan.clock_hz, p)
        assert plan.baud_error <= 0.01 and plan.cycles_per_tick * plan.update_hz == plan.clock_hz
    top = BoardTop(size_core(t, n_neurons=64)["link"], t["pll"], t.get("uart_tx_enable", False),
                   t.get("status_leds"))
    files = board_platform(t).prepare(top, name="top").files
    ext, pins = PINS[board]
    cons = _text(files[f"top.{ext}"])
    for pin in pins:
        assert f"{pin}" in cons.replace("{", " ").replace("}", " ").replace(";", " ").split() \
            or f'"{pin}"' in cons or f" {pin};" in cons, (board, pin)
    assert "uart_0__tx" in cons and "uart_0__rx" in cons


def test_limit_table_lists_every_board_with_units_and_one_row_where_depths_agree(capsys):
    assert main(["boards"]) == 0
    out = capsys.readouterr().out
    head, *rows = out.splitlines()
    for col in ("block-RAM bound (neurons)", "multiplier bound (neurons)",
                "logic x fmax bound (neurons)", "largest build (neurons)", "PLL plans (MHz)"):
        assert col in head
    assert {r.split()[0] for r in rows[:-1]} == set(TARGETS)
    assert "212 100 (at 80.8 MHz)" in out            # a neuron count, with the fmax it used
    assert main(["boards", "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    ulx = [r for r in js if r["name"] == "ulx3s"]
    assert len(ulx) == 1 and ulx[0]["depths"] == [5, 9]   # identical limits: one row
    ice = [r for r in js if r["name"] == "icebreaker"][0]
    assert ice["default_neurons"] == ice["largest"] == 734
    out = {r["name"]: r["output"] for r in js}
    assert out["arty"] == out["nexys4ddr"] == "Vivado project + estimate"
    assert out["atlys"] == "Verilog + estimate" and out["tang_nano_9k"] == "bitstream"
    assert out["arty_z7"] == out["pynq_z2"] == "Vivado IP + block design + estimate"


def test_nexus_carry_inputs_tied_low_are_disconnected():
    """A chain whose first CCU2 takes its carry from a VLO cell starts unconnected (nextpnr-
    nexus's chain root); a carry from another CCU2 or a VHI stays."""
    def cell(t, **conn):
        return {"type": t, "connections": conn,
                "port_directions": {k: "output" if k in ("Z", "COUT") else "input"
                                    for k in conn}}
    net = {"modules": {"top": {"cells": {
        "lo": cell("VLO", Z=[2]), "hi": cell("VHI", Z=[3]),
        "a": cell("CCU2", CIN=[2], COUT=[4]), "b": cell("CCU2", CIN=[4], COUT=[5]),
        "c": cell("CCU2", CIN=[3], COUT=[6])}}}}
    assert free_carry_inputs(net) == 1
    cells = net["modules"]["top"]["cells"]
    assert "CIN" not in cells["a"]["connections"] and cells["b"]["connections"]["CIN"] == [4]
    assert cells["c"]["connections"]["CIN"] == [3]


def test_vivado_project_is_written_and_its_tcl_and_xdc_run_against_stubs(tmp_path):
    """``cuneate build nexys4ddr --no-bitstream``: the Verilog of the board top (MMCME2_BASE to
    40 MHz), the XDC from the board file and amaranth's build TCL; tclsh runs the TCL (which
    reads the XDC) with every Vivado command stubbed: no unknown command, no missing file."""
    r = build_target("nexys4ddr", tmp_path, n_neurons=64, bitstream=False)
    vp = r["vivado_project"]
    assert {"cuneate_nexys4ddr.v", "cuneate_nexys4ddr.xdc", "cuneate_nexys4ddr.tcl"} <= \
        set(vp["files"])
    chk = vp["tcl_check"]
    assert chk["ok"], chk
    assert {"create_project", "read_xdc", "synth_design", "route_design", "write_bitstream",
            "create_clock", "set_property"} <= set(chk["used"])
    v = (tmp_path / "cuneate_nexys4ddr.v").read_text()
    assert "MMCME2_BASE" in v and "CLKFBOUT_MULT_F" in v
    # a misspelt command is what the check exists for
    tcl = tmp_path / "cuneate_nexys4ddr.tcl"
    tcl.write_text(tcl.read_text().replace("synth_design", "synth_desing"))
    from cuneate.boards.vivado import check_tcl
    bad = check_tcl(tmp_path, "cuneate_nexys4ddr")
    assert not bad["ok"] and "synth_desing" in bad["error"]


@pytest.mark.long
@pytest.mark.parametrize("board", ["tang_nano_9k", "crosslink_nx"])
def test_a_short_bitstream_per_new_family(board, tmp_path):
    """Gowin (nextpnr-himbaechel, gowin_pack) and Nexus (nextpnr-nexus with router1,
    prjoxide): a 256-neuron core behind the link placed, routed and packed with timing met at
    the board's clock."""
    r = build_target(board, tmp_path, n_neurons=256, seed=1)
    t = TARGETS[board]
    bit = tmp_path / f"cuneate_{board}.{t['bitstream_ext']}"
    assert r["bitstream"] and bit.stat().st_size > 10_000
    pr = r["place_route"]
    assert pr["resources"]["DSP"]["used"] == 4 and pr["resources"]["BRAM"]["used"] > 0
    assert pr["timing_met"], pr["fmax_mhz"]
    print("\n" + (tmp_path / f"cuneate_{board}.report.txt").read_text())


NEW_BOARDS = ["tang_nano_9k", "tang_primer_20k", "orangecrab", "colorlight", "butterstick",
              "crosslink_nx"]


@pytest.mark.release
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("board", NEW_BOARDS)
def test_largest_build_meets_timing(board, seed, tmp_path):
    """The largest count each new board's sizing accepts, placed and routed at seeds 1-3 with
    timing met (benchmarks/boards.md)."""
    largest = limits(TARGETS[board])["largest"]
    r = build_target(board, tmp_path, n_neurons=largest, seed=seed)
    print("\n" + (tmp_path / f"cuneate_{board}.report.txt").read_text()
          + f"build {r['build_seconds']} s")
    assert r["neurons"] == largest and r["bitstream"]
    assert r["timing_met"], r["place_route"]["fmax_mhz"]


@pytest.mark.release
@pytest.mark.parametrize("board", NEW_BOARDS)
def test_default_scene_core_builds(board, tmp_path):
    """The default scene (``cuneate run``'s four-material grasp) sized onto each new board."""
    from cuneate.sim.scenes.scene import default_scene
    r = build_target(board, tmp_path, scene=default_scene(), seed=1)
    print("\n" + (tmp_path / f"cuneate_{board}.report.txt").read_text()
          + f"build {r['build_seconds']} s")
    assert r["bitstream"] and r["timing_met"], r["place_route"]["fmax_mhz"]


@pytest.mark.long
@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", ["icarus", "verilator"])
def test_vivado_boards_core_verilog_answers_on_both_simulators(simulator, tmp_path):
    """The Arty's linked core (the Verilog its Vivado project holds, 64 neurons at 40 MHz, 20
    clocks a bit) on the link's cocotb bench: a counters request answered with one intact
    counters frame, the request counted. Icarus 11 runs the same design's yosys-lowered netlist
    (``link_verilog``)."""
    from cuneate.hdl.link import link_verilog
    from cuneate.hdl.link.codec import (MSG_COUNTERS, OP_READ_COUNTERS, FrameDecoder,
                                        control_message, encode_frame, parse_counters)
    from cuneate.sim.engines.cocotb import run_cocotb
    t = TARGETS["arty"]
    r = build_target("arty", tmp_path, n_neurons=64, bitstream=False)
    lc = size_core(t, n_neurons=64)["link"]
    src = tmp_path / "cuneate_arty_core.v"
    if simulator == "icarus":
        src = tmp_path / "cuneate_arty_core_lowered.v"
        src.write_text(link_verilog(lc, "cuneate_arty_core", lowered=True))
    cpb = r["clock_plan"]["clocks_per_bit"]
    frame = encode_frame(control_message(0, OP_READ_COUNTERS))
    run = run_cocotb(simulator, [src], "cuneate_arty_core", "cuneate.sim.link.bench",
                     tmp_path / simulator, testcase="play",
                     config={"clocks_per_bit": cpb, "total_cycles": 24_000,
                             "watch_writes": False, "chunks": [[frame.hex(), 0]]})
    dec = FrameDecoder()
    msgs = dec.feed(bytes.fromhex(run.report["received"]))
    assert dec.errors == {"framing": 0, "crc": 0, "length": 0, "version": 0}
    counters = [m for m in msgs if m.type == MSG_COUNTERS]
    assert len(counters) == 1 and parse_counters(counters[0])["frames_ok"] == 1
