"""k-induction of the coincidence detector against its one-tick reference
(hdl/coincidence/formal_core.py): the unbounded proof, and the faults it must catch, each found
by a shallow bounded run from the initial state."""

import numpy as np
import pytest
from proof_cases import assert_fails_first_at, v_one_high

from cuneate.hdl.coincidence import CoincidenceDetector
from cuneate.hdl.coincidence.datapath import history_slot
from cuneate.hdl.coincidence.formal_core import (MUTANTS, coincidence_proof_config,
                                                 induction_depth, prove_coincidence,
                                                 prove_history_slot)

#: the assertion each fault breaks first, and the step (a tick at step 0 is taken; target 0's
#: update leaves at step 9 = 1 + S + 6 with S = 2 sources)
EXPECTED = {
    "skipped_write": ("memory_state_mem_tracked_word", 9),   # the tracked word went stale
    "wrong_slot": ("tracked_update_upd_a", 9),               # the input of tick T - d + 1
    "stamp_wrong_slot": ("history_age_2", 1),                # stamped into the next tick's slot
}


def test_every_mutant_has_an_expectation():
    assert set(EXPECTED) == set(MUTANTS)


def test_the_history_slot_is_the_ring_index_of_the_delayed_tick():
    """The one slot formula the RTL and the twin share, against the ring's definition."""
    D = 5
    slot, delay = np.meshgrid(np.arange(D), np.arange(D))
    assert np.array_equal(history_slot(slot, delay, D), (slot - delay) % D)


# the long lane (CI); the wider detector in the release lane
@pytest.mark.long
def test_the_detector_equals_its_one_tick_reference_for_every_input_sequence(tmp_path):
    """k-induction at a target's period + 2 (k = 10 for 2 sources; about 20 s with yices):
    base case and step both pass, for every tick, input spike and clamp-clear sequence."""
    cfg = coincidence_proof_config()
    r = prove_coincidence(cfg, tmp_path, mode="prove", timeout_s=900)
    assert r.passed and r.mode == "prove" and r.depth == induction_depth(cfg) == 10, r


@pytest.mark.release
def test_a_wider_detector_equals_its_one_tick_reference(tmp_path):
    """Three sources, three targets on two parameter sets, a five-tick history, every delay
    from 0 to 4 (k = 11)."""
    cfg = coincidence_proof_config(
        n_sources=3, n_targets=3, max_delay_ticks=5,
        delays_ticks=[[0, 4, 2], [1, 3, 0], [4, 0, 1]],
        weights=[[8.0, 4.0, 2.0], [1.0, 8.0, 6.0], [3.0, 5.0, 8.0]],
        param_sets=("RS", "FS"), target_sets=[0, 1, 0])
    r = prove_coincidence(cfg, tmp_path, mode="prove", timeout_s=2400)
    assert r.passed and r.depth == 11, r


@pytest.mark.parametrize("mutant", sorted(EXPECTED))
def test_the_detector_proof_catches_the_fault(mutant, tmp_path):
    check, step = EXPECTED[mutant]
    r = prove_coincidence(coincidence_proof_config(), tmp_path, mode="bmc", depth=step + 1,
                          mutant=mutant, timeout_s=600)
    assert_fails_first_at(r, check, step)


def test_a_datapath_fault_in_the_detector_is_caught(tmp_path):
    """The detector's update stage gives v + 1 (the reference keeps the true stage function)."""
    r = prove_coincidence(coincidence_proof_config(), tmp_path, mode="bmc", depth=10,
                          timeout_s=600, detector=v_one_high(CoincidenceDetector))
    assert r.status == "fail" and "tracked_update_upd_v" in r.failed, r


@pytest.mark.parametrize("depth", [1, 3, 512, 513])
def test_the_history_address_is_the_delayed_ticks_slot_for_every_slot_and_delay(depth,
                                                                                tmp_path):
    """The RTL's address expression at the ring depth (the default 513 included) and the
    delay field's width, proven for every slot and delay below the depth."""
    cfg = coincidence_proof_config(max_delay_ticks=depth, delays_ticks=[[0, 0], [0, 0]])
    r = prove_history_slot(cfg, tmp_path)
    assert r.passed and r.mode == "bmc", r


def test_a_ring_address_without_the_wrap_is_caught(tmp_path):
    r = prove_history_slot(coincidence_proof_config(), tmp_path,
                           slot=lambda slot, delay, depth: slot - delay)
    assert r.status == "fail" and "history_slot_in_the_ring" in r.failed, r
