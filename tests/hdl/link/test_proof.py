"""k-induction of the host link's frame decoder and executor against the wire format's
specification (hdl/link/formal_core.py): every frame gets its verdict, no accepted write is lost
or reordered; the faults the proof must catch."""

import pytest
from proof_cases import assert_fails_first_at

from cuneate.hdl.link.formal_core import (MUTANTS, decoder_proof_config, induction_depth,
                                          prove_decoder)

#: the assertion each fault breaks: in the induction step (seconds), and from reset (a real
#: counterexample: a frame must be built, CRC included, so these take minutes - long lane)
EXPECTED = {
    "wrong_residue": "verdict_crc_errors",                    # a corrupted frame accepted
    "values_swapped": "state_tracked_value_assembled",        # a value stored in the wrong word
    "value_read_ahead": "state_the_tracked_value_read",       # the next write takes the next value
}
FROM_RESET = {
    "wrong_residue": ("verdict_crc_errors", 15),
    "values_swapped": ("state_tracked_value_assembled", 14),
    "value_read_ahead": ("writes_the_tracked_value", 23),
}


def test_every_mutant_has_an_expectation():
    assert set(EXPECTED) == set(MUTANTS) == set(FROM_RESET)


@pytest.mark.long
def test_the_decoder_meets_the_wire_format_for_every_byte_stream(tmp_path):
    """k-induction (about 25 s with yices): every byte stream of every length, any receive-
    buffer timing, any payload back-pressure, any block and tick activity."""
    lcfg = decoder_proof_config()
    r = prove_decoder(lcfg, tmp_path, mode="prove", timeout_s=900)
    assert r.passed and r.mode == "prove" and r.depth == induction_depth(lcfg), r


@pytest.mark.long
@pytest.mark.parametrize("mutant", sorted(EXPECTED))
def test_the_decoder_proof_fails_on_the_fault(mutant, tmp_path):
    """The same induction with the fault built in no longer closes, at the property the fault
    breaks (the base case from reset is the long lane's, below)."""
    r = prove_decoder(decoder_proof_config(), tmp_path, mode="prove", mutant=mutant,
                      timeout_s=900)
    assert not r.passed and EXPECTED[mutant] in r.failed, r


@pytest.mark.long
@pytest.mark.parametrize("mutant", ["values_swapped"])
def test_the_fault_has_a_counterexample_from_reset(mutant, tmp_path):
    """A bounded run from reset builds the byte stream that shows the fault (90 s with yices).
    The long lane runs the cheapest; the other two need a frame with a valid or near-valid
    CRC-32 (2-10 minutes) and were measured once (docs/formal.md; steps in FROM_RESET)."""
    check, step = FROM_RESET[mutant]
    r = prove_decoder(decoder_proof_config(), tmp_path, mode="bmc", depth=step + 1,
                      mutant=mutant, timeout_s=2400)
    assert_fails_first_at(r, check, step)


@pytest.mark.long
def test_the_default_links_decoder_meets_the_wire_format(tmp_path):
    """The default link (2 500 neurons, a 512-byte receive buffer): k-induction, about 25 s."""
    from cuneate.hdl.link.config import link_config
    lcfg = link_config()
    r = prove_decoder(lcfg, tmp_path, mode="prove", timeout_s=1800)
    assert r.passed and r.depth == induction_depth(lcfg), r
