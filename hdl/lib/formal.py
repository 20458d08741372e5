"""What every proof harness of the project shares: uninterpreted products, reading a
component's registers, delay lines, free initial memory contents, and the run that turns a
harness into a verdict.

**Uninterpreted products** (:class:`UninterpretedProducts`). Every multiplier of a datapath is
formed by :func:`cuneate.hdl.lib.fixed.product`, named by its site; inside
:meth:`UninterpretedProducts.role` (which opens :func:`cuneate.hdl.lib.fixed.arithmetic_hooks`)
each product of Amaranth values becomes a fresh signal instead of a ``$mul`` cell. The
reference's products are free values chosen when the reference takes its inputs (held as long
as the update is in flight); every product the design forms at the same site is free too,
except that it equals the reference's product whenever its operands equal the reference's
operands. This is Ackermann's reduction of an uninterpreted function, restricted to the pairs
the proof compares: every behaviour of the real design (any function of the operands,
multiplication included) is a behaviour of the abstract one, so a property proven with the
abstraction holds for the real multipliers. What the products are - their width, their range,
their rounding - is the business of the one-step range proofs and of the twin's bit-exact
equality with the RTL, not of the pipeline proof.

**Binding to components.** A harness instantiates the component it proves (or a subclass that
overrides one of its documented hooks: the mutants), drives its ports and reads what the
component records after elaboration (the cores' ``issue``, ``tags``, ``memories`` ...). The
host link's components record nothing: their registers are found by name in the elaborated
fragment (:func:`signal_named`).
"""

from __future__ import annotations

import contextlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

from amaranth import ClockDomain, Elaboratable, Module, Mux, Signal, Value
from amaranth.asserts import AnySeq
from amaranth.hdl import Assert, Assume, Fragment

from ..flow.sby import SOLVER, FormalError, parse_sby_log, run_sby
from .fixed import arithmetic_hooks

__all__ = ["ClockedHarness", "UninterpretedProducts", "signal_named", "faulty_write", "delay_line",
           "free_memories", "harness_rtlil", "harness_depth", "prove_harness",
           "ProofResult", "run_proof", "assert_all", "check_id", "assume_all", "FormalError"]


# ----------------------------------------------------------------------------------------------
# uninterpreted products

@dataclass
class _Product:
    role: str
    site: str
    a: Value
    b: Value
    y: Signal


class UninterpretedProducts:
    """Every product :func:`~cuneate.hdl.lib.fixed.product` forms inside :meth:`role` made
    uninterpreted (see the module docstring). Use :meth:`role` around the elaboration of each
    side (``"design"`` and ``"reference"``), then :meth:`constrain` once."""

    def __init__(self):
        self.products: list[_Product] = []

    @contextlib.contextmanager
    def role(self, role: str):
        """Products formed inside this block belong to ``role``."""
        def hook(a, b, site):
            # integer constants are operands too; anything else is multiplied as written
            if not all(isinstance(x, (Value, int)) for x in (a, b)):
                return a * b
            a, b = Value.cast(a), Value.cast(b)
            y = Signal((a * b).shape(), name=f"product{len(self.products)}_{role}")
            self.products.append(_Product(role, site, a, b, y))
            return y

        with arithmetic_hooks(product=hook):
            yield self

    def constrain(self, m, capture) -> None:
        """Drive every product: the reference's are free values loaded when ``capture`` is
        high (the cycle the reference takes its inputs) and held until the next capture; the
        design's are free except equal to the reference's product of the same site whenever
        their operands are equal."""
        ref = [p for p in self.products if p.role == "reference"]
        held = []
        for j, p in enumerate(ref):
            r = Signal(p.y.shape(), name=f"{p.y.name}_held")
            with m.If(capture):
                m.d.sync += r.eq(AnySeq(p.y.shape()))
            # one function per site: a reference product whose operands equal an earlier
            # one's of the same site (a loop over traces sharing a constant) is it
            out = r
            for q in reversed(ref[:j]):
                if q.site == p.site and (len(q.a), len(q.b)) == (len(p.a), len(p.b)):
                    out = Mux((p.a == q.a) & (p.b == q.b), q.y, out)
            m.d.comb += p.y.eq(out)
            held.append(p.y)
        for p in self.products:
            if p.role == "reference":
                continue
            out = AnySeq(p.y.shape())
            for q, r in zip(ref, held):
                if q.site != p.site:
                    continue
                if (len(q.a), len(q.b)) != (len(p.a), len(p.b)):
                    # one site forming products of several shapes (a loop over traces with
                    # their own constants): a function per shape, so these two are unrelated
                    continue
                out = Mux((p.a == q.a) & (p.b == q.b), r, out)
            m.d.comb += p.y.eq(out)

    def count(self, role: str) -> int:
        return sum(p.role == role for p in self.products)


