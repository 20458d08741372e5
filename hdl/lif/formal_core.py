"""The pipelined LIF core against its one-step datapath, for every input sequence of every
length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The harness is :class:`cuneate.hdl.lib.core_proof.SweepCoreProof` (the contract, the pipeline
invariants, the tracked neuron, the uninterpreted products: see there and docs/formal.md); this
module gives it the LIF core and the reference: one combinational step of the stage functions
(``gather_input``, ``leak_operand``, ``leak_product``, ``update_state``, bound at import) from
the tracked neuron's state word (``v`` and the refractory counter), current and set.

Covered: cores without input spikes and without synaptic traces (``n_inputs == 0``,
``synapses=False``), any form, decay, refractory period and parameter sets. Cores with input
spikes need the contract's pending/active spike vectors as a fetched input of the update
(:meth:`SweepCoreProof.fetched_inputs`) and the weight memory as a tracked memory; that is not
done yet.
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Cat, Const

from ..flow.sby import SOLVER
from ..lib.config import ConfigError
from ..lib.core_proof import MUTANTS, SweepCoreProof
from ..lib.formal import ProofResult, free_memories, run_proof
from . import core as core_module
from . import datapath
from .config import CLAMP_KINDS, LifConfig
from .core import LifCore
from .datapath import gather_input, leak_operand, leak_product, update_state

__all__ = ["LifCoreProof", "lif_harness", "prove_lif", "lif_proof_config", "MUTANTS",
           "ABSTRACTIONS"]

#: what the proof abstracts, for reports
ABSTRACTIONS = ["products of the datapath uninterpreted (same function per multiplier in core "
                "and reference)", "tick free (covers the internal divider)",
                "memories with free initial contents"]


class LifCoreProof(SweepCoreProof):
    """The LIF core without input spikes or traces (see
    :class:`~cuneate.hdl.lib.core_proof.SweepCoreProof`)."""

    core_module = core_module
    datapath_files = (datapath.__file__,)
    clamp_kinds = CLAMP_KINDS
    off_by_one_register = ("v", 4)          # stage 4's v: the previous neuron's

    def __init__(self, cfg: LifConfig, mutant: str | None = None):
        if cfg.n_inputs or cfg.traces:
            raise ConfigError("the LIF core proof covers cores without input spikes and "
                              f"synaptic traces; got {cfg.n_inputs} inputs, "
                              f"{len(cfg.traces)} traces")
        super().__init__(cfg, mutant)

    def make_core(self):
        return LifCore(self.cfg)

    def reference(self, words, inputs):
        cfg = self.cfg
        V, R = cfg.V, cfg.ref_bits
        st = words["state_mem"]
        v = st[:V.width].as_signed()
        ref = st[V.width:] if R else Const(0, 1)
        i, sel = words["cur_mem"], words["sel_mem"]
        g = gather_input(cfg, i, [], [], None)
        p = leak_product(cfg, leak_operand(cfg, v, g["d"], sel), sel)
        o = update_state(cfg, v, p, g["d"], ref, sel)
        flags = {"current": g["current"], "input": g["input"], "v_low": o["v_low"]}
        v_new, ref_new = o["v"], o["ref"]
        word = Cat(v_new[:V.width], ref_new[:R]) if R else v_new[:V.width]
        return {"words": {"state_mem": word},
                "ports": {"upd_v": v_new, "upd_ref": ref_new[:max(1, R)],
                          "upd_spike": o["spike"],
                          "upd_clamp": Cat(*(flags[k] for k in CLAMP_KINDS)),
                          "upd_current": i, "upd_acc": g["acc"]}}


def lif_proof_config(n_neurons: int = 8, **kwargs) -> LifConfig:
    """A LIF configuration for the proof: external tick, ``n_neurons`` (default 8, the fewest the
    LIF configuration accepts), ``kwargs`` passed on."""
    return LifConfig(n_neurons=n_neurons, clock_hz=n_neurons * 16e3, update_hz=16e3,
                     tick_source="external", **kwargs)


def lif_harness(cfg: LifConfig, mutant: str | None = None) -> tuple[str, int]:
    """RTLIL of the harness (top ``lif_eq``), the memories' initial contents removed, and the
    core's latency."""
    from amaranth.back import rtlil
    top = LifCoreProof(cfg, mutant)
    il = rtlil.convert(top, name="lif_eq", ports=top.ports)
    return free_memories(il, ("state_mem", "cur_mem", "sel_mem")), top.latency


def prove_lif(cfg: LifConfig, workdir: Path, mode: str = "prove", depth: int | None = None,
              mutant: str | None = None, timeout_s: float = 3600, engine: str = "smtbmc",
              solver: str = SOLVER) -> ProofResult:
    """Prove (``mode="prove"``: k-induction of ``depth`` steps, default the core's latency + 2)
    or check to a bound (``mode="bmc"``) that the LIF core equals its one-step reference."""
    il, latency = lif_harness(cfg, mutant)
    return run_proof("LIF core equals one-step datapath", il, workdir, "lif_eq", mode,
                     depth or latency + 2, timeout_s, engine, ABSTRACTIONS, solver)
