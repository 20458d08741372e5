"""Error detection of the link's frame format on the host codec: every corruption of a frame on
the wire is counted, none is accepted.

Every single-bit flip of every frame of :func:`edge_messages` (all four message types, payload
sizes from 0 to the largest, random, all-zero and zero-free payloads, frames with a 0x00 in
each CRC byte, the one-block 253- and 254-byte frames) is tried exhaustively, and so is every
single-byte drop; 2- and 3-bit errors, 2-bit errors in the COBS structure, byte
substitutions and multiple drops and insertions are sampled. Each damaged frame is followed by
an intact one (so that a damaged delimiter, which merges two frames, is tried too).

The verdict does not use the codec: the stream is split at its 0x00 bytes; a run equal to an
intact frame's encoding must come out as that frame, and every other run must be refused and
counted exactly once. A flip of the final COBS code byte 0x01 of a frame ending in 0x00 (the
truncation that a CRC with a zero residue and no length field let through) is among the
single-bit flips.
"""

import random
from collections import Counter

import pytest

from cuneate.sim.link.faults import (KINDS, chunks, corrupt, edge_messages, single_bit_flips,
                                        single_byte_drops, wire_of)
from cuneate.hdl.link.codec import (CRC_BYTES, MAX_FRAME, MIN_FRAME, MSG_CONTROL,
                                    MSG_COUNTERS, MSG_SPIKES, MSG_WRITE, CobsError,
                                    FrameDecoder, Message, cobs_decode)

EDGE = edge_messages()
TYPES = {"write": MSG_WRITE, "control": MSG_CONTROL, "spikes": MSG_SPIKES,
         "counters": MSG_COUNTERS}
#: samples per class and message type in the default lane (the release lane takes 20 times more)
SAMPLES = {"bits2": 5000, "bits3": 5000, "code_bits2": 2500, "byte": 2500, "drops": 1500,
           "insert": 2500, "inserts": 1500}


