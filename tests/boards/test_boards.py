"""Board targets: sizing refusals, Verilog and board-top elaboration (default lane) and a real
ULX3S place and route (long lane)."""

import json

import pytest

from cuneate.boards.build import BuildError, build_target
from cuneate.boards.sizing import size_core
from cuneate.boards.targets import TARGETS
from cuneate.boards.top import BoardTop, ClockPlan
from cuneate.hdl.izhikevich.config import ConfigError
from cuneate.sim.cli import main


def test_clock_plans_have_whole_sweeps_and_line_rates_within_a_uarts_tolerance():
    p = TARGETS["ulx3s"]["clock_plan"]
    assert (p.cycles_per_tick, p.clocks_per_bit, p.baud_error) == (3750, 20, 0.0)
    with pytest.raises(ConfigError, match=r"16.6667 clocks per bit at 3e\+06 baud: 17 clocks "
                                          r"are 1.96 % off.*\(baud limit\)"):
        ClockPlan(25e6, 50e6, 16e3, 3e6)
    with pytest.raises(ConfigError, match="gives 3333.33 cycles per sweep: not an integer"):
        ClockPlan(25e6, 50e6, 15e3, 2.5e6)


@pytest.mark.parametrize("board,kw,match", [
    ("ulx3s", dict(n_neurons=60000), "17 cores of 3530 at 60 MHz need about 344 block RAMs.*"
                                     r"\(RAM limit\)"),
    ("ulx3s", dict(n_neurons=40961), r"10 cores of 4097 at 70 MHz need about 254 block RAMs.*"
                                     r"RAM limit.*90 MHz plan is above.*\(fmax limit"),
    ("ulx3s", dict(n_neurons=70000), "65536 neuron ids \\(link limit\\)"),
    ("icebreaker", dict(n_neurons=500, operand_width=18), "DSP limit"),
    ("icebreaker", dict(n_neurons=700, spike_fifo_depth=4096), "RAM limit"),
    ("icebreaker", dict(n_neurons=1000), "2 cores of 500 .* \\(RAM limit\\)"),
    ("ulx3s", dict(clock_hz=48e6), "PLL plans give 60, 70, 90 MHz"),
])
def test_refusals_name_the_limit(board, kw, match):
    with pytest.raises(ConfigError, match=match):
        size_core(TARGETS[board], **kw)


def test_sizing_fills_the_ulx3s_with_cores():
    """The largest ULX3S build: 10 cores of 4096 at 70 MHz (204 of the 208 block RAMs by the
    estimate; the line at 2 Mbaud, which 70 MHz divides exactly); 37 340 still fits the
    60 MHz plan (the lower clock wins a tie of cores); 40 961 is refused naming every limit:
    cores of 4097 cross the 2048 x 9 blocks' depth, 11 cores at 60 MHz need more block RAM,
    and the 90 MHz plan is above 0.9 x the fmax the filled board build measured (the
    target's ``link_fmax_mhz``)."""
    r = size_core(TARGETS["ulx3s"], n_neurons=40960)
    lc = r["link"]
    assert (lc.n_cores, lc.core.n_neurons, lc.n_neurons) == (10, 4096, 40960)
    assert r["plan"]["clock_hz"] == 70e6 and r["plan"]["clocks_per_bit"] == 35
    assert r["plan"]["cycles_per_tick"] == 4375 and r["plan"]["baud"] == 2e6
    assert r["estimate"]["BRAM"] == 204 and r["estimate"]["DSP"] == 40
    r = size_core(TARGETS["ulx3s"], n_neurons=37340)
    assert r["plan"]["clock_hz"] == 60e6 and r["link"].n_cores == 10
    fmax = f"{TARGETS['ulx3s']['link_fmax_mhz']:.4g}"
    with pytest.raises(ConfigError, match=r"4097 at 70 MHz need about 254 block RAMs.*"
                                          r"224 block RAMs.*\(RAM limit\).*90 MHz plan is "
                                          rf"above 0.9 x the {fmax} MHz fmax"):
        size_core(TARGETS["ulx3s"], n_neurons=40961, pipeline_stages=9)