# ----------------------------------------------------------------------------------------------
# reading a component's registers

def signal_named(fragment: Fragment, name: str) -> Signal:
    """The one signal called ``name`` that ``fragment`` (not its subfragments) assigns.

    The signals a fragment assigns are what its statements' ``_lhs_signals()`` give: the one
    Amaranth method the harnesses call that is not public API (Amaranth 0.5 offers none that
    lists a fragment's assigned signals), kept to this function; the components proven here
    record what their harness reads instead."""
    found = {}
    for stmts in fragment.statements.values():
        for sig in stmts._lhs_signals():
            if sig.name == name:
                found[id(sig)] = sig
    if len(found) != 1:
        raise FormalError(f"expected one register {name!r} in the elaborated core, "
                          f"found {len(found)}")
    return next(iter(found.values()))


# ----------------------------------------------------------------------------------------------
# harness helpers

def faulty_write(m, port, skip=None, addr=None):
    """A stand-in for the write port ``port`` (``addr``, ``data``, ``en``) for a component's
    ``memory_write`` hook to return (a mutant): what the component drives on it reaches
    ``port`` with the enable gated by ``skip`` (a write skipped while it is high) and the
    address mapped by ``addr`` (a function of the address: a write landing elsewhere)."""
    fake = SimpleNamespace(addr=Signal.like(port.addr, name="mutant_wr_addr"),
                           data=Signal.like(port.data, name="mutant_wr_data"),
                           en=Signal(name="mutant_wr_en"))
    en = fake.en
    if skip is not None:
        gate = Signal(name="mutant_skip")
        m.d.comb += gate.eq(skip)
        en = en & ~gate
    m.d.comb += [port.addr.eq(fake.addr if addr is None else addr(fake.addr)),
                 port.data.eq(fake.data), port.en.eq(en)]
    return fake


def delay_line(m, sig, n: int, name: str) -> list:
    """``[sig, sig delayed 1, ..., sig delayed n]`` (registers named ``<name>_d<k>``)."""
    out = [sig]
    for k in range(1, n + 1):
        d = Signal.like(sig, name=f"{name}_d{k}")
        m.d.sync += d.eq(out[-1])
        out.append(d)
    return out


def check_id(name: str) -> str:
    """``name`` as the proofs report it: every run of characters other than letters, digits
    and ``_`` replaced by one ``_`` (``"stage 5: neuron"`` -> ``"stage_5_neuron"``)."""
    return re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_")


def assert_all(m, checks) -> None:
    """``Assert`` each ``(condition, name)``; the name stands in the assertion's source location,
    which is what SymbiYosys reports of a failed assertion (:func:`parse_sby_log`), as its
    :func:`check_id` (smtbmc cuts a location at the first space)."""
    for c, name in checks:
        check = Assert(c, name)
        check.src_loc = (check_id(name), 0)
        m.d.comb += check


def assume_all(m, conditions) -> None:
    m.d.comb += [Assume(c) for c in conditions]


_MEMINIT = r'(?:  attribute [^\n]*\n)*  cell \$meminit_v2 \S+\n    parameter \\MEMID "\\\\{}"\n.*?  end\n'


