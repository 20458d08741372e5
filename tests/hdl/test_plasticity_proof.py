"""k-induction of the learning stage against its one-operation specification
(hdl/plasticity/formal_core.py): the unbounded proof, and the faults it must catch, each found
by a shallow bounded run from the initial state (the long lane: about 45 s of yices)."""

import json

import pytest

from cuneate.hdl.plasticity.formal_core import (MUTANTS, induction_depth, prove_stage,
                                                stage_proof_config)

#: the assertion each fault breaks first, at step 4 (an operation issued at step 0 writes back
#: in step 3 and leaves on upd_* in step 4)
#: the properties each fault breaks (the solver names one or more of them)
EXPECTED = {
    "skipped_write": ("tracked_word",),                # the memory kept the old word
    "stale_drive": ("tracked_update_l",),              # a learn left the drive
    "unflagged_weight_clamp": ("tracked_update_clamps",),
    # a potentiation read the other table: another step, so another weight or clamp
    "wrong_sign_table": ("tracked_update_clamps", "tracked_update_w", "tracked_word"),
}


def test_every_mutant_has_an_expectation():
    assert set(EXPECTED) == set(MUTANTS)


@pytest.mark.long
def test_the_learning_stage_equals_its_specification_for_every_operation_sequence(capsys):
    """``cuneate prove plasticity --unbounded``: k-induction at the stage's latency + 2 (k = 6;
    10-17 s with yices): base case and step both pass, for every sequence of operations,
    operands and host writes."""
    from cuneate.sim.cli import main
    assert main(["-q", "prove", "plasticity", "--unbounded", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["status"] == "pass" and r["mode"] == "prove", r
    assert r["depth"] == induction_depth(stage_proof_config()) == 6 and r["mutant"] is None


@pytest.mark.parametrize("argv,message", [
    (["prove", "plasticity", "--mutant", "wrong_slot"],
     "cuneate prove plasticity: mutant wrong_slot is not the learning stage's"),
    (["prove", "core", "--mutant", "stale_drive"],
     "cuneate prove core: mutant stale_drive is the learning stage's (cuneate prove "
     "plasticity)"),
])
def test_a_mutant_of_another_block_is_refused_in_one_line(argv, message, capsys):
    from cuneate.sim.cli import main
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err


@pytest.mark.long
@pytest.mark.parametrize("mutant", sorted(EXPECTED))
def test_the_stage_proof_catches_the_fault(mutant, tmp_path):
    r = prove_stage(stage_proof_config(), tmp_path, mode="bmc", depth=5, mutant=mutant,
                    timeout_s=600)
    assert r.status == "fail" and r.phase == "basecase" and r.step == 4, r
    assert set(EXPECTED[mutant]) & set(r.failed), r
