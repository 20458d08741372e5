"""k-induction of the pipelined Izhikevich core against its one-step datapath
(hdl/izhikevich/formal_core.py): the unbounded proof (long lane), and the faults it must catch,
each found by a shallow bounded run from the initial state (default lane, seconds each)."""

import pytest
from proof_cases import assert_fails_first_at

from cuneate.hdl.izhikevich import IzhikevichConfig, IzhikevichCore, datapath
from cuneate.hdl.izhikevich.formal_core import (MUTANTS, induction_depth, proof_config,
                                                prove_core)
from cuneate.sim.hardcases import record

#: the assertion each fault breaks first
EXPECTED = {
    # the tracked neuron's word went stale (the registered write lands a cycle after the
    # result leaves, at step 6)
    "skipped_write": ("memory_state_mem_tracked_word", 7),
    # stage 4's u is the previous neuron's, in the first update that can leave
    "stage_off_by_one": ("tracked_update_upd_u", 6),
    "late_host_write": ("memory_cur_mem_tracked_word", 1),   # the current lands a cycle late
    "tag_off_by_one": ("stage_5_neuron", 5),                 # the write-back addressed one off
}


def test_every_mutant_has_an_expectation():
    assert set(EXPECTED) == set(MUTANTS)


@pytest.fixture(scope="module")
def cfg():
    return proof_config()


# the long lane (CI), beside the proofs the mutants break
@pytest.mark.long
@pytest.mark.parametrize("mutant", sorted(EXPECTED))
def test_the_proof_catches_the_fault(cfg, mutant, tmp_path):
    """A bounded run from the initial state, just deep enough, finds a counterexample in the
    first step where the fault can show, naming the broken invariant (so the unbounded proof
    cannot pass either)."""
    check, step = EXPECTED[mutant]
    r = prove_core(cfg, tmp_path, mode="bmc", depth=step + 1, mutant=mutant, timeout_s=600)
    assert_fails_first_at(r, check, step)


def _select_v_one_high(cfg, x):
    out = dict(datapath.select_step(cfg, x))
    out["v_next"] = out["v_next"] + 1
    return out


class _VOneHigh(IzhikevichCore):
    """The core with a faulty last step: v one LSB high."""

    STEPS = IzhikevichCore.STEPS[:-1] + (IzhikevichCore.STEPS[-1].with_fn(_select_v_one_high),)


def test_a_datapath_fault_in_the_core_is_caught(cfg, tmp_path):
    """The core built with a faulty last step (v one LSB high; the reference keeps the true
    steps) fails at the tracked neuron's first update: the uninterpreted products do not hide
    the arithmetic around them."""
    r = prove_core(cfg, tmp_path, mode="bmc", depth=induction_depth(cfg), timeout_s=600,
                   core=_VOneHigh)
    assert r.status == "fail", r
    assert "tracked_update_upd_v" in r.failed, r


@pytest.mark.long
@pytest.mark.parametrize("n_neurons", [None, 8], ids=["smallest", "N=8-counter-wraps"])
def test_the_pipelined_core_equals_the_one_step_datapath_for_every_input_sequence(n_neurons,
                                                                                   tmp_path):
    """k-induction: the base case and the induction step both pass at the core's latency + 2,
    so the core equals its one-step datapath for every input sequence of every length; on the
    smallest core and on one whose issue counter wraps to 0 (a power of two, see
    docs/formal.md)."""
    cfg = proof_config(n_neurons)
    r = prove_core(cfg, tmp_path, mode="prove", timeout_s=2400)
    record(f"formal_core_k_induction_n{cfg.n_neurons}", 1, 0, int(not r.passed),
           f"SymbiYosys prove, k={r.depth}, {r.solver}, {r.seconds:.0f} s, N={cfg.n_neurons}")
    assert r.passed and r.mode == "prove", r


def test_cuneate_prove_core_reports_a_caught_fault_as_json(capsys):
    """``cuneate prove core --json``: exit 1 on a failed proof, with the mode, depth, solver
    and the broken assertion in the record."""
    import json

    from cuneate.sim.cli import main
    rc = main(["prove", "core", "--mutant", "late_host_write", "--depth", "3", "--json"])
    out = capsys.readouterr()
    rec = json.loads(out.out)
    assert rc == 1
    # what runs is said on stderr (timestamped lines when stderr is not a terminal)
    assert "cuneate prove core ..." in out.err and "cuneate prove core: done in" in out.err
    assert (rec["status"], rec["mode"], rec["depth"]) == ("fail", "bmc", 3), rec
    assert rec["solver"] == "yices" and rec["n_neurons"] == proof_config().n_neurons, rec
    assert "memory_cur_mem_tracked_word" in rec["failed"], rec


