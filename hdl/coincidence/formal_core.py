"""The coincidence detector against its one-tick reference, for every input sequence of every
length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The detector is not a pipeline of neurons but a schedule per tick (:mod:`cuneate.hdl
.coincidence.core`): on a tick taken while idle the pending input spikes are stamped into the
history ring, then each target in turn accumulates its delayed inputs (one source a cycle, read
through the delay/weight ROM and the ring) and runs four update cycles. The harness states that
schedule as a contract and checks the core against it.

**What is proven.** The detector beside a reference written against the documented contract:

* *ticks*: a tick is taken when the detector is idle (otherwise it sets ``tick_overrun`` and is
  counted in ``overrun_count``); a taken tick processes targets ``0 .. M-1``, ``P = S + 6``
  cycles each (``S`` sources), and target ``k``'s update leaves on ``upd_*`` ``(k + 1) P + 1``
  cycles after the tick; ``busy`` is high from the cycle after the tick to the last target's
  write-back; ``tick_count`` counts processed ticks;
* *input spikes*: an event sets its source's bit in the pending vector; a taken tick stamps the
  pending vector as that tick's spikes (an event on the tick's own cycle goes to the next
  tick); a second event of a source before the next taken tick is counted in ``merged_count``;
* *each update of the tracked target* ``t`` (a free constant) equals one step of the detector's
  stage functions composed combinationally (:func:`psp_current`, the Izhikevich ``operands``,
  ``multiply1``, ``multiply2``, ``update_state``, the trace products and updates) from the
  state its previous update produced (or the memory's initial contents) and the input
  ``a = sum_s w[t, s] x_s(T - delay[t, s])``: the spikes stamped ``delay`` ticks before the
  tick ``T`` being processed, with the configuration's delays and weights;
* *bookkeeping*: ``spike_*`` (one event per spiking update, target and tick), ``upd_tick``,
  the sticky ``clamp_flags`` with ``clamp_clear``.

The reference keeps the history as the last ``D`` stamped words **by age** (``age[j]`` the
spikes of tick ``T - j``), not by ring slot: it never computes a slot, so a core that reads or
writes the wrong slot disagrees with it.

**Why the induction step closes** - the invariants asserted in every cycle: the core's
``busy`` and target counter equal the schedule model's, its ring slot and tick counter equal
the model's tick count, its pending vector equals the model's, every history word equals the
model's word of the age that slot holds (``mem[(T - j) mod D] = age[j]``), the tracked target's
state word equals the reference's last result, the counters equal the model's. What is left -
the FSM's phase within a target, the source counter, the read-pipeline valid bits and the
accumulator - is a function of the last ``P + 1`` cycles once the target counter is pinned, so
an induction of ``P + 2`` steps determines it (:func:`induction_depth`).

**Binding to the detector.** The harness instantiates :class:`~cuneate.hdl.coincidence
.CoincidenceDetector`, drives its ports and reads what it records when elaborated (its
memories and its schedule's target, slot and pending registers); to read the memories' words
it adds asynchronous read ports through a subclass. The **mutants** are subclasses overriding
the detector's documented hooks: ``memory_write`` (the state's write-back skipped, the
history's stamp one slot on) and ``history_address`` (the delayed input read one slot late).

**Abstractions.** The products of the Izhikevich datapath and of the synaptic traces are
uninterpreted (the same function per site in the core and the reference:
:class:`~cuneate.hdl.lib.formal.UninterpretedProducts`); the state and history memories start
with any contents; the delay/weight ROM is the configuration's (the proof is per delay and
weight table, like the range proofs); the tick input is free (an internal divider's ticks are
among its sequences).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from amaranth import Array, Cat, ClockDomain, Const, Elaboratable, Module, Mux, Signal
from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import Fragment

from ..flow.sby import SOLVER
from ..izhikevich import multiply1, multiply2, operands, update_state
from ..lib.datapath import lookup
from ..lib.formal import (ProofResult, UninterpretedProducts, assert_all, assume_all,
                          faulty_write, harness_rtlil, run_proof)
from ..lib.synapses import trace_products, trace_update
from .config import CLAMP_KINDS, CoincidenceConfig
from .core import CoincidenceDetector
from .datapath import accumulate, clamp_bits_hdl, history_slot, psp_current

__all__ = ["CoincidenceProof", "coincidence_harness", "prove_coincidence",
           "coincidence_proof_config", "induction_depth", "prove_history_slot", "MUTANTS",
           "ABSTRACTIONS"]

#: faults the harness can build into its copy of the detector (never into the product): the
#: state write-back skipped whenever the solver chooses; the delayed input read one slot late
#: (the spikes of tick ``T - delay + 1``); the pending spikes stamped into the next tick's slot
MUTANTS = ("skipped_write", "wrong_slot", "stamp_wrong_slot")

#: what the proof abstracts, for reports
ABSTRACTIONS = ["products of the Izhikevich and trace datapaths uninterpreted (same function "
                "per multiplier in detector and reference)", "tick free (covers the internal "
                "divider)", "state and history memories with free initial contents",
                "delay/weight ROM: the configuration's table"]

#: cycles of a target beyond one per source: two read latencies, four update cycles
EXTRA_CYCLES = 6


class _SkippedWrite(CoincidenceDetector):
    """The state's write-back skipped whenever the solver chooses."""

    def memory_write(self, m, name, port):
        port = super().memory_write(m, name, port)
        return faulty_write(m, port, skip=AnySeq(1)) if name == "state_mem" else port


