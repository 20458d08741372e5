"""Formal checks of the Izhikevich block with SymbiYosys (``yowasp-sby``; z3 or yices).

**The one-update datapath.** :func:`one_step` builds one combinational update with free inputs
``v``, ``u``, ``I`` (and the parameter-set index) assumed inside the configuration's state box
(``v_floor <= v <= v_th``, ``u_lo <= u <= u_hi``) and the accepted current range. It asserts:

* ``datapath`` (default): on the four-stage update (:func:`~cuneate.hdl.izhikevich.datapath
  .stage_update`: ``operands``, ``multiply1``, ``multiply2``, ``update_state``, the arithmetic's
  specification and the coincidence core's datapath), every unclamped narrowing
  (:func:`cuneate.hdl.lib.fixed.narrow`: the ``w`` and ``v`` operands, ``q``, ``v`` below
  threshold where it is used) holds its proven bounds - nothing can wrap - and the ``y``
  operand clamp never acts;
* ``state_box``: additionally, the next state stays in the box with no flagged clamp (``v_low``,
  ``u_high``, ``u_low``) - i.e. the box is closed under one update;
* ``steps``: the pipelined steps the Izhikevich core and its twin compute
  (:func:`~cuneate.hdl.izhikevich.datapath.one_update` of :data:`~cuneate.hdl.izhikevich
  .datapath.STEPS`) give the four-stage update's ``v``, ``u``, spike and every clamp flag, and
  their own narrowings (the floors of ``v``, the floor of ``q``, the ``y`` operand) hold their
  bounds. With ``datapath`` this carries the range proof over to the core's arithmetic.

A bounded check of depth 1 on a combinational circuit covers every input: a pass is a proof for
all states in the box and all accepted currents. :func:`prove` runs SymbiYosys in a work
directory (relative paths: the YoWASP tools see only their current directory) and returns the
status, the time and, on failure, the counterexample ``(v, u, I)``.

The pipelined core against this datapath, for every input sequence: :mod:`cuneate.hdl
.izhikevich.formal_core` (k-induction).
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
from amaranth import Elaboratable, Module, Signal, signed
from amaranth.hdl import Assert, Assume

from ..flow.sby import FormalError, run_sby, signed_bits
from ..lib.fixed import arithmetic_hooks
from . import datapath as izh
from .config import IzhikevichConfig

__all__ = ["PROPERTIES", "one_step", "prove", "FormalError"]

PROPERTIES = ("datapath", "state_box", "steps")


class _OneStep(Elaboratable):
    def __init__(self, cfg: IzhikevichConfig, prop: str):
        self.cfg, self.prop = cfg, prop
        self.v = Signal(cfg.V.shape(), name="v")
        self.u = Signal(cfg.U.shape(), name="u")
        self.I = Signal(cfg.I.shape(), name="I")
        n_sets = len(cfg.params)
        self.sel = Signal(range(max(2, n_sets)), name="sel")
        # the "steps" property's free products
        self.p_free = Signal(signed(48), name="p_free")
        self.m_free = Signal(signed(48), name="m_free")
        self.b_free = Signal(signed(48), name="b_free")

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        v, u, I = self.v, self.u, self.I
        n_sets = len(cfg.params)
        sel = self.sel if n_sets > 1 else 0
        checks: list = []        # every narrowing of the update: (value, bounds, name)
        with arithmetic_hooks(narrow=lambda x, bounds, name: checks.append((x, bounds, name))):
            if self.prop == "steps":
                # the variable products free (see _stages_with_products)
                P, M, B = self.p_free, self.m_free, self.b_free
                out = izh.one_update(cfg, v, u, I, sel, _steps_with_products(P, M, B))
                mark = len(checks)
                ref, ref_flags = izh.stage_update(
                    cfg, v, u, I, sel, _stages_with_products(m, P, M, B, out))
                # B is floor(v) b (assumed, not substituted: the narrowing of the y operand
                # depends on it)
                m.d.comb += Assume(B == out["vs_q"] * izh.lookup([b.raw for b in cfg.beta], sel))
                del checks[mark:]           # the four-stage narrows: the datapath property's
            else:
                out, flags = izh.stage_update(cfg, v, u, I, sel)
        m.d.comb += [Assume((v >= cfg.v_floor_raw) & (v <= cfg.VTH.raw)),
                     Assume((u >= cfg.u_lo_raw) & (u <= cfg.u_hi_raw)),
                     Assume((I >= cfg.i_lo_raw) & (I <= cfg.i_hi_raw))]
        if n_sets > 1:
            m.d.comb += Assume(self.sel < n_sets)
        if self.prop == "steps":
            # the pipelined steps give the four-stage update's results, flags included
            for k in ("v", "u", "spike"):
                m.d.comb += Assert(out[k] == ref[k], f"steps: {k}")
            for k, flag in izh.step_flags(out).items():
                m.d.comb += Assert(flag == ref_flags[k], f"steps: {k} flag")
        for x, (lo, hi), name in checks:
            if self.prop == "steps" and name == "v below threshold":
                continue                    # depends on P: the datapath property's
            ok = (x >= lo) & (x <= hi)
            if name == "v below threshold":     # used only when neither spike nor floor
                ok = ok | out["spike"] | out["v_low"]
            m.d.comb += Assert(ok, name)
        if self.prop != "steps":
            m.d.comb += Assert(~flags["y"], "y clamp")
        if self.prop == "state_box":
            m.d.comb += Assert(~out["u_low"] & ~out["u_high"] & ~out["v_low"], "state clamp")
        return m


def _steps_with_products(P, M, B):
    """:data:`izh.STEPS` with their variable products free: ``pb = B`` (step 1's ``floor(v) b``),
    ``m2 = M`` and ``p2 = P - extra`` (step 3; the ``v`` sums see ``P`` where they see
    ``floor(q) w + extra``, ``extra`` the ``w`` multiple of the rounding of ``q`` that step 3
    adds to them)."""
    def product1(cfg, x):
        return dict(izh.product1_step(cfg, x), pb=B)

    def product2(cfg, x):
        out = izh.product2_step(cfg, x)
        return dict(out, p2=P - (out["vb"] - x["vb"]), m2=M)
    swap = {"multiply1": product1, "multiply2": product2}
    return tuple((swap.get(s.name, s.fn), s.reads) for s in izh.STEPS)


def _small_multiple(m, d, lo: int, hi: int, consts, sel, name: str):
    """``d * consts[sel]`` for ``lo <= d <= hi`` as a multiplexer of constants, with the
    range of ``d`` asserted (so the substitution is exact wherever the proof passes)."""
    m.d.comb += Assert((d >= lo) & (d <= hi), name)
    return izh.select_by(d - lo, [izh.lookup([j * c for c in consts], sel)
                                  for j in range(lo, hi + 1)])


def _stages_with_products(m, P, M, B, steps: dict):
    """The four stage functions with their variable products written through the pipelined
    steps' free ones by exact integer identities: ``round(v) b = B + (round(v) - floor(v)) b``
    (``floor(v)``: the steps' ``vs_q``), ``y (a dt) = (M << k) + (y - (y_hi << k)) (a dt)``
    (``y_hi``: the steps' high part of ``y``), the small multiples as multiplexers of
    constants with their ranges asserted; and ``p = P`` (both sides' ``q w`` depend on ``v``
    and the set alone, compared for every ``v`` by :func:`prove_steps_products`)."""
    def multiply1(cfg, wq, vq, x, u, sel):
        o = izh.multiply1(cfg, wq, vq, x, u, sel)
        betas = [b.raw for b in cfg.beta]
        return dict(o, bvp=B + _small_multiple(m, vq - steps["vs_q"], 0, 1, betas, sel,
                                               "steps: v operand less its floor"))

    def multiply2(cfg, q, bvp, uy, wq, v, u, x, sel):
        o = izh.multiply2(cfg, q, bvp, uy, wq, v, u, x, sel)
        k = cfg.y_split
        r = _small_multiple(m, o["y"] - (steps["y_hi"] << k), -1, (1 << k) - 1,
                            [a.raw for a in cfg.alpha], sel, "steps: y less its high part")
        return dict(o, p=P, m=(M << k) + r)
    return (izh.operands, multiply1, multiply2, izh.update_state)


def steps_product_table(cfg: IzhikevichConfig, sel: int, v) -> tuple:
    """``(four-stage p, pipelined p)`` for the states ``v`` (raw, numpy) of set ``sel``: the
    ``q w`` product of :func:`izh.multiply2` and what the pipelined steps add to the ``v``
    sums in its place (``p2`` plus step 3's ``w`` multiple). Both depend on ``v`` and the set
    alone (``u`` and ``I`` are passed as 0), so comparing them over every ``v`` is a proof."""
    v = np.asarray(v, dtype=np.int64)
    zero = np.zeros_like(v)
    sel = np.full_like(v, sel)
    s2 = izh.operands(cfg, v, zero, zero, sel)
    s3 = izh.multiply1(cfg, s2["wq"], s2["vq"], s2["x"], zero, sel)
    p_old = izh.multiply2(cfg, s3["q"], s3["bvp"], s3["uy"], s2["wq"], v, zero, s3["x"],
                          sel)["p"]
    vals = {"v": v, "u": zero, "i": zero, "sel": sel}
    for step in izh.STEPS[:3]:
        vals.update(step.fn(cfg, {k: vals[k] for k in step.reads}))
    out = izh.product2_step(cfg, {k: vals[k] for k in izh.STEPS[3].reads})
    return np.asarray(p_old), np.asarray(out["p2"] + (out["vb"] - vals["vb"]))


def prove_steps_products(cfg: IzhikevichConfig, chunk: int = 1 << 22) -> dict:
    """Compare :func:`steps_product_table` over every ``v`` in ``[v_floor, v_th]`` and every
    set; returns ``{"states", "mismatches", "first", "seconds"}`` (``first``: ``(sel, v)`` of
    the first mismatch, or None)."""
    t0 = time.perf_counter()
    lo, hi = cfg.v_floor_raw, cfg.VTH.raw
    states = mismatches = 0
    first = None
    for sel in range(len(cfg.params)):
        for a in range(lo, hi + 1, chunk):
            v = np.arange(a, min(a + chunk, hi + 1), dtype=np.int64)
            p_old, p_new = steps_product_table(cfg, sel, v)
            bad = np.flatnonzero(p_old != p_new)
            states += len(v)
            mismatches += len(bad)
            if len(bad) and first is None:
                first = (sel, int(v[bad[0]]))
    return {"states": states, "mismatches": mismatches, "first": first,
            "seconds": time.perf_counter() - t0}


def one_step(cfg: IzhikevichConfig, prop: str = "datapath"):
    """The one-update harness of ``cfg`` for property ``prop`` and its ports."""
    if prop not in PROPERTIES:
        raise ValueError(f"unknown property {prop!r}; known: {', '.join(PROPERTIES)}")
    top = _OneStep(cfg, prop)
    free = [top.p_free, top.m_free, top.b_free] if prop == "steps" else []
    return top, [top.v, top.u, top.I, top.sel] + free


def prove(cfg: IzhikevichConfig, workdir: Path, prop: str = "datapath",
          timeout_s: float = 1800, solver: str = "portfolio") -> dict:
    """Run the one-step check; returns ``{"property", "status" ("pass"/"fail"), "seconds",
    "counterexample" ({"v", "u", "I", "sel"} raw, or None)}``; for ``steps`` also
    ``"products"``, the exhaustive comparison of :func:`prove_steps_products` (run first: a
    mismatch fails the property without the solver)."""
    from amaranth.back import rtlil
    extra = {}
    if prop == "steps":
        table = prove_steps_products(cfg)
        extra["products"] = table
        if table["mismatches"]:
            sel, v = table["first"]
            return {"property": prop, "status": "fail", "seconds": table["seconds"],
                    "counterexample": {"v": v, "u": cfg.u_lo_raw, "I": 0, "sel": sel},
                    "failed": ["steps: q w product"], **extra}
    top, ports = one_step(cfg, prop)
    status, secs, out = run_sby(workdir, "onestep",
                                rtlil.convert(top, name="onestep", ports=ports), 1, timeout_s,
                                solver=solver)
    secs += extra.get("products", {}).get("seconds", 0.0)
    if status != "fail":
        return {"property": prop, "status": status, "seconds": secs, "counterexample": None,
                **extra}
    # the engine that found the counterexample (one of two in a portfolio)
    vcd = next((Path(workdir) / "onestep").glob("engine_*/trace.vcd")).read_text()
    names = dict(re.findall(r"\$var wire \d+ (\S+) (\w+) ", vcd))
    cex = {}
    for bits, ident in re.findall(r"^b([01]+) (\S+)$", vcd, re.M):
        n = names.get(ident)
        if n in ("v", "u", "I", "sel") and n not in cex:
            cex[n] = signed_bits(bits) if n != "sel" else int(bits, 2)
    failed = re.findall(r"failed assertion (\S+)", out)
    return {"property": prop, "status": "fail", "seconds": secs, "counterexample": cex,
            "failed": failed, **extra}