@pytest.mark.release
def test_the_default_configuration_core_equals_the_one_step_datapath(tmp_path):
    """The default configuration itself (2500 neurons, internal tick divider - the harness
    drives the tick freely, which covers the divider): k-induction closes at the same k."""
    cfg = IzhikevichConfig()
    r = prove_core(cfg, tmp_path, mode="prove", timeout_s=2400)
    record("formal_core_k_induction_default", 1, 0, int(not r.passed),
           f"SymbiYosys prove, k={r.depth}, {r.solver}, {r.seconds:.0f} s, N={cfg.n_neurons}")
    assert cfg.n_neurons == 2500 and r.passed and r.mode == "prove", r


@pytest.mark.long
# the deepest in CI; the depths between in the release lane (make test-release)
@pytest.mark.parametrize("depth", [*[pytest.param(d, marks=pytest.mark.release) for d in (6, 7, 8)],
                                   9])
def test_every_deeper_pipeline_equals_the_one_step_datapath(depth, tmp_path):
    """k-induction of every deeper pipeline on its smallest core (N = depth + 1: a neuron is
    fetched again as its registered write-back lands - at depths 5-8 its memories are read a
    cycle ahead, as the write lands; at depth 9 at the fetch, the host's writes registered)
    at its own latency + 2."""
    from cuneate.hdl.izhikevich.config import PIPELINE_STAGES, min_neurons
    assert max(PIPELINE_STAGES) == 9
    cfg = proof_config(pipeline_stages=depth)
    r = prove_core(cfg, tmp_path, mode="prove", timeout_s=2400)
    record(f"formal_core_k_induction_depth{depth}", 1, 0, int(not r.passed),
           f"SymbiYosys prove, k={r.depth}, {r.solver}, {r.seconds:.0f} s, N={cfg.n_neurons}")
    assert r.passed and r.depth == depth + 2 and cfg.n_neurons == min_neurons(depth), r
    assert cfg.n_neurons == depth + 1


def test_cuneate_prove_core_takes_the_pipeline_depth(capsys):
    """``--pipeline-stages``: the core's depth proven (its smallest core, depth + 1 neurons),
    named in the record; refused for the targets without one."""
    import json

    from cuneate.sim.cli import main
    rc = main(["prove", "core", "--pipeline-stages", "9", "--depth", "3", "--json"])
    rec = json.loads(capsys.readouterr().out)
    assert rc == 0 and rec["status"] == "pass", rec
    assert (rec["pipeline_stages"], rec["n_neurons"]) == (9, 10), rec
    for target in ("lif", "coincidence", "link", "banked", "datapath"):
        assert main(["prove", target, "--pipeline-stages", "9"]) == 2
        assert "--pipeline-stages is the" in capsys.readouterr().err


def test_progress_reads_the_phase_and_step_of_a_symbiyosys_run():
    """The position a running proof reports, from SymbiYosys's own lines: the base case
    counting up, the induction counting down, each phase's verdict."""
    from cuneate.hdl.flow.sby import SbyProgress
    p = SbyProgress(7)
    assert p.text() == "elaborating"
    lines = ["SBY 23:12:52 [core_eq] engine_0.basecase: ##   0:00:00  Checking assertions in "
             "step 2..",
             "SBY 23:12:52 [core_eq] engine_0.induction: ##   0:00:00  Trying induction in "
             "step 7..",
             "SBY 23:12:53 [core_eq] engine_0.induction: ##   0:00:00  Trying induction in "
             "step 6..",
             "SBY 23:12:53 [core_eq] engine_0: ##   0:00:00  Checking assertions in step 3.."]
    assert [p.feed(x) for x in lines] == [True, True, True, True]
    assert p.text() == "base case step 3 of 7; induction step 6 (from 7 down to 0)"
    assert not p.feed("SBY 23:12:53 [core_eq] engine_0.basecase: ##   0:00:01  Solving ..")
    assert p.feed("SBY 23:15:09 [core_eq] engine_0.basecase: Status returned by engine for "
                  "basecase: pass")
    assert p.text() == "base case pass; induction step 6 (from 7 down to 0)"
