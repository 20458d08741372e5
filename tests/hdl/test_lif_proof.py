"""k-induction of the pipelined LIF core (no input spikes, no traces) against its one-step
datapath (hdl/lif/formal_core.py), and the faults it must catch."""

import pytest
from amaranth.hdl import Fragment
from proof_cases import assert_fails_first_at, v_one_high

from cuneate.hdl.lif import LifCore
from cuneate.hdl.lif.formal_core import MUTANTS, LifCoreProof, lif_proof_config, prove_lif

EXPECTED = {
    "skipped_write": ("memory_state_mem_tracked_word", 6),
    # stage 4's v is the previous neuron's: the update written back is wrong
    "stage_off_by_one": ("memory_state_mem_tracked_word", 7),
    "late_host_write": ("memory_cur_mem_tracked_word", 1),
    "tag_off_by_one": ("stage_5_neuron", 5),
}

REFRACTORY_MIX = {"param_sets": [{"tau_m_ms": 20.0, "t_ref_ms": 2.0}, {"tau_m_ms": 10.0}]}
DISCRETE_SHIFT = {"decay": "shift", "form": "discrete",
                  "param_sets": [{"alpha": 0.875, "refractory_steps": 3}]}


def test_every_mutant_has_an_expectation():
    assert set(EXPECTED) == set(MUTANTS)


@pytest.mark.parametrize("kwargs", [{}, REFRACTORY_MIX,
                                    pytest.param(DISCRETE_SHIFT, marks=pytest.mark.long)],
                         ids=["default", "refractory-mix", "discrete-shift"])
def test_the_lif_core_equals_the_one_step_datapath_for_every_input_sequence(kwargs, tmp_path):
    """k-induction at the latency + 2 with yices (seconds; the discrete form with a shift
    decay, about 30 s, in the long lane): base case and step both pass."""
    r = prove_lif(lif_proof_config(**kwargs), tmp_path, mode="prove", timeout_s=900)
    assert r.passed and r.mode == "prove" and r.depth == 7, r


@pytest.mark.parametrize("mutant", sorted(EXPECTED))
def test_the_lif_proof_catches_the_fault(mutant, tmp_path):
    check, step = EXPECTED[mutant]
    r = prove_lif(lif_proof_config(), tmp_path, mode="bmc", depth=step + 1, mutant=mutant,
                  timeout_s=600)
    assert_fails_first_at(r, check, step)


def test_a_datapath_fault_in_the_lif_core_is_caught(tmp_path):
    """The core's last stage gives v + 1 (the reference keeps the true stage function)."""
    r = prove_lif(lif_proof_config(), tmp_path, mode="bmc", depth=7, timeout_s=600,
                  core=v_one_high(LifCore))
    assert r.status == "fail" and "tracked_update_upd_v" in r.failed, r


INPUTS = {"form": "discrete", "weights": [[0.5, -0.25, 0.125]] * 8, "current_format": (4, 12)}


SYNAPSES = {"weights": [[0.5, 0.25]] * 8, "synapses": True}        # AMPA and GABA: 4 traces
CURRENT_SYNAPSE = {"weights": [[0.5, 0.25]] * 8, "syn_alpha": 0.875}  # one current trace


@pytest.mark.parametrize("kwargs", [SYNAPSES, CURRENT_SYNAPSE],
                         ids=["four-traces", "current-synapse"])
def test_the_lif_core_with_synaptic_traces_equals_the_one_step_datapath(kwargs, tmp_path):
    """The trace memory as a second state memory, each trace's product uninterpreted
    (seconds)."""
    cfg = lif_proof_config(**kwargs)
    harness = LifCoreProof(cfg)
    assert cfg.traces and harness.state_memories == ("state_mem", "trace_mem")
    Fragment.get(harness, None)                     # elaborates with the trace memory
    r = prove_lif(cfg, tmp_path, mode="prove", timeout_s=900)
    assert r.passed and r.mode == "prove" and r.depth == 7, r


class _TraceOneHigh(LifCore):
    @staticmethod
    def trace_update(cfg, ys, ps):
        out = list(LifCore.trace_update(cfg, ys, ps))
        return [out[0] + 1] + out[1:]


def test_a_trace_fault_is_caught(tmp_path):
    """The core's trace update gives the first trace one LSB high (the reference keeps the
    true ``trace_update``)."""
    r = prove_lif(lif_proof_config(**SYNAPSES), tmp_path, mode="bmc", depth=7, timeout_s=600,
                  core=_TraceOneHigh)
    assert r.status == "fail" and "tracked_update_upd_xd_ampa" in r.failed, r


@pytest.mark.long
@pytest.mark.parametrize("writable", [False, True], ids=["fixed-weights", "host-weights"])
def test_the_lif_core_with_input_spikes_equals_the_one_step_datapath(writable, tmp_path):
    """Three input sources, weights any contents of the weight memory (fixed) or written by
    the host: k-induction with the contract's pending/active spike vectors (30-45 s)."""
    r = prove_lif(lif_proof_config(**INPUTS, weights_writable=writable), tmp_path,
                  mode="prove", timeout_s=1800)
    assert r.passed and r.mode == "prove", r


class _IgnoresSource0(LifCore):
    @staticmethod
    def gather_input(cfg, I, x, w, traces=None):
        return LifCore.gather_input(cfg, I, [x[0] & 0] + list(x[1:]), w, traces)


def test_an_input_spike_fault_is_caught(tmp_path):
    """The core ignores source 0's spikes (the reference keeps the true ``gather_input``):
    the first update of a sweep with that spike active breaks the tracked update."""
    r = prove_lif(lif_proof_config(**INPUTS), tmp_path, mode="bmc", depth=8, timeout_s=600,
                  core=_IgnoresSource0)
    assert r.status == "fail" and r.step == 7, r
    assert "tracked_update_upd_acc" in r.failed, r
