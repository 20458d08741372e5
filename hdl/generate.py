"""Verilog generation: deterministic output plus a JSON description of the generated core."""

from __future__ import annotations

import json
from pathlib import Path

from amaranth.back import verilog
from amaranth.lib.wiring import In

from .izhikevich import IzhikevichConfig, IzhikevichCore

__all__ = ["izhikevich_verilog", "generate_izhikevich", "lowered_verilog", "port_table",
           "write_block"]


def lowered_verilog(top, name: str) -> str:
    """Verilog of ``top`` after yosys ``proc``: every process becomes multiplexers and
    registers (no ``always @*`` blocks). Icarus 11 does not re-evaluate some combinational
    processes of Amaranth FSMs when an input changes while the state holds; it simulates the
    lowered netlist of the same design correctly."""
    from amaranth._toolchain.yosys import find_yosys
    from amaranth.back import rtlil
    il = rtlil.convert(top, name=name, emit_src=False)
    yosys = find_yosys(lambda ver: ver >= (0, 40))
    return yosys.run(["-q", "-"], f"read_rtlil <<rtlil\n{il}\nrtlil\nproc\nopt_clean\n"
                                  f"write_verilog -noattr\n")


def port_table(core) -> dict:
    """Direction, width and signedness of every port of a ``wiring.Component``."""
    return {pname: {"direction": "in" if member.flow == In else "out",
                    "width": member.shape.width if hasattr(member.shape, "width")
                    else len(getattr(core, pname)),
                    "signed": bool(getattr(member.shape, "signed", False))}
            for pname, member in core.signature.members.items()}


def izhikevich_verilog(config: IzhikevichConfig, name: str = "izhikevich_core") -> str:
    """Verilog text of the core (no source locations, so the same config gives the same bytes)."""
    return verilog.convert(IzhikevichCore(config), name=name, emit_src=False)


def generate_izhikevich(out: Path, n_neurons: int = 2500, clock_hz: float = 40e6,
                        update_hz: float = 16e3, config: IzhikevichConfig | None = None,
                        name: str = "izhikevich_core") -> list[Path]:
    """Write ``out/<name>.v`` and ``out/<name>.json``; returns the paths."""
    cfg = config or IzhikevichConfig(n_neurons=n_neurons, clock_hz=clock_hz, update_hz=update_hz)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    core = IzhikevichCore(cfg)
    text = verilog.convert(core, name=name, emit_src=False)
    desc = cfg.to_dict()
    desc["module"] = name
    desc["ports"] = port_table(core)
    vpath, jpath = out / f"{name}.v", out / f"{name}.json"
    vpath.write_text(text)
    jpath.write_text(json.dumps(desc, indent=2, sort_keys=True) + "\n")
    return [vpath, jpath]


def write_block(out, top, description: dict, name: str) -> list[Path]:
    """Write ``out/<name>.v`` (deterministic bytes) and ``out/<name>.json`` (``description``
    plus the module name and the port table) for the component ``top``; returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    text = verilog.convert(top, name=name, emit_src=False)
    desc = description | {"module": name, "ports": port_table(top)}
    vpath, jpath = out / f"{name}.v", out / f"{name}.json"
    vpath.write_text(text)
    jpath.write_text(json.dumps(desc, indent=2, sort_keys=True, default=float) + "\n")
    return [vpath, jpath]