def free_memories(il: str, memids) -> str:
    """``il`` with the initial contents of the memories ``memids`` removed (and of their banks
    ``<memid>_1``, ``<memid>_2`` ..., :mod:`cuneate.hdl.lib.banked`): they start with any
    contents the solver picks (a proof then covers every initial contents, the design's
    included)."""
    for memid in memids:
        for bank in range(1 << 16):
            name = memid if bank == 0 else f"{memid}_{bank}"
            il, n = re.subn(_MEMINIT.format(re.escape(name)), "", il, flags=re.S)
            if n > 1:
                raise FormalError(f"expected at most one initializer of {name} in the "
                                  f"netlist, found {n}")
            if n == 0 and bank > 0:
                break
    return il


class ClockedHarness(Elaboratable):
    """A harness of ``dut`` on a reset-less clock domain (:attr:`cd`; the initial state is the
    registers' reset values, the induction step starts anywhere); :meth:`reg` delays a value."""

    def __init__(self, dut):
        self.dut = dut
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]

    def module(self, dut=None):
        """A module on :attr:`cd` holding ``dut`` (default the harness's) as ``dut``."""
        m = Module()
        m.domains.sync = self.cd
        m.submodules.dut = self.dut if dut is None else dut
        return m

    @staticmethod
    def free(m, *signals) -> None:
        """Each of ``signals`` any value in any cycle (``AnySeq``)."""
        for sig in signals:
            m.d.comb += sig.eq(AnySeq(len(sig)))

    def reg(self, m, value, name: str, init: int = 0) -> Signal:
        """``value`` one cycle late."""
        r = Signal.like(value, name=name, init=init)
        m.d.sync += r.eq(value)
        return r


def harness_rtlil(top, name: str, memories=()) -> str:
    """RTLIL of the proof harness ``top`` (top module ``name``), the initial contents of the
    memories ``memories`` removed. Converting elaborates the harness, which is when it reads
    what it needs from the design (its latency)."""
    from amaranth.back import rtlil
    return free_memories(rtlil.convert(top, name=name, ports=top.ports), memories)


def harness_depth(top, name: str, memories=()) -> int:
    """The k of the k-induction of the harness ``top``: its ``induction_depth``, which it reads
    from the design when elaborated."""
    harness_rtlil(top, name, memories)
    return top.induction_depth


# ----------------------------------------------------------------------------------------------
# the run

@dataclass
class ProofResult:
    """One property's verdict: ``status`` ``pass``/``fail``/``unknown``/``timeout``; ``mode``
    (``prove``: k-induction, ``bmc``: bounded from the initial state), ``depth``, ``engine``
    and ``solver``, ``seconds``; on failure the failed assertions, the step and the phase."""

    property: str
    status: str
    mode: str
    depth: int
    engine: str
    solver: str
    seconds: float
    failed: list = field(default_factory=list)
    step: int | None = None
    phase: str | None = None
    abstractions: list = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return self.status == "pass"

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def run_proof(prop: str, il: str, workdir: Path, name: str, mode: str, depth: int,
              timeout_s: float, engine: str = "smtbmc", abstractions=(),
              solver: str = SOLVER) -> ProofResult:
    """Run a harness's RTLIL (top module ``name``) and return its :class:`ProofResult`."""
    status, secs, log = run_sby(Path(workdir), name, il, depth, timeout_s, mode=mode,
                                engine=engine, solver=solver)
    info = parse_sby_log(log) if status in ("fail", "unknown") else {}
    return ProofResult(prop, status, mode, depth, engine,
                       solver if engine == "smtbmc" else "abc", secs,
                       info.get("failed", []), info.get("step"), info.get("phase"),
                       list(abstractions))


def prove_harness(prop: str, top, name: str, memories, workdir: Path, mode: str,
                  depth: int | None, timeout_s: float, engine: str = "smtbmc", abstractions=(),
                  solver: str = SOLVER) -> ProofResult:
    """:func:`run_proof` of the harness ``top`` (top module ``name``, ``memories`` free) to
    ``depth``, default its ``induction_depth``: one elaboration gives the RTLIL and k."""
    il = harness_rtlil(top, name, memories)
    return run_proof(prop, il, workdir, name, mode, depth or top.induction_depth, timeout_s,
                     engine, abstractions, solver)
