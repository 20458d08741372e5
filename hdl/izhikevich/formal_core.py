"""The pipelined Izhikevich core against its one-step datapath, for every input sequence of
every length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The harness is :class:`cuneate.hdl.lib.core_proof.SweepCoreProof` (the contract, the pipeline
invariants, the tracked neuron, the uninterpreted products: see there and docs/formal.md); this
module gives it the core and the reference: one combinational composition of the pipelined steps
(:data:`~cuneate.hdl.izhikevich.datapath.STEPS`, their functions bound at import; a core proven
with a fault of its own replaces one in its ``STEPS``) from the tracked neuron's state word,
current and set. The steps' products are the ones the core forms (same sites), so each is one
uninterpreted function on both sides; that the steps compute the four-stage update's integers is
proven per configuration by the ``steps`` property of :mod:`cuneate.hdl.izhikevich.formal`.

The pipeline's depth is read from the core, not assumed: the latency ``L`` is the last stage of
its ``tags``, and every stage's tag is checked against the fetch of ``k - 1`` cycles
before. The induction needs ``L + 1`` steps (the data registers between the stages are a
function of the last ``L`` cycles); :func:`prove_core` uses ``L + 2``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from amaranth import Cat

from ..lib.core_proof import MUTANTS, SweepCoreProof
from ..flow.sby import SOLVER
from ..lib.formal import ProofResult, harness_depth, harness_rtlil, prove_harness
from . import datapath
from .config import CLAMP_KINDS, ConfigError, IzhikevichConfig
from .core import IzhikevichCore

#: the reference keeps the true step functions, bound at import (a core proven with a fault of
#: its own replaces one in its ``STEPS``)
_TRUE_STEPS = tuple((s.fn, s.reads) for s in datapath.STEPS)


def reference_update(cfg: IzhikevichConfig, v, u, i, sel) -> dict:
    """One update by the pipelined steps as bound at import (see
    :func:`~cuneate.hdl.izhikevich.datapath.one_update`)."""
    return datapath.one_update(cfg, v, u, i, sel, _TRUE_STEPS)

__all__ = ["IzhikevichCoreProof", "reference_update", "core_harness", "prove_core", "proof_config",
           "induction_depth", "one_bank", "MUTANTS", "ABSTRACTIONS"]

#: what the proof abstracts, for reports
ABSTRACTIONS = ["products of the datapath uninterpreted (same function per multiplier in core "
                "and reference)", "tick free (covers the internal divider)",
                "memories with free initial contents",
                "each memory in one bank (a memory in several banks meets the same per-cycle "
                "contract: cuneate prove banked)"]


def one_bank(cfg: IzhikevichConfig) -> IzhikevichConfig:
    """``cfg`` with each memory in one bank (a block shape as deep as the core): the core the
    proof elaborates. A memory in several banks meets the same per-cycle contract as one
    bank (:mod:`cuneate.hdl.lib.banked_proof`, whose k-induction closes in seconds where a
    core's with banked memories does not), so the two proofs together cover the banked
    core."""
    deep = 1 << max(0, (cfg.n_neurons - 1).bit_length())
    return dataclasses.replace(cfg, bram_shapes=((deep, 1),))


class IzhikevichCoreProof(SweepCoreProof):
    """The Izhikevich core (see :class:`~cuneate.hdl.lib.core_proof.SweepCoreProof`)."""

    core_class = IzhikevichCore
    clamp_kinds = CLAMP_KINDS
    off_by_one_register = ("u", 4)          # stage 4's u: the previous neuron's

    def core_config(self):
        return one_bank(super().core_config())

    def reference(self, words, inputs):
        cfg = self.cfg
        st = words["state_mem"]
        v, u = st[:cfg.V.width].as_signed(), st[cfg.V.width:].as_signed()
        i, sel = words["cur_mem"], words["sel_mem"]
        o = reference_update(cfg, v, u, i, sel)
        flags = datapath.step_flags(o)
        v_new, u_new = o["v"], o["u"]
        return {"words": {"state_mem": Cat(v_new[:cfg.V.width], u_new[:cfg.U.width])},
                "ports": {"upd_v": v_new, "upd_u": u_new, "upd_spike": o["spike"],
                          "upd_clamp": Cat(*(flags[k] for k in CLAMP_KINDS)),
                          "upd_current": i}}


def proof_config(n_neurons: int | None = None, **kwargs) -> IzhikevichConfig:
    """The configuration a core proof runs on: external tick (the harness drives it freely,
    which covers the internal divider), ``n_neurons`` neurons or, by default, the fewest the
    configuration accepts (the pipeline depth + 1: the smallest core is the hardest, a
    neuron's memories are read again as its registered write-back lands),
    ``kwargs`` passed on (``pipeline_stages``,
    formats ...)."""
    if n_neurons is not None:
        return IzhikevichConfig(n_neurons=n_neurons, clock_hz=n_neurons * 16e3,
                                update_hz=16e3, tick_source="external", **kwargs)
    last = None
    for n in range(1, 65):
        try:
            return proof_config(n, **kwargs)
        except ConfigError as exc:
            last = exc
    raise last


#: memories of the core that start with any contents
MEMORIES = ("state_mem", "cur_mem", "sel_mem")


def core_harness(cfg: IzhikevichConfig, mutant: str | None = None) -> str:
    """RTLIL of the harness (top ``core_eq``), the memories' initial contents removed."""
    return harness_rtlil(IzhikevichCoreProof(cfg, mutant), "core_eq", MEMORIES)


def induction_depth(cfg: IzhikevichConfig) -> int:
    """The k of the k-induction: the core's latency (read from its tags) + 2."""
    return harness_depth(IzhikevichCoreProof(cfg), "core_eq", MEMORIES)


def prove_core(cfg: IzhikevichConfig, workdir: Path, mode: str = "prove",
               depth: int | None = None, mutant: str | None = None,
               timeout_s: float = 3600, engine: str = "smtbmc",
               solver: str = SOLVER, core: type | None = None) -> ProofResult:
    """Prove (``mode="prove"``: k-induction of ``depth`` steps, default the core's latency + 2)
    or check to a bound (``mode="bmc"``) that the core equals its one-step reference;
    ``core``: a subclass of :class:`IzhikevichCore` to prove instead (a fault of its own)."""
    return prove_harness("core equals one-step datapath", IzhikevichCoreProof(cfg, mutant, core),
                         "core_eq", MEMORIES, workdir, mode, depth, timeout_s, engine,
                         ABSTRACTIONS, solver)