def judge(damaged: bytes, msg: Message, nxt: Message, tally: Counter):
    """Feed a damaged wire of ``msg`` and the intact wire of ``nxt``; check against the byte
    comparison and tally what caught the damage."""
    w_msg, w_nxt = WIRES[msg], WIRES[nxt]
    intact = {w_msg[:-1]: msg, w_nxt[:-1]: nxt}
    stream = damaged + w_nxt
    runs = chunks(stream)
    expect = [intact[r] for r in runs if r in intact]
    # a run longer than the receiver's buffer is dropped (and counted) per 2 * MAX_FRAME + 1
    # bytes, then its rest is refused: ceil(len / (2 * MAX_FRAME + 1)) errors per damaged run
    count = sum(-(-len(r) // (2 * MAX_FRAME + 1)) for r in runs if r not in intact)
    dec = FrameDecoder()
    got = dec.feed(stream)
    assert count >= 1, f"not a corruption: {damaged.hex()}"
    assert got == expect, f"accepted {got} from {damaged.hex()}"
    assert sum(dec.errors.values()) == count, \
        f"{damaged.hex()}: {count} damaged runs, counted {dec.errors}"
    for k, v in dec.errors.items():
        tally[k] += v
    tally["tried"] += 1
    # what stood between each damaged run of a plausible size and acceptance: the CRC and the
    # len field (it disagrees with the size), or the CRC alone, either certainly (at most four
    # bits differ from the intact frame: Hamming distance 5; or all differences lie within
    # four consecutive bytes: a burst of at most 32 bits) or with probability 1 - 2**-32
    orig = msg.raw()
    for r in runs:
        if r in intact:
            continue
        try:
            raw = cobs_decode(r)
        except CobsError:
            continue
        if not MIN_FRAME <= len(raw) <= MAX_FRAME:
            continue
        if raw[3] != len(raw) - MIN_FRAME:
            tally["crc_and_len"] += 1
        elif len(raw) == len(orig) and _certain(raw, orig):
            tally["crc_certain"] += 1
        else:
            tally["crc_only"] += 1


def _certain(raw: bytes, orig: bytes) -> bool:
    """True when CRC-32 detects the change from ``orig`` to ``raw`` (same length) with
    certainty: at most four bits differ, or the differing bytes span at most four."""
    diff = [i for i, (a, b) in enumerate(zip(raw, orig)) if a != b]
    weight = (int.from_bytes(raw, "little") ^ int.from_bytes(orig, "little")).bit_count()
    return weight <= 4 or diff[-1] - diff[0] < 4


class _Wires(dict):
    """Intact wires, encoded once."""

    def __missing__(self, msg):
        self[msg] = w = wire_of(msg)
        return w


WIRES = _Wires()


def by_type(name):
    return [(label, m) for label, m in EDGE if m.type == TYPES[name]]


#: the intact frame after each damaged one in the exhaustive sweeps (short: a damaged
#: delimiter merges the two)
NEXT = Message(MSG_CONTROL, 0x5A, 0x01020304, b"\x03\x10\x00\x00\x00")


def _sweep(name, corruptions):
    msgs = by_type(name)
    assert msgs
    tally = Counter()
    for _, msg in msgs:
        for damaged in corruptions(WIRES[msg]):
            judge(damaged, msg, NEXT, tally)
    return tally


def _report(what, name, tally):
    caught = ", ".join(f"{k} {tally[k]}" for k in ("framing", "length", "crc", "version"))
    print(f"\n{what} {name}: {tally['tried']} tried, 0 accepted; runs refused by {caught}; "
          f"runs of a plausible size held by the CRC and the len field "
          f"{tally['crc_and_len']}, by the CRC alone: certainly {tally['crc_certain']}, "
          f"with probability 1 - 2**-32 {tally['crc_only']}")


@pytest.mark.parametrize("name", list(TYPES))
def test_every_single_bit_flip_is_counted_and_never_accepted(name):
    tally = _sweep(name, single_bit_flips)
    _report("single-bit flips", name, tally)
    assert tally["tried"] == sum(8 * len(wire_of(m)) for _, m in by_type(name))


@pytest.mark.parametrize("name", list(TYPES))
def test_every_single_byte_drop_is_counted_and_never_accepted(name):
    tally = _sweep(name, single_byte_drops)
    _report("single-byte drops", name, tally)
    assert tally["tried"] == sum(len(wire_of(m)) for _, m in by_type(name))


def _sample(name, kind, n, seed):
    msgs = by_type(name)
    rng = random.Random(f"{seed}/{name}/{kind}")
    tally = Counter()
    for _ in range(n):
        i = rng.randrange(len(msgs))
        msg, nxt = msgs[i][1], msgs[(i + 1) % len(msgs)][1]
        judge(corrupt(WIRES[msg], kind, rng), msg, nxt, tally)
    return tally


@pytest.mark.parametrize("name", list(TYPES))
def test_sampled_multi_bit_errors_drops_and_insertions_are_counted(name):
    for kind, n in SAMPLES.items():
        tally = _sample(name, kind, n, 1)
        _report(f"{kind} (sampled)", name, tally)
        assert tally["tried"] == n


@pytest.mark.release
@pytest.mark.parametrize("name", list(TYPES))
def test_long_sampled_multi_bit_errors_drops_and_insertions(name):
    for kind, n in SAMPLES.items():
        tally = _sample(name, kind, 20 * n, 2)
        _report(f"{kind} (long sample)", name, tally)


@pytest.mark.long
# the spike frames in CI (every size the device sends), the host's types in the release lane
@pytest.mark.parametrize("name", ["spikes", *[pytest.param(n, marks=pytest.mark.release)
                                              for n in TYPES if n != "spikes"]])
def test_long_every_single_bit_flip_at_every_payload_size(name):
    """Every payload size from 0 to the largest, every single-bit flip."""
    from cuneate.hdl.link.codec import MAX_PAYLOAD
    msgs = [(label, m) for label, m in edge_messages(range(MAX_PAYLOAD + 1), seed=3)
            if m.type == TYPES[name]]
    tally = Counter()
    for _, msg in msgs:
        for damaged in single_bit_flips(WIRES[msg]):
            judge(damaged, msg, NEXT, tally)
    _report("single-bit flips (every size)", name, tally)


def test_crc32_detects_every_error_of_up_to_four_bits_in_the_longest_frame():
    """Hamming distance 5 of CRC-32 over a 254-byte frame, verified, not assumed: the change of
    the CRC check (zlib's CRC, linear for frames of one length) by each single-bit error, its
    syndrome, is non-zero (1 bit), all syndromes differ (2 bits), no pair's XOR is a third
    syndrome (3 bits), and all pair XORs differ (4 bits). Shorter frames use a subset of the
    positions (leading bytes do not change the CRC of zeros' differences)."""
    import zlib

    import numpy as np
    n = MAX_FRAME
    zero = zlib.crc32(bytes(n))
    syn = np.array([zlib.crc32((1 << b).to_bytes(n, "little")) ^ zero for b in range(8 * n)],
                   dtype=np.uint32)
    assert np.all(syn != 0)
    assert np.unique(syn).size == syn.size
    i, j = np.triu_indices(syn.size, 1)
    pairs = syn[i] ^ syn[j]
    assert not np.isin(pairs, syn).any()
    assert np.unique(pairs).size == pairs.size
    assert pairs.size == 2032 * 2031 // 2


def test_catalogue_has_the_edge_cases():
    """The frames the exhaustive tests run over include each case the format must survive."""
    raws = [m.raw() for _, m in EDGE]
    wires = [wire_of(m) for _, m in EDGE]
    assert {m.type for _, m in EDGE} == set(TYPES.values())
    for i in range(CRC_BYTES):
        assert sum(r[-CRC_BYTES + i] == 0 for r in raws) >= 4
    # the truncation case: the frame ends in 0x00, its encoding in the code byte 0x01
    assert sum(w[-2:] == b"\x01\x00" for w in wires) >= 4
    assert any(len(r) == 254 and 0 not in r for r in raws)       # one block, code 0xFF
    assert any(len(r) == 253 and 0 not in r for r in raws)       # one block, code 0xFE
    assert any(w[0] == 0xFF for w in wires)
    assert any(r.count(0) > len(r) // 2 for r in raws)           # mostly zeros
    sizes = {len(r) for r in raws}
    assert min(sizes) == 12 and max(sizes) == 254
    assert set(SAMPLES) | {"bit", "drop"} == set(KINDS)          # every class tried


def test_the_truncating_flip_of_the_last_code_byte_is_counted():
    """A frame ending in 0x00 is encoded ending ``... 0x01 0x00``; the flip 0x01 -> 0x00 drops
    its last byte. The shortened frame is refused (its ``len`` and its CRC residue disagree),
    counted, and the next frame still arrives."""
    for label, msg in EDGE:
        w = wire_of(msg)
        if w[-2:] != b"\x01\x00":
            continue
        nxt = Message(MSG_WRITE, 9, 9, b"\x01\x00\x05")
        dec = FrameDecoder()
        damaged = w[:-2] + b"\x00\x00"
        assert dec.feed(damaged + wire_of(nxt)) == [nxt], label
        assert sum(dec.errors.values()) == 1, label