def test_limits_per_board():
    """The bounds on neurons at 16 kHz and the largest count each board's sizing accepts."""
    from cuneate.boards.sizing import limits
    u5, u8 = limits(TARGETS["ulx3s"], 5), limits(TARGETS["ulx3s"], 9)
    assert (u5["largest"], u5["cores"], u5["clock_hz"]) == (40960, 10, 70e6)
    # the board build's fmax rules both depths: below 90 MHz / 0.9, so the 90 MHz plan is
    # refused and the largest is the 70 MHz one (cores of 4096: the block shape's depth)
    t = TARGETS["ulx3s"]
    assert u8["fmax_mhz"] == t["link_fmax_mhz"] < min(t["fmax_mhz"][9], 90 / 0.9)
    assert 70 / 0.9 <= t["link_fmax_mhz"]
    assert u8["largest"] == u5["largest"] == 40960
    # every device bit at 76 bits per neuron: the block-RAM bound is the tightest
    assert u8["bram"] == 208 * 18432 // 76 < min(u8["multiplier"], u8["fmax"])
    ice = limits(TARGETS["icebreaker"], 5)
    assert (ice["largest"], ice["cores"]) == (734, 1)
    atlys = limits(TARGETS["atlys"], 5)
    assert atlys["largest"] == 20480 > 8 * 2500       # the reference held 2 500


def test_ulx3s_verilog_and_board_top_elaborate(tmp_path):
    r = build_target("ulx3s", tmp_path, bitstream=False)
    v = (tmp_path / "cuneate_ulx3s_core.v").read_text()
    assert "module cuneate_ulx3s_core" in v and r["core"]["n_neurons"] == 2500
    assert r["clock_plan"]["cycles_per_tick"] == 3750 and r["link"]["clocks_per_bit"] == 20
    assert json.loads((tmp_path / "cuneate_ulx3s.report.json").read_text())["board"] == "ulx3s"
    t = TARGETS["ulx3s"]
    plan = t["platform"]().prepare(BoardTop(size_core(t, n_neurons=64)["link"], t["pll"],
                                            True), name="top")
    top_v = plan.files["top.il"]
    top_v = top_v.decode() if isinstance(top_v, bytes) else top_v
    assert "EHXPLLL" in top_v and "CLKFB_DIV" in top_v
    lpf = plan.files["top.lpf"]
    lpf = lpf.decode() if isinstance(lpf, bytes) else lpf
    assert "FREQUENCY PORT" in lpf and "25000000" in lpf.replace(".0", "")


@pytest.mark.parametrize("plan_index", range(len(TARGETS["ulx3s"]["clock_plans"])))
def test_each_ulx3s_pll_makes_its_plans_clock(plan_index):
    """nextpnr constrains the core's clock through the EHXPLLL's dividers (25 MHz / CLKI_DIV x
    CLKFB_DIV, the VCO at that x CLKOP_DIV within the ECP5's 400-800 MHz): each plan's PLL
    gives the plan's clock."""
    import re
    t = TARGETS["ulx3s"]
    plan, pll = t["clock_plans"][plan_index]
    il = t["platform"]().prepare(BoardTop(size_core(t, n_neurons=64)["link"], pll, True),
                                 name="top").files["top.il"]
    il = il.decode() if isinstance(il, bytes) else il
    div = {k: int(re.search(rf"parameter \\{k} (\d+)", il).group(1))
           for k in ("CLKI_DIV", "CLKFB_DIV", "CLKOP_DIV")}
    out_hz = 25e6 / div["CLKI_DIV"] * div["CLKFB_DIV"]
    assert out_hz == plan.clock_hz and 400e6 <= out_hz * div["CLKOP_DIV"] <= 800e6


