"""The learning stage against its one-operation specification, for every sequence of
operations of every length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The harness is built on the stage's ports: a :class:`~cuneate.hdl.plasticity.stage
.SynapseStage` made with ``observe=True`` (its ``obs_addr`` / ``obs_word`` port reads any
synapse word combinationally) takes free operations on its operation port, and a reference
written against the documented contract (:mod:`cuneate.hdl.plasticity.stage`) follows one
tracked synapse ``t`` (a free constant, so the proof holds for every synapse at once).

**What is proven.** For every sequence of operations (any op, address, spike bits, main
calcium within its format's proven range, CN drive total within ``K`` drives' range, apply
flag, host weight) in which two operations on ``t`` are at least
:data:`~cuneate.hdl.plasticity.config.STAGE_LATENCY` cycles apart (the stage's contract,
counted in ``hazard_count`` when broken):

* *the tracked word*: in every cycle the memory word of ``t`` equals the reference's, which
  starts as the memory's (any initial contents) and takes, four cycles after each operation on
  ``t``, :func:`~cuneate.hdl.plasticity.datapath.synapse_step` of the word it had when the
  operation was issued and the operation's operands (a ``read`` leaves it);
* *what leaves*: every operation's fetch (``fetch_valid``, ``fetch_op``) one cycle after its
  issue and its update (``upd_valid``, ``upd_op``, ``upd_addr``) four cycles after; for the
  operations on ``t`` the word as fetched (``fetch_w``, ``fetch_l``), the CN input sum's term
  (``contrib``) and the new word and its clamp flags (``upd_w``, ``upd_cd``, ``upd_cr``,
  ``upd_l``, ``upd_clamp``) equal the specification's;
* *bookkeeping*: ``busy`` is high exactly while an operation is in flight, and
  ``hazard_count`` counts exactly the operations issued to a synapse with a write-back in
  flight.

**Why the induction step closes**: the memory word of ``t`` is asserted equal to the reference
in every cycle, and everything else the stage holds (three stages of registers) is a function
of the last three cycles' operations, so an induction of :func:`induction_depth` steps
determines it.

**Abstractions**: the products of the stage functions (the calcium decays, ``C Z``, ``D``
times the step) are uninterpreted (:class:`~cuneate.hdl.lib.formal.UninterpretedProducts`: the
same function per source line in the stage and the reference, so every behaviour of the real
multipliers is covered; what they compute is the twin's bit-exact equality with the RTL). The
step table is the configuration's ROM (asserted whole in every cycle through ``obs_steps``: in
the base case its initializer holds it, in the induction step the invariant, nothing writing
it), the synapse memory free at the start (any initial contents). The proof is per configuration (its formats and constants), like the range proofs.
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Array, Cat, ClockDomain, Const, Elaboratable, Module, Mux, Signal, Value
from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import Fragment

from ..flow.sby import SOLVER
from ..lib.formal import (ProofResult, UninterpretedProducts, assert_all, assume_all,
                          harness_rtlil, run_proof)
from . import datapath as dp
from .config import OPS, STAGE_LATENCY, PlasticityConfig
from .stage import SynapseStage, unpack

__all__ = ["StageProof", "MUTANTS", "stage_harness", "prove_stage", "stage_proof_config",
           "induction_depth", "ABSTRACTIONS"]

ABSTRACTIONS = ["products of the stage functions uninterpreted (same function per multiplier "
                "in the stage and the reference)", "synapse memory with free initial contents",
                "step table: the configuration's"]


class _SkippedWrite(SynapseStage):
    """Mutant: the write-back skipped whenever the solver chooses."""

    def _write_enable(self, m, en):
        skip = Signal(name="mutant_skip")
        m.d.comb += skip.eq(AnySeq(1))
        return en & ~skip


def _mutant_stage(name: str):
    """A stage class with one fault (never the product's)."""
    if name == "skipped_write":
        return _SkippedWrite
    if name == "stale_drive":                  # the learn operation keeps the drive
        class Stale(SynapseStage):
            def _new_drive(self, is_int, L_int, c_L):
                return Mux(is_int, L_int, c_L)
        return Stale
    if name == "unflagged_weight_clamp":       # the weight's clamp acts without its flag
        class Silent(SynapseStage):
            def _clamp_bits(self, bits):
                return Cat(bits[0], bits[1], Const(0, 2))
        return Silent
    if name == "wrong_sign_table":             # the depression table for every step
        class Sign(SynapseStage):
            def _step_index(self, index):
                return index & ((1 << self.cfg.sigmoid_bits) - 1)
        return Sign
    raise ValueError(f"unknown mutant {name!r}; known: {', '.join(MUTANTS)}")


#: faults the harness can build into its stage (never into the product): the write-back skipped
#: whenever the solver chooses; a learn operation that keeps the drive instead of clearing it;
#: the weight's clamp without its flag; every step read from the depression table
MUTANTS = ("skipped_write", "stale_drive", "unflagged_weight_clamp", "wrong_sign_table")


class StageProof(Elaboratable):
    """Harness of :class:`~cuneate.hdl.plasticity.stage.SynapseStage` (see the module
    docstring); ``mutant`` one of :data:`MUTANTS` or ``None``."""

    def __init__(self, cfg: PlasticityConfig, mutant: str | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.cfg, self.mutant = cfg, mutant
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        m.domains.sync = self.cd
        n = cfg.n_targets * cfg.n_synapses
        cls = SynapseStage if self.mutant is None else _mutant_stage(self.mutant)
        dut = cls(cfg, observe=True)
        products = UninterpretedProducts()
        with products.role("design"):
            m.submodules.dut = Fragment.get(dut, platform)
        fmts = [f for _, f in cfg.synapse_fields]
        L4 = STAGE_LATENCY

        # free operations
        for name in ("op_valid", "op", "op_spike", "op_late", "op_apply", "op_addr", "op_z",
                     "op_total", "op_weight"):
            port = getattr(dut, name)
            m.d.comb += port.eq(AnySeq(len(port)))
        K = cfg.n_synapses
        assume_all(m, [dut.op_addr < n,
                       (dut.op_z >= cfg.z_bounds[0]) & (dut.op_z <= cfg.z_bounds[1]),
                       (dut.op_total >= K * cfg.L.min_raw) &
                       (dut.op_total <= K * cfg.L.max_raw)])

        # the tracked synapse, observed through the stage's port
        t = Signal(range(max(2, n)), name="tracked")
        m.d.comb += [t.eq(AnyConst(len(t))), dut.obs_addr.eq(t)]
        assume_all(m, [t < n])
        on_t = dut.op_valid & (dut.op_addr == t)

        def line(value, name, n_):
            out = [value]
            for k in range(1, n_ + 1):
                s = Signal(value.shape(), name=f"{name}_d{k}")
                m.d.sync += s.eq(out[-1])
                out.append(s)
            return out
        t_l = line(on_t, "tracked", L4)
        # the contract: two operations on one synapse at least STAGE_LATENCY cycles apart
        assume_all(m, [~(on_t & Cat(*t_l[1:L4]).any())])
        v_l = line(dut.op_valid, "valid", L4)
        op_l = line(dut.op, "op", L4)
        ad_l = line(dut.op_addr, "addr", L4)

        primed = Signal(name="primed")
        m.d.sync += primed.eq(1)
        ref = Signal(dut.word_width, name="ref_word")
        now = Signal(dut.word_width, name="ref_word_now")
        m.d.comb += now.eq(Mux(primed, ref, dut.obs_word))

        # the operation on t, taken as issued (word and operands), evaluated a cycle later
        held = {}
        for name, value in (("word", now), ("op", dut.op), ("spike", dut.op_spike),
                            ("late", dut.op_late), ("z", dut.op_z), ("total", dut.op_total),
                            ("apply", dut.op_apply), ("weight", dut.op_weight)):
            r = Signal(value.shape(), name=f"ref_in_{name}")
            with m.If(on_t):
                m.d.sync += r.eq(value)
            held[name] = r
        w, cd, cr, L = unpack(held["word"], fmts)
        table = Array(Const(x, cfg.step_bits) for x in cfg.step_table)
        with products.role("reference"):
            spec = dp.synapse_step(cfg, held["op"], w, cd, cr, L, held["spike"],
                                   held["late"], held["z"], held["total"], held["apply"],
                                   held["weight"], lambda i: Value.cast(table[i]))
        products.constrain(m, on_t)
        new = Cat(*[spec[k][:f.width] for k, f in zip(("w", "cd", "cr", "L"), fmts)])
        clamp = Cat(*[spec[k] for k in ("drive_low", "drive_high", "weight_low",
                                        "weight_high")])
        new_l = line(new, "new", L4 - 1)            # index k: k + 1 cycles after the issue
        clamp_l = line(clamp, "clamp", L4 - 1)
        # the write-back of an operation on t lands at the end of its fourth cycle
        lands = t_l[L4 - 1] & (op_l[L4 - 1] != OPS["read"])
        m.d.sync += ref.eq(Mux(lands, new_l[L4 - 2], now))

        checks = [(dut.obs_word == now, "tracked word"),
                  (dut.obs_steps == Cat(*table), "step table"),
                  (dut.fetch_valid == v_l[1], "fetch timing"),
                  (~v_l[1] | (dut.fetch_op == op_l[1]), "fetch op"),
                  (dut.upd_valid == v_l[L4], "update timing"),
                  (~v_l[L4] | ((dut.upd_op == op_l[L4]) & (dut.upd_addr == ad_l[L4])),
                   "update op and address"),
                  (dut.busy == Cat(*v_l[1:L4]).any(), "busy"),
                  (~t_l[1] | ((dut.fetch_w == w) & (dut.fetch_l == L)),
                   "tracked fetch: the word"),
                  (~t_l[1] | (dut.contrib == spec["contrib"][:len(dut.contrib)]),
                   "tracked fetch: contrib"),
                  (~t_l[L4] | (dut.upd_clamp == clamp_l[L4 - 1]), "tracked update: clamps")]
        exp = unpack(new_l[L4 - 1], fmts)
        for name, port, x in zip(("w", "cd", "cr", "l"),
                                 (dut.upd_w, dut.upd_cd, dut.upd_cr, dut.upd_l), exp):
            checks.append((~t_l[L4] | (port == x), f"tracked update: {name}"))

        # hazards: an operation issued to a synapse with a write-back in flight
        clash = dut.op_valid & Cat(*[v_l[k] & (op_l[k] != OPS["read"]) &
                                     (ad_l[k] == dut.op_addr)
                                     for k in range(1, L4)]).any()
        hz = Signal(len(dut.hazard_count), name="ref_hazards")
        hz_now = Signal(len(dut.hazard_count), name="ref_hazards_now")
        m.d.comb += hz_now.eq(Mux(primed, hz, dut.hazard_count))
        m.d.sync += hz.eq(hz_now + clash)
        checks.append((dut.hazard_count == hz_now, "hazard_count"))
        assert_all(m, checks)
        return m


def stage_proof_config(**kwargs) -> PlasticityConfig:
    """The configuration a stage proof runs on by default: 2 CNs of 2 synapses over 3
    afferents, unequal initial weights, a step table of 16 bins a sign, the default formats
    otherwise; ``kwargs`` override."""
    kw = dict(n_sources=3, sources=[[0, 2], [1, 2]], weights=[[1.0, 5.5], [0.25, 3.0]],
              sigmoid_bits=4, clock_hz=2000.0 * 40)
    kw.update(kwargs)
    return PlasticityConfig(**kw)


def induction_depth(cfg: PlasticityConfig) -> int:
    """The k of the k-induction: the stage's latency plus 2."""
    return STAGE_LATENCY + 2


def stage_harness(cfg: PlasticityConfig, mutant: str | None = None) -> str:
    """RTLIL of the harness (top ``stage_eq``), the synapse memory's initial contents removed."""
    return harness_rtlil(StageProof(cfg, mutant), "stage_eq", ("synapses",))


def prove_stage(cfg: PlasticityConfig, workdir: Path, mode: str = "prove",
                depth: int | None = None, mutant: str | None = None, timeout_s: float = 3600,
                engine: str = "smtbmc", solver: str = SOLVER) -> ProofResult:
    """Prove (``mode="prove"``: k-induction of ``depth`` steps, default
    :func:`induction_depth`) or check to a bound (``mode="bmc"``) that the learning stage
    equals its one-operation specification."""
    return run_proof("learning stage equals its one-operation specification",
                     stage_harness(cfg, mutant), workdir, "stage_eq", mode,
                     depth or induction_depth(cfg), timeout_s, engine, ABSTRACTIONS, solver)
