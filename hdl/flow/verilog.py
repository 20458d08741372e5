"""Verilog emission: deterministic text of a block (no source locations, so the same
configuration gives the same bytes), the lowered netlist Icarus needs for some designs, and the
files every block writes (``<name>.v`` and a JSON description with its port table)."""

from __future__ import annotations

import json
from pathlib import Path

from amaranth.back import verilog
from amaranth.lib.wiring import In

__all__ = ["verilog_text", "lowered_verilog", "port_table", "write_block"]


def verilog_text(top, name: str, lowered: bool = False, opt_clean: bool = True) -> str:
    """Verilog text of the component ``top`` as module ``name``; with ``lowered``, after yosys
    ``proc`` (see :func:`lowered_verilog`)."""
    if lowered:
        return lowered_verilog(top, name, opt_clean)
    return verilog.convert(top, name=name, emit_src=False)


def lowered_verilog(top, name: str, opt_clean: bool = True) -> str:
    """Verilog of ``top`` after yosys ``proc``: every process becomes multiplexers and
    registers (no ``always @*`` blocks). Icarus 11 does not re-evaluate some combinational
    processes of Amaranth FSMs when an input changes while the state holds; it simulates the
    lowered netlist of the same design correctly. Without ``opt_clean`` internal signals that
    drive no output stay (for scoreboards that probe them)."""
    from amaranth._toolchain.yosys import find_yosys
    from amaranth.back import rtlil
    il = rtlil.convert(top, name=name, emit_src=False)
    yosys = find_yosys(lambda ver: ver >= (0, 40))
    clean = "opt_clean\n" if opt_clean else ""
    return yosys.run(["-q", "-"], f"read_rtlil <<rtlil\n{il}\nrtlil\nproc\n{clean}"
                                  f"write_verilog -noattr\n")


def port_table(core) -> dict:
    """Direction, width and signedness of every port of a ``wiring.Component``."""
    return {pname: {"direction": "in" if member.flow == In else "out",
                    "width": member.shape.width if hasattr(member.shape, "width")
                    else len(getattr(core, pname)),
                    "signed": bool(getattr(member.shape, "signed", False))}
            for pname, member in core.signature.members.items()}


def write_block(out, top, description: dict, name: str) -> list[Path]:
    """Write ``out/<name>.v`` (deterministic bytes) and ``out/<name>.json`` (``description``
    plus the module name and the port table) for the component ``top``; returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    text = verilog_text(top, name)
    desc = description | {"module": name, "ports": port_table(top)}
    vpath, jpath = out / f"{name}.v", out / f"{name}.json"
    vpath.write_text(text)
    jpath.write_text(json.dumps(desc, indent=2, sort_keys=True, default=float) + "\n")
    return [vpath, jpath]
