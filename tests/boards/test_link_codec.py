"""Wire format: COBS, CRC-16/CCITT and messages (properties with Hypothesis)."""

import binascii
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cuneate.hdl.link.codec import (MAX_FRAME, MSG_SPIKES, CobsError, FrameDecoder,
                                    FrameError, Message, cobs_decode, cobs_encode, crc16,
                                    decode_frame, encode_frame, parse_spikes, write_message)

frames = st.builds(Message, st.integers(0, 255), st.integers(0, 255),
                   st.integers(0, (1 << 32) - 1), st.binary(max_size=MAX_FRAME - 8))


def test_crc_catalogue_check_value_and_python_stdlib():
    # CRC-16/CCITT-FALSE check value from the CRC catalogue, and binascii's CRC-CCITT
    assert crc16(b"123456789") == 0x29B1
    assert crc16(b"\x00\xff" * 40) == binascii.crc_hqx(b"\x00\xff" * 40, 0xFFFF)


@given(st.binary(max_size=600))
def test_crc_matches_stdlib(data):
    assert crc16(data) == binascii.crc_hqx(data, 0xFFFF)


def test_cobs_published_examples():
    # examples of the COBS paper / common reference
    cases = {b"\x00": b"\x01\x01", b"\x00\x00": b"\x01\x01\x01",
             b"\x11\x22\x00\x33": b"\x03\x11\x22\x02\x33",
             b"\x11\x22\x33\x44": b"\x05\x11\x22\x33\x44",
             b"\x11\x00\x00\x00": b"\x02\x11\x01\x01\x01",
             bytes(range(1, 255)): b"\xff" + bytes(range(1, 255)),
             bytes(range(0, 255)): b"\x01\xff" + bytes(range(1, 255)),
             bytes(range(1, 256)): b"\xff" + bytes(range(1, 255)) + b"\x02\xff"}
    for raw, enc in cases.items():
        assert cobs_encode(raw) == enc
        assert cobs_decode(enc) == raw


@given(st.binary(max_size=800))
def test_cobs_round_trip_without_zeros(data):
    enc = cobs_encode(data)
    assert 0 not in enc
    assert len(enc) <= len(data) + 1 + len(data) // 254
    assert cobs_decode(enc) == data


@given(frames)
def test_frame_round_trip(msg):
    wire = encode_frame(msg)
    assert wire[-1] == 0 and 0 not in wire[:-1]
    assert FrameDecoder().feed(wire) == [msg]


@settings(max_examples=300)
@given(frames, st.data())
def test_any_bit_error_is_detected(msg, data):
    """Flip 1..3 bits of the decoded frame: CRC-16/CCITT detects every error of up to three
    bits in frames this short (Hamming distance 4 below 32751 bits)."""
    raw = bytearray(msg.raw())
    nbits = len(raw) * 8
    flips = data.draw(st.sets(st.integers(0, nbits - 1), min_size=1, max_size=3))
    for b in flips:
        raw[b // 8] ^= 1 << (b % 8)
    with pytest.raises(FrameError, match="CRC"):
        decode_frame(bytes(raw))


@given(st.lists(frames, min_size=1, max_size=6, unique=True), st.data())
def test_stream_with_damage_loses_only_damaged_frames(msgs, data):
    """Drop, corrupt or truncate one frame of a stream: the others all arrive, the damaged one
    never does, and one error is counted."""
    wires = [bytearray(encode_frame(m)) for m in msgs]
    i = data.draw(st.integers(0, len(msgs) - 1))
    kind = data.draw(st.sampled_from(["corrupt", "drop_byte", "truncate"]))
    w = wires[i]
    pos = data.draw(st.integers(0, len(w) - 2))
    if kind == "corrupt":
        w[pos] = data.draw(st.integers(1, 255).filter(lambda v: v != w[pos]))
    elif kind == "drop_byte":
        del w[pos]
    else:
        del w[pos:-1]
    dec = FrameDecoder()
    got = dec.feed(b"".join(bytes(x) for x in wires))
    others = [m for j, m in enumerate(msgs) if j != i]
    assert got == others
    if kind == "truncate" and pos == 0:
        assert sum(dec.errors.values()) == 0       # nothing left of the frame but its delimiter
    else:
        assert sum(dec.errors.values()) == 1


def test_write_message_layout_and_refusals():
    m = write_message(7, 1234, 3, [-1, 5, -131072], 18)
    assert m.payload == struct.pack("<H", 3) + b"\xff\xff\xff" + b"\x05\x00\x00" + \
        (-131072 & 0xFFFFFF).to_bytes(3, "little")
    with pytest.raises(FrameError, match="does not fit 18"):
        write_message(0, 0, 0, [1 << 17], 18)
    with pytest.raises(FrameError, match="exceeds 254"):
        write_message(0, 0, 0, [0] * 90, 18).raw()


def test_parse_spikes():
    payload = struct.pack("<HB", 2, 16) + struct.pack("<BH", 0, 7) + struct.pack("<BH", 15, 300)
    dropped, sweeps, spikes = parse_spikes(Message(MSG_SPIKES, 0, 160, payload))
    assert (dropped, sweeps, spikes) == (2, 16, [(160, 7), (175, 300)])
    with pytest.raises(FrameError):
        parse_spikes(Message(MSG_SPIKES, 0, 0, payload[:-1]))


def test_cobs_refusals():
    with pytest.raises(CobsError, match="truncated"):
        cobs_decode(b"\x05\x11\x22")
    with pytest.raises(CobsError, match="zero"):
        cobs_decode(b"\x03\x11\x00")
