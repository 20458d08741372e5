"""The channel fan-out's one-entry datapath against its specification (SymbiYosys, yices): every
gain of a table's shared exponent and every sample, at the gains the twin once wrapped (1e18:
more bits added than the current has); the mutants each fail it."""

import json

import pytest

from cuneate.hdl.fanout.formal import MUTANTS, PROOF_TABLES, prove_entry, proof_tables


def test_the_datapath_meets_its_spec_at_a_gain_of_1e18_and_the_int64_wrap_fails_it(tmp_path):
    cfg = proof_tables()["gain_1e18"]
    assert cfg.shift < -cfg.I.width          # more bits added than the current holds
    r = prove_entry(cfg, tmp_path, "gain_1e18")
    assert r.status == "pass", r
    bad = prove_entry(cfg, tmp_path, "gain_1e18_wrap", mutant="fanout_wrap_int64")
    assert bad.status == "fail" and "current" in bad.failed, bad


@pytest.mark.long
def test_cli_proves_every_table_and_each_mutant_fails_one(capsys):
    from cuneate.sim.cli import main
    assert main(["prove", "fanout", "--json"]) == 0
    recs = json.loads(capsys.readouterr().out)
    assert [r["table"] for r in recs] == list(PROOF_TABLES)
    assert all(r["status"] == "pass" for r in recs)
    shifts = [r["shift"] for r in recs]
    assert min(shifts) < -16 and 0 in shifts and max(shifts) > 0
    assert {r["rounding"] for r in recs} == {"nearest", "truncate"}
    assert {r["clamp_built"] for r in recs} == {True, False}
    for mutant in MUTANTS:
        assert main(["prove", "fanout", "--json", "--mutant", mutant]) == 1
        recs = json.loads(capsys.readouterr().out)
        assert any(r["status"] == "fail" for r in recs), mutant