class _StampWrongSlot(CoincidenceDetector):
    """The pending spikes stamped into the next tick's history slot."""

    def memory_write(self, m, name, port):
        port = super().memory_write(m, name, port)
        if name != "hist_mem":
            return port
        last = self.cfg.max_delay_ticks - 1
        return faulty_write(m, port, addr=lambda a: Mux(a == last, 0, a + 1))


class _WrongSlot(CoincidenceDetector):
    """The delayed input read from the slot of tick ``T - delay + 1``."""

    def history_address(self, slot, delay):
        return super().history_address(slot + 1, delay) % self.cfg.max_delay_ticks


DETECTORS = {"skipped_write": _SkippedWrite, "stamp_wrong_slot": _StampWrongSlot,
             "wrong_slot": _WrongSlot}


def _watched(detector: type, history_depth: int, rom_words: int) -> type:
    """``detector`` with asynchronous read ports on its memories for the harness (``watch``:
    one on the state, one per history slot, one per ROM word), added through the memories it
    records."""
    class Watched(detector):
        def elaborate(self, platform):
            m = super().elaborate(platform)
            mems = self.memories
            self.watch = {"state_mem": mems["state_mem"].read_port(domain="comb"),
                          "hist_mem": [mems["hist_mem"].read_port(domain="comb")
                                       for _ in range(history_depth)],
                          "dw_mem": [mems["dw_mem"].read_port(domain="comb")
                                     for _ in range(rom_words)]}
            return m
    return Watched


