"""The banked, prefetched memory against its per-cycle contract (hdl/lib/banked_proof.py):
k-induction for one and several banks, direct and registered writes, the default core's state
layout (2500 words in five banks of 512), and the faults the proof must catch (seconds each)."""

import json

import pytest
from proof_cases import assert_fails_first_at

from cuneate.hdl.lib.banked_proof import MUTANTS, prove_banked
from cuneate.sim.cli import main


@pytest.mark.parametrize("registered", [False, True], ids=["direct", "registered"])
@pytest.mark.parametrize("words, bank", [(8, 8), (10, 4), (2500, 512)],
                         ids=["one-bank", "three-banks-padded", "default-state-layout"])
def test_a_banked_memory_meets_its_contract_for_every_access_sequence(words, bank, registered,
                                                                      tmp_path):
    r = prove_banked(tmp_path, words, bank, write_register=registered, mode="prove")
    assert r.passed and r.mode == "prove" and r.depth == 4, r


#: the check each fault breaks first, and the step
EXPECTED = {"wrong_bank": ("a_read_of_t_two_cycles_on", 3),
            "no_bypass": ("a_read_of_t_two_cycles_on", 3)}


def test_every_mutant_has_an_expectation():
    assert set(EXPECTED) == set(MUTANTS)


@pytest.mark.parametrize("registered", [False, True], ids=["direct", "registered"])
@pytest.mark.parametrize("mutant", sorted(EXPECTED))
def test_the_proof_catches_the_fault(mutant, registered, tmp_path):
    check, step = EXPECTED[mutant]
    r = prove_banked(tmp_path, 10, 4, write_register=registered, mode="bmc", k=step + 1,
                     mutant=mutant)
    assert_fails_first_at(r, check, step)


def test_a_write_landing_in_the_wrong_bank_is_caught(tmp_path):
    """Every bank written (the bank decode of the write enable left out): the RAM's word at
    the tracked address goes wrong at the first write to another bank."""
    from amaranth import Module

    from cuneate.hdl.lib.banked import prefetched_memory

    def every_bank(m: Module, name, shape, depth, init, read_addr, shapes, **kw):
        mem = prefetched_memory(m, name, shape, depth, init, read_addr, shapes, **kw)
        for b, bank in enumerate(mem.banks[1:], 1):
            stray = bank.write_port()
            lo = (mem.bank_depth - 1).bit_length()
            m.d.comb += [stray.addr.eq(mem.wr_addr[:lo]), stray.data.eq(mem.wr_data),
                         stray.en.eq(mem.wr_en)]
        return mem
    r = prove_banked(tmp_path, 10, 4, mode="bmc", k=3, memory=every_bank)
    assert r.status == "fail" and "the_RAM_s_word_at_t" in r.failed, r


def test_cuneate_prove_banked_reports_both_write_modes(capsys):
    rc = main(["prove", "banked", "--unbounded", "--neurons", "10", "--bank-depth", "4",
               "--json"])
    recs = json.loads(capsys.readouterr().out)
    assert rc == 0 and [r["write_register"] for r in recs] == [False, True], recs
    assert all(r["status"] == "pass" and r["banks"] == 3 for r in recs), recs


@pytest.mark.parametrize("argv, match", [
    (["--bank-depth", "6"], "power of two"),
    (["--mutant", "skipped_write"], "not the memory's"),
])
def test_cuneate_prove_banked_refuses(argv, match, capsys):
    assert main(["prove", "banked", *argv]) == 2
    assert match in capsys.readouterr().err

