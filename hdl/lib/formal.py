"""What every proof harness of the project shares: uninterpreted products, observing a core's
internals without changing it, fault injection for mutants, delay lines, free initial memory
contents, and the run that turns a harness into a verdict.

**Uninterpreted products** (:class:`UninterpretedProducts`). While it is active, every product
``a * b`` of Amaranth values written in one of the given source files (the datapath's stage
functions) becomes a fresh signal instead of a ``$mul`` cell. The reference's products are free
values chosen when the reference takes its inputs (held as long as the update is in flight);
every product the design forms at the same source line is free too, except that it equals the
reference's product whenever its operands equal the reference's operands. This is Ackermann's
reduction of an uninterpreted function, restricted to the pairs the proof compares: every
behaviour of the real design (any function of the operands, multiplication included) is a
behaviour of the abstract one, so a property proven with the abstraction holds for the real
multipliers. What the products are - their width, their range, their rounding - is the
business of the one-step range proofs and of the twin's bit-exact equality with the RTL, not of
the pipeline proof.

**Observing without changing** (:func:`patched`, :func:`signal_named`). A harness elaborates
the core itself, with some of the helpers the core calls (``sweep_issue``, ``pipeline_tags``,
``core_memories``, ``registrar``, ``Memory`` ...) wrapped in the core's module namespace for
the duration of that call: the wrappers record what they return (the issue counter, the stage
tags, the memories, each stage register) and may substitute a faulty version (mutants). The
product's cores ship without any formal port or knob. Registers local to an ``elaborate`` are
found by name in the elaborated fragment (:func:`signal_named`).
"""

from __future__ import annotations

import contextlib
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

from amaranth import ClockDomain, Elaboratable, Module, Mux, Signal, Value
from amaranth.hdl import Assert, Assume, Fragment
from amaranth.hdl._ast import AnySeq, Assign, Switch

from ..flow.sby import SOLVER, FormalError, parse_sby_log, run_sby

__all__ = ["ClockedHarness", "UninterpretedProducts", "patched", "signal_named", "delay_line", "free_memories",
           "harness_rtlil",
           "ProofResult", "run_proof", "assert_all", "check_id", "assume_all", "FormalError"]


# ----------------------------------------------------------------------------------------------
# uninterpreted products

@dataclass
class _Product:
    role: str
    site: tuple
    a: Value
    b: Value
    y: Signal


class UninterpretedProducts:
    """Replace every product written in ``files`` by an uninterpreted one (see the module
    docstring). Use :meth:`role` around the elaboration of each side (``"design"`` and
    ``"reference"``), then :meth:`constrain` once."""

    def __init__(self, files):
        self.files = {str(Path(f).resolve()) for f in files}
        self.products: list[_Product] = []
        self._role = None

    @contextlib.contextmanager
    def role(self, role: str):
        """Products formed inside this block belong to ``role``."""
        orig_mul, orig_rmul = Value.__mul__, Value.__rmul__
        this = self

        def site(depth=2):
            f = sys._getframe(depth)
            path = str(Path(f.f_code.co_filename).resolve())
            # the bytecode offset tells two products written on one line apart
            return (path, f.f_lineno, f.f_lasti) if path in this.files else None

        def mul(a, b):
            where = site()
            if where is None or not isinstance(b, (Value, int)):
                return orig_mul(a, b)
            return this._product(where, a, Value.cast(b), orig_mul)

        def rmul(a, b):
            where = site()
            if where is None or not isinstance(b, int):
                return orig_rmul(a, b)
            return this._product(where, Value.cast(b), a, orig_mul)

        self._role = role
        Value.__mul__, Value.__rmul__ = mul, rmul
        try:
            yield self
        finally:
            Value.__mul__, Value.__rmul__ = orig_mul, orig_rmul
            self._role = None

    def _product(self, where, a, b, orig_mul):
        shape = orig_mul(a, b).shape()
        n = len(self.products)
        y = Signal(shape, name=f"product{n}_{self._role}")
        self.products.append(_Product(self._role, where, a, b, y))
        return y

    def constrain(self, m, capture) -> None:
        """Drive every product: the reference's are free values loaded when ``capture`` is
        high (the cycle the reference takes its inputs) and held until the next capture; the
        design's are free except equal to the reference's product of the same source line
        whenever their operands are equal."""
        ref = [p for p in self.products if p.role == "reference"]
        held = []
        for j, p in enumerate(ref):
            r = Signal(p.y.shape(), name=f"{p.y.name}_held")
            with m.If(capture):
                m.d.sync += r.eq(AnySeq(p.y.shape()))
            # one function per source line: a reference product whose operands equal an
            # earlier one's of the same line (a loop over traces sharing a constant) is it
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
                    # one line forming products of several shapes (a loop over traces with
                    # their own constants): a function per shape, so these two are unrelated
                    continue
                out = Mux((p.a == q.a) & (p.b == q.b), r, out)
            m.d.comb += p.y.eq(out)

    def count(self, role: str) -> int:
        return sum(p.role == role for p in self.products)


# ----------------------------------------------------------------------------------------------
# observing a core without changing it

@contextlib.contextmanager
def patched(namespace, name: str, wrapper):
    """Replace ``namespace.name`` by ``wrapper(original)`` for the duration of the block."""
    orig = getattr(namespace, name)
    setattr(namespace, name, wrapper(orig))
    try:
        yield
    finally:
        setattr(namespace, name, orig)


def _statements(stmts):
    for s in stmts:
        yield s
        if isinstance(s, Switch):
            for _patterns, body, _src_loc in s.cases:
                yield from _statements(body)


def signal_named(fragment: Fragment, name: str) -> Signal:
    """The one signal called ``name`` that ``fragment`` (not its subfragments) assigns."""
    found = {}

    for stmts in fragment.statements.values():
        for s in _statements(stmts):
            if isinstance(s, Assign):
                # every signal the target may write (through slices, parts and Array
                # elements)
                for sig in s.lhs._lhs_signals():
                    if sig.name == name:
                        found[id(sig)] = sig
    if len(found) != 1:
        raise FormalError(f"expected one register {name!r} in the elaborated core, "
                          f"found {len(found)}")
    return next(iter(found.values()))


# ----------------------------------------------------------------------------------------------
# harness helpers

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