class CoincidenceProof(Elaboratable):
    """Harness of :class:`~cuneate.hdl.coincidence.CoincidenceDetector` (see the module
    docstring); ``mutant`` one of :data:`MUTANTS` or ``None``."""

    def __init__(self, cfg: CoincidenceConfig, mutant: str | None = None,
                 detector: type | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.cfg, self.mutant = cfg, mutant
        self.detector = detector or DETECTORS.get(mutant, CoincidenceDetector)
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]
        self.period = cfg.n_sources + EXTRA_CYCLES

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        m.domains.sync = self.cd
        M, S, D, P = cfg.n_targets, cfg.n_sources, cfg.max_delay_ticks, self.period
        products = self.products = UninterpretedProducts()
        t = Signal(range(max(2, M)), name="tracked")
        m.d.comb += t.eq(AnyConst(len(t)))
        assume_all(m, [t < M])

        core = _watched(self.detector, D, M * S)(cfg)
        with products.role("design"):
            m.submodules.core = Fragment.get(core, platform)
        st_port = core.watch["state_mem"]
        m.d.comb += st_port.addr.eq(t)
        hist_words = []
        for k, p in enumerate(core.watch["hist_mem"]):
            m.d.comb += p.addr.eq(k)
            hist_words.append(p.data)
        # the delay/weight ROM holds the configuration's table (in the base case by its
        # initializer, in the induction step by this invariant: nothing writes it)
        rom_checks = []
        for k, (p, want) in enumerate(zip(core.watch["dw_mem"],
                                          CoincidenceDetector.delay_weight_rom(cfg))):
            m.d.comb += p.addr.eq(k)
            rom_checks.append((p.data == want, f"delay/weight ROM: word {k}"))
        assert_all(m, rom_checks)
        sched = core.schedule

        # free inputs
        for name in ("tick", "in_valid", "clamp_clear"):
            m.d.comb += getattr(core, name).eq(AnySeq(1))
        m.d.comb += core.in_source.eq(AnySeq(len(core.in_source)))
        assume_all(m, [core.in_source < S])
        tick = core.tick

        # --- the contract's schedule --------------------------------------------------------
        busy = Signal(name="ref_busy")
        tgt = Signal(range(max(2, M)), name="ref_tgt")
        ph = Signal(range(P), name="ref_phase")
        ticks = Signal(len(core.tick_count), name="ref_ticks")
        slot = Signal(range(D), name="ref_slot")
        take = tick & ~busy
        last = busy & (ph == P - 1)                      # a target's write-back cycle
        with m.If(take):
            m.d.sync += [busy.eq(1), tgt.eq(0), ph.eq(0)]
        with m.Elif(busy):
            with m.If(ph == P - 1):
                m.d.sync += ph.eq(0)
                with m.If(tgt == M - 1):
                    m.d.sync += [busy.eq(0), ticks.eq(ticks + 1),
                                 slot.eq(Mux(slot == D - 1, 0, slot + 1))]
                with m.Else():
                    m.d.sync += tgt.eq(tgt + 1)
            with m.Else():
                m.d.sync += ph.eq(ph + 1)
        overruns = Signal(len(core.overrun_count), name="ref_overruns")
        overrun = Signal(name="ref_overrun")
        with m.If(tick & busy):
            m.d.sync += [overruns.eq(overruns + 1), overrun.eq(1)]
        assert_all(m, [((tgt < M) & (ph < P) & (slot < D), "schedule model: in range"),
                       (core.busy == busy, "schedule: busy"),
                       (~busy | (sched.target == tgt), "schedule: target"),
                       (sched.slot == slot, "history: slot"),
                       (core.tick_count == ticks, "tick_count"),
                       (core.overrun_count == overruns, "overrun_count"),
                       (core.tick_overrun == overrun, "tick_overrun")])

        # --- input spikes ------------------------------------------------------------------
        pending = Signal(S, name="ref_pending")
        merged = Signal(len(core.merged_count), name="ref_merged")
        event = Mux(core.in_valid, Const(1, S) << core.in_source, 0)
        with m.If(take):
            m.d.sync += pending.eq(event)
        with m.Else():
            m.d.sync += pending.eq(pending | event)
            with m.If(core.in_valid & (pending & (Const(1, S) << core.in_source)).any()):
                m.d.sync += merged.eq(merged + 1)
        assert_all(m, [(sched.pending == pending, "input spikes: pending"),
                       (core.merged_count == merged, "merged_count")])

        # --- the history by age ---------------------------------------------------------------
        primed = Signal(name="ref_primed")      # step 0: the reference takes the memories' words
        m.d.sync += primed.eq(1)
        # the slot of age 0: the tick being processed, or (idle) the last one processed
        newest = Mux(busy, slot, Mux(slot == 0, D - 1, slot - 1))
        words = Array(hist_words)
        age, age_now = [], []
        for j in range(D):
            at = Signal(range(D), name=f"ref_slot_of_age{j}")
            m.d.comb += at.eq(Mux(newest >= j, newest - j, newest + D - j))
            r = Signal(S, name=f"ref_age{j}")
            now = Signal(S, name=f"ref_age{j}_now")
            m.d.comb += now.eq(Mux(primed, r, words[at]))
            assert_all(m, [(words[at] == now, f"history: age {j}")])
            age.append(r)
            age_now.append(now)
        with m.If(take):
            m.d.sync += [age[0].eq(pending)] + [age[j].eq(age_now[j - 1]) for j in range(1, D)]
        with m.Else():
            m.d.sync += [age[j].eq(age_now[j]) for j in range(D)]

        # --- the tracked target -----------------------------------------------------------------
        state = Signal.like(st_port.data, name="ref_state")
        state_now = Signal.like(st_port.data, name="ref_state_now")
        m.d.comb += state_now.eq(Mux(primed, state, st_port.data))
        assert_all(m, [(st_port.data == state_now, "memory state_mem: tracked word")])
        mine = busy & (tgt == t)
        with products.role("reference"):
            exp = self.reference(state_now, age_now, t)
        products.constrain(m, mine & (ph == 0))
        m.d.sync += state.eq(Mux(last & (tgt == t), exp["word"], state_now))

        # what leaves on the ports the cycle after a write-back
        upd = Signal(name="ref_upd")
        upd_tgt = Signal.like(tgt, name="ref_upd_tgt")
        upd_tick = Signal.like(ticks, name="ref_upd_tick")
        tracked = Signal(name="ref_upd_tracked")
        m.d.sync += [upd.eq(last), upd_tgt.eq(tgt), upd_tick.eq(ticks),
                     tracked.eq(last & (tgt == t))]
        held = {}
        for port, value in exp["ports"].items():
            h = Signal.like(getattr(core, port), name=f"ref_{port}")
            m.d.sync += h.eq(value)
            held[port] = h
        checks = [(core.upd_valid == upd, "update timing"),
                  (~upd | (core.upd_target == upd_tgt), "update order"),
                  (~upd | (core.upd_tick == upd_tick), "upd_tick"),
                  (core.spike_valid == (upd & core.upd_spike), "spike_valid"),
                  (~upd | (core.spike_target == upd_tgt), "spike_target"),
                  (~upd | (core.spike_tick == upd_tick), "spike_tick")]
        checks += [(~tracked | (getattr(core, port) == h), f"tracked update: {port}")
                   for port, h in held.items()]
        assert_all(m, checks)

        # sticky clamp flags: cleared by clamp_clear, or-ed with each update's flags
        base = Signal(len(CLAMP_KINDS), name="ref_clamp_base")
        clear_d = Signal(name="ref_clear_d")
        flags = Signal(len(CLAMP_KINDS), name="ref_clamp_flags")
        m.d.comb += flags.eq(base | Mux(core.upd_valid & ~clear_d, core.upd_clamp, 0))
        m.d.sync += [base.eq(Mux(core.clamp_clear, 0, flags)), clear_d.eq(core.clamp_clear)]
        assert_all(m, [(core.clamp_flags == flags, "clamp_flags")])
        return m

    def reference(self, word, age, t):
        """One update of target ``t`` from its state ``word`` and the history by ``age``: the
        delayed weighted input sum, then the stage functions composed combinationally."""
        cfg, iz = self.cfg, self.cfg.iz
        S = cfg.n_sources
        widths = [iz.V.width, iz.U.width, cfg.traces[0].T.width, cfg.traces[1].T.width]
        pos = np.cumsum([0] + widths)
        v0, u0, xd0, xr0 = (word[pos[k]:pos[k + 1]].as_signed() for k in range(4))
        a = Const(0, cfg.acc_bits)
        ages = Array(age)
        for s in range(S):
            d = Array(Const(int(cfg.delays[k, s]), range(cfg.max_delay_ticks))
                      for k in range(cfg.n_targets))[t]
            w = Array(Const(int(cfg.weights_raw[k, s]), cfg.W.width)
                      for k in range(cfg.n_targets))[t]
            a = accumulate(a, ages[d][s], w)[:cfg.acc_bits]
        sel = lookup(cfg.target_sets_, t)
        i1, ys = psp_current(cfg, xd0, xr0, a)
        s2 = operands(iz, v0, u0, i1, sel)
        s3 = multiply1(iz, s2["wq"], s2["vq"], s2["x"], u0, sel)
        xs = trace_update(cfg.tview, ys, trace_products(cfg.tview, ys))
        s4 = multiply2(iz, s3["q"], s3["bvp"], s3["uy"], s2["wq"], v0, u0, s3["x"], sel)
        out = update_state(iz, *(s4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh",
                                                 "p", "m")), sel)
        clamp = clamp_bits_hdl(dict(out, current=s2["i_flag"], y=s4["y_flag"]))
        v1, u1 = out["v"][:iz.V.width], out["u"][:iz.U.width]
        xd1, xr1 = xs[0][:widths[2]], xs[1][:widths[3]]
        return {"word": Cat(v1, u1, xd1, xr1),
                "ports": {"upd_v": v1, "upd_u": u1, "upd_xd": xd1, "upd_xr": xr1, "upd_a": a,
                          "upd_i": s2["i"], "upd_spike": out["spike"], "upd_clamp": clamp}}


