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

**The pipelined core against the one-step datapath.** :func:`core_vs_one_step` puts a small
core (external tick) beside a reference written against the core's documented contract, not its
registers:

* **host writes**: a write to the current or set RAM in cycle ``c`` is in the RAM from
  ``c + 1``; the update fetched in cycle ``f`` sees the RAM as it was ``pipeline_stages`` cycles
  before its result leaves (a write in the fetch cycle counts from the next sweep);
* **sweeps**: a tick starts a sweep when none is being issued or in its last issuing cycle,
  otherwise it is ignored and sets ``overrun``; the update fetched in cycle ``f`` leaves on
  ``upd_*`` in cycle ``f + pipeline_stages``, in index order;
* **each update** is one combinational step of the pipelined steps (bound at import so a fault
  injected into the core's copy does not reach the reference) from the state the update read;
* **state**: the state an update of neuron ``n`` reads is the state the previous update of
  ``n`` produced - across sweep boundaries, with back-to-back sweeps on the smallest core
  (5 neurons for a 5-stage pipeline: the read of a neuron's next update follows its write-back
  by one cycle);
* **bookkeeping**: ``sweep_done``, ``sweep_count``, ``sweep_number``, per-sweep clamp counters,
  sticky clamp flags and ``overrun``.

The state RAM starts with **arbitrary contents** (its initial value is removed from the
netlist), so every first update starts from any state the solver picks; ticks, host writes (any
neuron, any time, any value), ``clamp_clear`` and ``spike_ready`` are free inputs. The state an
update reads is taken at the core's first datapath registers (``IzhikevichCore.probes``); the
"state" property above ties it to the previous update's result, so together the checks say:
every update's result is the one-step function of the previous result, the current and the
set the contract gives it.

The check is **bounded**: :func:`prove_core` covers every input sequence of ``depth`` cycles
from power-up (depth 14 on 5 neurons: two complete back-to-back sweeps, every neuron read once
from the free RAM and once after its own write-back, host writes in flight throughout).
"""

from __future__ import annotations

import contextlib
import re
import time
from pathlib import Path

import numpy as np
from amaranth import Array, Cat, ClockDomain, Elaboratable, Module, Mux, Signal, signed
from amaranth.hdl import Assert, Assume

from ..flow.sby import FormalError, run_sby, signed_bits
from . import datapath as izh
from .config import CLAMP_KINDS, IzhikevichConfig
from .core import IzhikevichCore
from .formal_core import reference_update

__all__ = ["PROPERTIES", "one_step", "prove", "FormalError", "core_vs_one_step", "prove_core"]

PROPERTIES = ("datapath", "state_box", "steps")


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
        # the "steps" property's free products
        self.p_free = Signal(signed(48), name="p_free")
        self.m_free = Signal(signed(48), name="m_free")
        self.b_free = Signal(signed(48), name="b_free")

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        v, u, I = self.v, self.u, self.I
        n_sets = len(cfg.params)
        sel = self.sel if n_sets > 1 else 0
        checks: list = []
        with _recording_narrows(checks):
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


# ----------------------------------------------------------------------------------------------
# the pipelined core against the one-step datapath

class _CoreVsOneStep(Elaboratable):
    def __init__(self, cfg: IzhikevichConfig, write_latency: int | None = None):
        if cfg.tick_source != "external":
            raise ValueError("the equivalence harness drives the tick: use tick_source='external'")
        self.cfg = cfg
        # != the depth only to show the check is tight
        self.write_latency = cfg.pipeline_stages if write_latency is None else write_latency
        N = cfg.n_neurons
        self.core = IzhikevichCore(cfg)
        self.core._MustUse__silence = True     # elaborated by hand in elaborate()
        self.tick = Signal(name="tick")
        self.i_wr_en = Signal(name="i_wr_en")
        self.i_wr_addr = Signal(range(N), name="i_wr_addr")
        self.i_wr_data = Signal(cfg.I.shape(), name="i_wr_data")
        self.sel_wr_en = Signal(name="sel_wr_en")
        self.sel_wr_addr = Signal(range(N), name="sel_wr_addr")
        self.sel_wr_data = Signal(cfg.sel_bits, name="sel_wr_data")
        self.clamp_clear = Signal(name="clamp_clear")
        self.spike_ready = Signal(name="spike_ready")
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk, self.tick, self.i_wr_en, self.i_wr_addr, self.i_wr_data,
                      self.sel_wr_en, self.sel_wr_addr, self.sel_wr_data, self.clamp_clear,
                      self.spike_ready]

    def elaborate(self, platform):
        cfg, m, core = self.cfg, Module(), self.core
        N, n_sets, L = cfg.n_neurons, len(cfg.params), cfg.pipeline_stages
        # no reset input: step 0 is power-up; a later reset would clear registers, not RAMs
        m.domains.sync = self.cd
        m.submodules.core = core.elaborate(platform)    # elaborated here to reach its probes
        probe = core.probes
        for name in ("tick", "i_wr_en", "i_wr_addr", "i_wr_data", "sel_wr_en", "sel_wr_addr",
                     "sel_wr_data", "clamp_clear", "spike_ready"):
            m.d.comb += getattr(core, name).eq(getattr(self, name))
        m.d.comb += [Assume(self.i_wr_addr < N), Assume(self.sel_wr_addr < N),
                     Assume(self.sel_wr_data < n_sets)]

        def delayed(sig, k, name):
            for j in range(k):
                d = Signal.like(sig, name=f"{name}_d{j + 1}")
                m.d.sync += d.eq(sig)
                sig = d
            return sig

        # host-visible RAM contents: a write in cycle c is in the RAM from cycle c + 1
        cur = [Signal(cfg.I.shape(), name=f"ref_cur{n}") for n in range(N)]
        sel = [Signal(cfg.sel_bits, init=cfg.neuron_sets[n], name=f"ref_sel{n}")
               for n in range(N)]
        for n in range(N):
            with m.If(self.i_wr_en & (self.i_wr_addr == n)):
                m.d.sync += cur[n].eq(self.i_wr_data)
            with m.If(self.sel_wr_en & (self.sel_wr_addr == n)):
                m.d.sync += sel[n].eq(self.sel_wr_data)

        # the contract's sweep control: which neuron is fetched in this cycle
        left = Signal(range(N + 1), name="ref_left")
        overrun = Signal(name="ref_overrun")
        with m.If(self.tick & (left <= 1)):
            m.d.sync += left.eq(N)
        with m.Else():
            with m.If(left > 0):
                m.d.sync += left.eq(left - 1)
            with m.If(self.tick):
                m.d.sync += overrun.eq(1)
        fetch_valid = Signal(name="ref_fetch_valid")
        fetch_idx = Signal(range(N), name="ref_fetch_idx")
        m.d.comb += [fetch_valid.eq(left > 0), fetch_idx.eq(N - left)]
        exp_valid = delayed(fetch_valid, L, "ref_valid")
        exp_idx = delayed(fetch_idx, L, "ref_idx")
        exp_cur = Array(delayed(c, self.write_latency, f"ref_cur{n}") for n, c in enumerate(cur))
        exp_sel = Array(delayed(c, self.write_latency, f"ref_sel{n}") for n, c in enumerate(sel))
        i_ref, sel_ref = exp_cur[exp_idx], exp_sel[exp_idx]

        # one combinational step from the state the update read, computed in the cycle it is
        # read (the first datapath registers) and held until the result leaves (probe latency)
        pv0, pi0, v0, u0, i0, sel0 = (probe[k] for k in ("valid", "index", "v", "u", "i", "sel"))
        sel_arg = sel0 if n_sets > 1 else 0
        o = reference_update(cfg, v0, u0, i0, sel_arg)
        flags = izh.step_flags(o)
        now = {"valid": pv0, "index": pi0, "i": i0, "sel": sel0, "v": o["v_next"],
               "u": o["u_next"], "spike": o["spike"],
               "clamp": Cat(*(flags[k] for k in CLAMP_KINDS))}
        later = {k: delayed(x, probe["latency"], f"ref_step_{k}") for k, x in now.items()}
        pv, pi, i_in, sel_in = (later[k] for k in ("valid", "index", "i", "sel"))
        out, clamp_ref = later, later["clamp"]

        m.d.comb += Assert(core.upd_valid == exp_valid, "update timing")
        with m.If(exp_valid):
            m.d.comb += [Assert(core.upd_index == exp_idx, "update order"),
                         Assert(pv & (pi == exp_idx), "update tracked from its read"),
                         Assert(core.upd_current == i_ref, "current seen by the update"),
                         Assert(i_in == i_ref, "current used by the update"),
                         Assert(sel_in == sel_ref, "set used by the update"),
                         Assert(core.upd_v == out["v"], "v"),
                         Assert(core.upd_u == out["u"], "u"),
                         Assert(core.upd_spike == out["spike"], "spike"),
                         Assert(core.upd_clamp == clamp_ref, "clamp flags")]

        # the state an update reads is the previous update's result for that neuron
        sv = [Signal(cfg.V.shape(), name=f"ref_v{n}") for n in range(N)]
        su = [Signal(cfg.U.shape(), name=f"ref_u{n}") for n in range(N)]
        known = Signal(N, name="ref_known")
        with m.If(probe["valid"] & known.bit_select(probe["index"], 1)):
            m.d.comb += [Assert(probe["v"] == Array(sv)[probe["index"]], "v read back"),
                         Assert(probe["u"] == Array(su)[probe["index"]], "u read back")]
        with m.If(core.upd_valid):
            for n in range(N):
                with m.If(core.upd_index == n):
                    m.d.sync += [sv[n].eq(core.upd_v), su[n].eq(core.upd_u), known[n].eq(1)]

        # sweep bookkeeping
        done = Signal(name="ref_sweep_done")
        count = Signal(range(N + 1), name="ref_count")
        total = Signal(range(N + 1), name="ref_total")
        number = Signal(cfg.sweep_number_width, name="ref_number")
        started = Signal(name="ref_started")
        last = exp_valid & (exp_idx == N - 1)
        m.d.sync += done.eq(last)
        counts = [Signal(range(N + 1), name=f"ref_clamps_{k}") for k in CLAMP_KINDS]
        totals = [Signal(range(N + 1), name=f"ref_clamps_total_{k}") for k in CLAMP_KINDS]
        with m.If(exp_valid):
            with m.If(last):
                m.d.sync += [count.eq(0), total.eq(count + core.upd_spike),
                             number.eq(Mux(started, number + 1, 0)), started.eq(1)]
                m.d.sync += [c.eq(0) for c in counts]
                m.d.sync += [t.eq(c + core.upd_clamp[i])
                             for i, (c, t) in enumerate(zip(counts, totals))]
            with m.Else():
                m.d.sync += count.eq(count + core.upd_spike)
                m.d.sync += [c.eq(c + core.upd_clamp[i]) for i, c in enumerate(counts)]
        m.d.comb += Assert(core.sweep_done == done, "sweep_done")
        with m.If(done):
            m.d.comb += [Assert(core.sweep_count == total, "sweep_count"),
                         Assert(core.sweep_number == number, "sweep_number")]
            m.d.comb += [Assert(getattr(core, f"sweep_clamps_{k}") == t, f"sweep_clamps_{k}")
                         for k, t in zip(CLAMP_KINDS, totals)]
        sticky = Signal(len(CLAMP_KINDS), name="ref_clamp_flags")
        m.d.sync += sticky.eq(Mux(self.clamp_clear, 0, sticky) | core.upd_clamp)
        m.d.comb += [Assert(core.clamp_flags == sticky, "clamp_flags"),
                     Assert(core.overrun == overrun, "overrun")]
        return m


_STATE_INIT = re.compile(r'(?:  attribute [^\n]*\n)*  cell \$meminit_v2 \S+\n'
                         r'    parameter \\MEMID "\\\\state_mem"\n.*?  end\n', re.S)


def core_vs_one_step(cfg: IzhikevichConfig, **kwargs) -> str:
    """RTLIL of the equivalence harness, the state RAM's initial contents removed."""
    from amaranth.back import rtlil
    top = _CoreVsOneStep(cfg, **kwargs)
    il = rtlil.convert(top, name="core_eq", ports=top.ports)
    il, n = _STATE_INIT.subn("", il)
    if n != 1:
        raise FormalError(f"expected one state RAM initializer in the netlist, found {n}")
    return il


# Every multiplier (``$mul``) of core and reference replaced by one cheap, non-commutative function
# of its operands, the same everywhere: what the pipeline must get right - which operands meet in
# which cycle - is unchanged, while the solver no longer has to show two multipliers equal
# (with real multipliers z3 does not finish depth 9 in 240 s).
_ABSTRACT_MUL = """(* techmap_celltype = "$mul" *)
module _abstract_mul (A, B, Y);
  parameter A_SIGNED = 0;
  parameter B_SIGNED = 0;
  parameter A_WIDTH = 1;
  parameter B_WIDTH = 1;
  parameter Y_WIDTH = 1;
  input [A_WIDTH-1:0] A;
  input [B_WIDTH-1:0] B;
  output [Y_WIDTH-1:0] Y;
  \\$sub #(.A_SIGNED(A_SIGNED), .B_SIGNED(B_SIGNED), .A_WIDTH(A_WIDTH), .B_WIDTH(B_WIDTH),
          .Y_WIDTH(Y_WIDTH)) _TECHMAP_REPLACE_ (.A(A), .B(B), .Y(Y));
endmodule
"""


def prove_core(cfg: IzhikevichConfig, workdir: Path, depth: int = 14,
               timeout_s: float = 3600, abstract_multipliers: bool = True, **kwargs) -> dict:
    """Bounded check of the pipelined core against the one-step reference for every input
    sequence of ``depth`` cycles from power-up; returns ``{"property", "status", "seconds",
    "depth", "failed", "step"}`` (the failed assertions and the failing step).
    ``abstract_multipliers``: every multiplier replaced by the same stand-in (see above)."""
    extra, script = {}, ""
    if abstract_multipliers:
        extra = {"abstract_mul.v": _ABSTRACT_MUL}
        script = "techmap -map abstract_mul.v t:$mul\nopt_clean\n"
    status, secs, out = run_sby(workdir, "core_eq", core_vs_one_step(cfg, **kwargs), depth,
                                timeout_s, options="--unroll", script=script,
                                extra_files=extra)
    res = {"property": "equivalence", "status": status, "seconds": secs, "depth": depth,
           "failed": [], "step": None}
    if status == "fail":
        res["failed"] = sorted(set(re.findall(r"Assert failed in \S+: (.+?)(?: \(|$)", out,
                                              re.M)))
        steps = re.findall(r"Checking assertions in step (\d+)", out)
        res["step"] = int(steps[-1]) if steps else None
    return res