def test_cli_lists_boards_and_refuses_in_one_line(capsys, tmp_path):
    assert main(["boards", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["name"] for r in rows} == set(TARGETS)
    assert main(["build", "nosuch", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown board 'nosuch'" in err
    assert main(["build", "ulx3s", "--neurons", "60000", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "(RAM limit)" in err
    assert main(["build", "atlys", "--out", str(tmp_path), "--no-bitstream"]) == 0
    assert (tmp_path / "cuneate_atlys_core.v").exists()
    # --board is the positional's other spelling; without a board, the hint names both
    assert main(["build", "--board", "arty", "--out", str(tmp_path), "--no-bitstream"]) == 0
    assert (tmp_path / "cuneate_arty_core.v").exists()
    capsys.readouterr()
    assert main(["build", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cuneate build BOARD, or --board BOARD" in err


@pytest.mark.long
def test_ulx3s_bitstream_meets_60mhz(tmp_path):
    r = build_target("ulx3s", tmp_path, bitstream=True, seed=1)
    assert r["bitstream"] and (tmp_path / "cuneate_ulx3s.bit").stat().st_size > 100_000
    pr = r["place_route"]
    assert pr["resources"]["DSP"]["used"] == 4
    assert pr["resources"]["BRAM"]["used"] <= r["estimate"]["BRAM"]
    # packed by default: the multipliers' registers in the MULT18X18D
    assert r["register_packing"]["outputs_packed"] > 0
    assert pr["timing_met"], pr["fmax_mhz"]
    print("\n" + (tmp_path / "cuneate_ulx3s.report.txt").read_text())


@pytest.mark.release
def test_ulx3s_filled_with_cores_meets_timing(tmp_path):
    """The largest count the ULX3S sizing accepts: 10 cores of 4096 neurons at 70 MHz behind
    the link (655 M neuron updates/s, 16 times the reference design), placed and routed into
    a bitstream with timing met."""
    from cuneate.boards.sizing import limits
    largest = limits(TARGETS["ulx3s"])["largest"]
    r = build_target("ulx3s", tmp_path, n_neurons=largest, seed=1)
    text = (tmp_path / "cuneate_ulx3s.report.txt").read_text()
    print("\n" + text)
    assert (r["neurons"], r["cores"], r["neurons_per_core"]) == (40960, 10, 4096)
    assert r["clock_plan"]["clock_hz"] == 70e6 and r["neurons"] * 16e3 >= 640e6
    assert r["bitstream"] and (tmp_path / "cuneate_ulx3s.bit").stat().st_size > 100_000
    pr = r["place_route"]
    assert pr["resources"]["DSP"]["used"] == 40
    assert pr["resources"]["BRAM"]["used"] <= r["estimate"]["BRAM"] <= 208
    assert r["register_packing"]["outputs_packed"] > 0          # packed by default
    assert r["timing_met"] and not text.startswith("TIMING NOT MET"), pr["fmax_mhz"]


@pytest.mark.long
def test_icebreaker_bitstream_fits_and_meets_12mhz(tmp_path):
    """The iCEBreaker at the largest count its sizing accepts (734: the 12 MHz clock's 750
    cycles per sweep less the link's 16 idle cycles; two cores need more EBR than the UP5K
    has)."""
    from cuneate.boards.sizing import limits
    largest = limits(TARGETS["icebreaker"])["largest"]
    r = build_target("icebreaker", tmp_path, n_neurons=largest, bitstream=True, seed=1)
    assert r["bitstream"] and (tmp_path / "cuneate_icebreaker.bin").exists()
    pr = r["place_route"]
    assert r["core"]["operand_width"] == 16 and r["core"]["n_neurons"] == largest == 734
    assert pr["resources"]["DSP"]["used"] == 4
    assert pr["resources"]["BRAM"]["used"] <= 30 and pr["resources"]["LC"]["used"] <= 5280
    # a logic cell holds one LUT4 and one flip-flop: the netlist's counts of each fit the LCs
    assert max(pr["resources"]["LUT"]["used"], pr["resources"]["FF"]["used"]) \
        <= pr["resources"]["LC"]["used"]
    assert pr["timing_met"], pr["fmax_mhz"]
    print("\n" + (tmp_path / "cuneate_icebreaker.report.txt").read_text())


@pytest.mark.parametrize("board", [pytest.param("atlys", marks=pytest.mark.long),
                                   pytest.param("arty", marks=pytest.mark.release)])
def test_xilinx_targets_yosys_estimate(board, tmp_path):
    r = build_target(board, tmp_path, n_neurons=2484)
    ye = r["yosys_estimate"]
    assert ye["DSP"]["used"] >= 4 and ye["BRAM"]["used"] > 0
    assert ye["LUT"]["percent"] < 15
    print("\n" + (tmp_path / f"cuneate_{board}.report.txt").read_text())


def test_program_refuses_clearly(capsys, tmp_path):
    assert main(["program", "atlys", str(tmp_path / "x.bit")]) == 2
    assert "no bitstream flow for 'atlys'" in capsys.readouterr().err
    assert main(["program", "ulx3s", str(tmp_path / "x.bit")]) == 2
    assert "not found" in capsys.readouterr().err
    bit = tmp_path / "x.bit"
    bit.write_bytes(b"\xff" * 16)
    assert main(["program", "ulx3s", str(bit)]) == 2
    err = capsys.readouterr().err
    # without openFPGALoader, or with it and no board attached: one line saying so
    assert err.count("\n") == 1 and ("not installed" in err or "no ulx3s board" in err)


def test_a_build_at_115200_baud_divides_the_clock_within_the_uart_tolerance(tmp_path, capsys):
    """The ULX3S at 115200 baud beside its 3 Mbaud: 521 clocks a bit at 60 MHz (115 163 baud,
    0.03 % off); a rate no plan's clock divides within 1 % is refused before any synthesis."""
    assert main(["build", "ulx3s", "--baud", "115200", "--no-bitstream", "--json", "--out",
                 str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["link"]["clocks_per_bit"] == 521 and r["clock_plan"]["clocks_per_bit"] == 521
    assert r["link"]["baud"] == r["clock_plan"]["baud"] == pytest.approx(60e6 / 521)
    txt = (tmp_path / "cuneate_ulx3s.report.txt").read_text()
    assert "UART 115163 baud (521 clocks a bit)" in txt.splitlines()[0]
    assert main(["build", "ulx3s", "--baud", "5714286", "--no-bitstream", "--out",
                 str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "60 MHz gives 10.5 clocks per bit" in err[0]
    assert "5.00 % off, more than a UART's 1 % (baud limit)" in err[0]
    # the budget of a scene is taken at the build's rate
    assert main(["build", "ulx3s", "skin_3x3", "--baud", "115200", "--no-bitstream", "--out",
                 str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "more than the 115200 baud link's 11,520 B/s (link limit)" in err[0]


def test_sizing_gives_each_core_of_an_array_its_own_parameter_sets():
    """A request mixing parameter sets over several cores: each core starts its own neurons
    with their own sets (the link's ``neuron_sets``, padding neurons set 0), the model's twins
    too; a single core takes them in its configuration; more sets than neurons are refused."""
    from cuneate.hdl.link import LinkModel
    sets = [0] * 3000 + [1] * 2000
    r = size_core(TARGETS["ulx3s"], n_neurons=5000, param_sets=("RS", "FS"), neuron_sets=sets)
    lc = r["link"]
    assert lc.n_cores == 2 and lc.core.n_neurons == 2500
    assert list(lc.neuron_sets) == sets
    twins = LinkModel(lc).twin.model.twins
    assert [list(t.cfg.neuron_sets) for t in twins] == [sets[:2500], sets[2500:]]
    one = size_core(TARGETS["ulx3s"], n_neurons=100, param_sets=("RS", "FS"),
                    neuron_sets=[1] * 100)["link"]
    assert one.n_cores == 1 and one.neuron_sets is None
    assert list(one.core.neuron_sets) == [1] * 100
    with pytest.raises(ConfigError, match="neuron_sets gives 101 sets for 100 neurons"):
        size_core(TARGETS["ulx3s"], n_neurons=100, param_sets=("RS", "FS"),
                  neuron_sets=[1] * 101)


def test_a_report_whose_timing_fails_says_so_first_with_each_clocks_fmax(tmp_path):
    """A nextpnr report (written here by hand: two clocks, the core's below the requested 90
    MHz) read as a build's: ``timing_met`` false, the failing fmax in the first line of the
    text report, every clock's fmax under its domain's name."""
    from cuneate.boards.build import _nextpnr_report, format_report
    nextpnr = {"fmax": {"$glbnet$clk": {"achieved": 82.877, "constraint": 90.0},
                        "$glbnet$clk_uart": {"achieved": 131.5, "constraint": 90.0}},
               "utilization": {"TRELLIS_COMB": {"used": 21802, "available": 83640},
                               "MULT18X18D": {"used": 40, "available": 156}}}
    (tmp_path / "n.json").write_text(json.dumps(nextpnr))
    pr = _nextpnr_report(tmp_path / "n.json", TARGETS["ulx3s"], 90e6)
    assert pr["fmax_mhz"] == {"clk": 82.877, "clk_uart": 131.5}
    assert (pr["min_fmax_mhz"], pr["requested_mhz"], pr["timing_met"]) == (82.877, 90.0, False)
    assert pr["resources"]["LUT"] == {"used": 21802, "available": 83640, "percent": 26.07}
    r = build_target("ulx3s", tmp_path / "b", bitstream=False)
    lines = format_report({**r, "place_route": pr}).splitlines()
    assert lines[0] == "TIMING NOT MET: 82.88 MHz reached, 90 MHz requested"
    assert "fmax of clock clk: 82.88 MHz" in lines and "fmax of clock clk_uart: 131.50 MHz" in lines
    assert lines[-1] == "fmax 82.88 MHz, requested 90 MHz: timing NOT met"
    nextpnr["fmax"]["$glbnet$clk"]["constraint"] = 84.0      # a PLL making the wrong clock
    (tmp_path / "n.json").write_text(json.dumps(nextpnr))
    with pytest.raises(BuildError, match=r"^ulx3s: nextpnr derives 84 MHz for clock clk from "
                                         r"the PLL, the clock plan asks 90 MHz"):
        _nextpnr_report(tmp_path / "n.json", TARGETS["ulx3s"], 90e6)
