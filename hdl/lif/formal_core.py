"""The pipelined LIF core against its one-step datapath, for every input sequence of every
length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The harness is :class:`cuneate.hdl.lib.core_proof.SweepCoreProof` (the contract, the pipeline
invariants, the tracked neuron, the uninterpreted products: see there and docs/formal.md); this
module gives it the LIF core and the reference: one combinational step of the stage functions
(``gather_input``, ``leak_operand``, ``leak_product``, ``update_state``, bound at import) from
the tracked neuron's state word (``v`` and the refractory counter), current and set.

Covered: every LIF core: with or without input spikes (the contract's pending and active spike
vectors are modelled in :meth:`LifCoreProof.fetched_inputs`; weights fixed, with any contents,
or host-written), with synaptic traces (AMPA/GABA's four, or the current synapse's one: the
trace memory is a second state memory, written back with the state, its products
uninterpreted like the leak's) or without.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amaranth import Cat, Const, Mux, Signal
from amaranth.asserts import AnySeq

from ..flow.sby import SOLVER
from ..lib.core_proof import MUTANTS, SweepCoreProof
from ..lib.formal import ProofResult, assert_all, assume_all, harness_rtlil, prove_harness
from .config import CLAMP_KINDS, LifConfig
from .core import LifCore
from .datapath import gather_input, leak_operand, leak_product, update_state
from ..lib.synapses import trace_products, trace_update

__all__ = ["LifCoreProof", "lif_harness", "prove_lif", "lif_proof_config", "MUTANTS",
           "ABSTRACTIONS"]

#: what the proof abstracts, for reports
ABSTRACTIONS = ["products of the datapath uninterpreted (same function per multiplier in core "
                "and reference)", "tick free (covers the internal divider)",
                "memories with free initial contents"]


class LifCoreProof(SweepCoreProof):
    """The LIF core, with or without synaptic traces (see
    :class:`~cuneate.hdl.lib.core_proof.SweepCoreProof`)."""

    core_class = LifCore
    clamp_kinds = CLAMP_KINDS
    off_by_one_register = ("v", 4)          # stage 4's v: the previous neuron's

    def __init__(self, cfg: LifConfig, mutant: str | None = None, core: type | None = None):
        super().__init__(cfg, mutant, core)
        if cfg.traces:
            # the traces are a second state memory, written back with the state; their
            # products (one per trace) are uninterpreted like the leak's
            self.state_memories = ("state_mem", "trace_mem")

    def host_write_ports(self) -> dict:
        ports = dict(self.host_memories)
        if self.cfg.n_inputs and self.cfg.weights_writable:
            ports["weight_mem"] = "w_wr"
        return ports

    def read_only_memories(self) -> tuple:
        return ("weight_mem",) if self.cfg.n_inputs and not self.cfg.weights_writable else ()

    def fetched_inputs(self, m, core, fetch) -> dict:
        """The contract's input spikes: events (free) set a source's bit in the pending
        vector; a sweep's start moves it into the active vector (and the event of that cycle
        into the new pending one); a second event of a source within one tick sets
        ``in_merged``. The core's vectors and flag must equal the model's in every cycle; an
        update uses the active vector of its fetch cycle."""
        F = self.cfg.n_inputs
        if not F:
            return {}
        m.d.comb += [core.in_valid.eq(AnySeq(1)), core.in_source.eq(AnySeq(len(core.in_source)))]
        assume_all(m, [core.in_source < F])
        pending, active = Signal(F, name="ref_pending"), Signal(F, name="ref_active")
        merged = Signal(name="ref_in_merged")
        event = Mux(core.in_valid, Const(1, F) << core.in_source, 0)
        start = self.sweep_start
        with m.If(start):
            m.d.sync += [active.eq(pending), pending.eq(event)]
        with m.Else():
            m.d.sync += pending.eq(pending | event)
            with m.If(core.in_valid & (pending & (Const(1, F) << core.in_source)).any()):
                m.d.sync += merged.eq(1)
        assert_all(m, [(core.input_spikes.pending == pending, "input spikes: pending"),
                       (core.input_spikes.active == active, "input spikes: active"),
                       (core.in_merged == merged, "input spikes: in_merged")])
        return {"x": active}

    def reference(self, words, inputs):
        cfg = self.cfg
        V, R = cfg.V, cfg.ref_bits
        st = words["state_mem"]
        v = st[:V.width].as_signed()
        ref = st[V.width:] if R else Const(0, 1)
        i, sel = words["cur_mem"], words["sel_mem"]
        F, wb = cfg.n_inputs, cfg.W.width
        x = inputs.get("x")
        w = words.get("weight_mem")
        tr = None
        if cfg.traces:
            offs = np.cumsum([0] + [t.T.width for t in cfg.traces])
            tw = words["trace_mem"]
            tr = [tw[offs[j]:offs[j + 1]].as_signed() for j in range(len(cfg.traces))]
        g = gather_input(cfg, i, [x[k] for k in range(F)],
                         [w[wb * k: wb * (k + 1)].as_signed() for k in range(F)], tr)
        p = leak_product(cfg, leak_operand(cfg, v, g["d"], sel), sel)
        o = update_state(cfg, v, p, g["d"], ref, sel)
        flags = {"current": g["current"], "input": g["input"], "v_low": o["v_low"]}
        v_new, ref_new = o["v"], o["ref"]
        word = Cat(v_new[:V.width], ref_new[:R]) if R else v_new[:V.width]
        out = {"words": {"state_mem": word},
               "ports": {"upd_v": v_new, "upd_ref": ref_new[:max(1, R)],
                         "upd_spike": o["spike"],
                         "upd_clamp": Cat(*(flags[k] for k in CLAMP_KINDS)),
                         "upd_current": i, "upd_acc": g["acc"]}}
        if cfg.traces:
            new = trace_update(cfg, g["ys"], trace_products(cfg, g["ys"]))
            fields = [x[:t.T.width] for t, x in zip(cfg.traces, new)]
            out["words"]["trace_mem"] = Cat(*fields)
            out["ports"] |= {f"upd_{t.name}": x.as_signed()     # the ports are signed
                             for t, x in zip(cfg.traces, fields)}
        return out


def lif_proof_config(n_neurons: int = 8, **kwargs) -> LifConfig:
    """A LIF configuration for the proof: external tick, ``n_neurons`` (default 8, the fewest the
    LIF configuration accepts), ``kwargs`` passed on."""
    return LifConfig(n_neurons=n_neurons, clock_hz=n_neurons * 16e3, update_hz=16e3,
                     tick_source="external", **kwargs)


#: memories of the core that start with any contents
MEMORIES = ("state_mem", "cur_mem", "sel_mem", "weight_mem", "trace_mem")


def lif_harness(cfg: LifConfig, mutant: str | None = None,
                core: type | None = None) -> tuple[str, int]:
    """RTLIL of the harness (top ``lif_eq``), the memories' initial contents removed, and the
    core's latency; ``core``: a subclass of :class:`LifCore` to prove instead."""
    top = LifCoreProof(cfg, mutant, core)
    return harness_rtlil(top, "lif_eq", MEMORIES), top.latency


def prove_lif(cfg: LifConfig, workdir: Path, mode: str = "prove", depth: int | None = None,
              mutant: str | None = None, timeout_s: float = 3600, engine: str = "smtbmc",
              solver: str = SOLVER, core: type | None = None) -> ProofResult:
    """Prove (``mode="prove"``: k-induction of ``depth`` steps, default the core's latency + 2)
    or check to a bound (``mode="bmc"``) that the LIF core equals its one-step reference;
    ``core``: a subclass of :class:`LifCore` to prove instead (a fault of its own)."""
    return prove_harness("LIF core equals one-step datapath", LifCoreProof(cfg, mutant, core),
                         "lif_eq", MEMORIES, workdir, mode, depth, timeout_s, engine,
                         ABSTRACTIONS, solver)