def coincidence_proof_config(**kwargs) -> CoincidenceConfig:
    """The configuration a detector proof runs on by default: 2 sources, 2 targets, a history
    of 3 ticks, delays covering 0, 1 and the deepest slot, unequal weights, external tick at
    the fewest cycles the schedule needs; ``kwargs`` override."""
    kw = dict(n_sources=2, n_targets=2, max_delay_ticks=3, delays_ticks=[[0, 2], [1, 0]],
              weights=[[8.0, 4.0], [2.0, 8.0]], tick_source="external")
    kw.update(kwargs)
    cfg = CoincidenceConfig(**kw)
    if "clock_hz" not in kwargs:
        kw["clock_hz"] = cfg.cycles_needed * cfg.update_hz
        cfg = CoincidenceConfig(**kw)
    return cfg


def coincidence_harness(cfg: CoincidenceConfig, mutant: str | None = None,
                        detector: type | None = None) -> str:
    """RTLIL of the harness (top ``coincidence_eq``), the state and history memories' initial
    contents removed; ``detector``: a subclass of :class:`CoincidenceDetector` to prove
    instead."""
    return harness_rtlil(CoincidenceProof(cfg, mutant, detector), "coincidence_eq",
                         ("state_mem", "hist_mem"))


def induction_depth(cfg: CoincidenceConfig) -> int:
    """The k of the k-induction: a target's period ``S + 6`` plus 2."""
    return cfg.n_sources + EXTRA_CYCLES + 2


