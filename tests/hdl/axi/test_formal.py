"""The bus faces' protocol proofs (hdl/axi/formal.py, hdl/wishbone/formal.py) by k-induction:
AXI4-Stream out (a beat held unchanged while stalled, none dropped) and in (a write taken once,
unchanged until taken), AXI4-Lite's handshakes, Wishbone B4 pipelined's one answer a request;
and each proof fails on its mutant at the property the fault breaks."""

import pytest

from cuneate.hdl.axi.formal import prove_face

#: target -> (its mutant, a property the mutant breaks)
EXPECTED = {
    "axi-stream-out": ("beat_loaded_while_stalled", "stream_the_beat_unchanged_while_stalled"),
    "axi-stream-in": ("write_overwritten", "write_unchanged_until_taken"),
    "axi-lite": ("bvalid_withdrawn", "B_held_until_BREADY"),
    "wishbone": ("write_unanswered", "answer_every_request_in_the_next_cycle"),
}


@pytest.mark.parametrize("target", sorted(EXPECTED))
def test_the_face_meets_its_protocol(target, tmp_path):
    r = prove_face(target, tmp_path, mode="prove")
    assert r.passed and r.mode == "prove" and not r.failed, r


#: the default lane's mutant; the others run in the long lane
DEFAULT_MUTANT = "axi-stream-in"


@pytest.mark.parametrize("target", [t if t == DEFAULT_MUTANT else
                                    pytest.param(t, marks=pytest.mark.long)
                                    for t in sorted(EXPECTED)])
def test_the_proof_fails_on_the_fault(target, tmp_path):
    mutant, broken = EXPECTED[target]
    r = prove_face(target, tmp_path, mode="prove", mutant=mutant)
    assert not r.passed and broken in r.failed, r