def prove_coincidence(cfg: CoincidenceConfig, workdir: Path, mode: str = "prove",
                      depth: int | None = None, mutant: str | None = None,
                      timeout_s: float = 3600, engine: str = "smtbmc",
                      solver: str = SOLVER, detector: type | None = None) -> ProofResult:
    """Prove (``mode="prove"``: k-induction of ``depth`` steps, default
    :func:`induction_depth`) or check to a bound (``mode="bmc"``) that the detector equals its
    one-tick reference; ``detector``: a subclass of :class:`CoincidenceDetector` to prove
    instead (a fault of its own)."""
    return run_proof("coincidence detector equals one-tick reference",
                     coincidence_harness(cfg, mutant, detector), workdir, "coincidence_eq", mode,
                     depth or induction_depth(cfg), timeout_s, engine, ABSTRACTIONS, solver)


class HistorySlotProof(Elaboratable):
    """:func:`~cuneate.hdl.coincidence.datapath.history_slot` as the detector forms it (a ring
    slot of ``range(depth)``, a delay field of ``delay_bits``) names the ring slot of the delayed
    tick for every slot and every delay below ``depth``: the slot is below ``depth`` and slot +
    delay is the tick's slot modulo ``depth``; ``slot``: the function proven (a faulty one: a
    test of the proof)."""

    def __init__(self, depth: int, delay_bits: int, slot=history_slot):
        self.depth, self.delay_bits, self.slot = depth, delay_bits, slot
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]

    def elaborate(self, platform):
        m, D = Module(), self.depth
        m.domains.sync = self.cd
        slot, delay = Signal(range(D), name="slot"), Signal(self.delay_bits, name="delay")
        m.d.comb += [slot.eq(AnySeq(len(slot))), delay.eq(AnySeq(len(delay)))]
        assume_all(m, [slot < D, delay < D])
        at = self.slot(slot, delay, D)
        assert_all(m, [((at >= 0) & (at < D), "history slot: in the ring"),
                       ((at + delay == slot) | (at + delay == slot + D),
                        "history slot: the delayed tick's")])
        return m


def prove_history_slot(cfg: CoincidenceConfig, workdir: Path, timeout_s: float = 600,
                       solver: str = SOLVER, slot=history_slot) -> ProofResult:
    """The history address of ``cfg``'s detector (its ring depth and delay field width) is the
    delayed tick's slot for every slot and delay: one combinational step, every input;
    ``slot``: see :class:`HistorySlotProof`."""
    il = harness_rtlil(HistorySlotProof(cfg.max_delay_ticks, cfg.history_addr_bits, slot),
                       "history_slot")
    return run_proof("history slot is the delayed tick's", il, workdir, "history_slot", "bmc",
                     1, timeout_s, "smtbmc", [], solver)
