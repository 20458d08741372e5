"""Wire format: COBS, CRC-32, the versioned frame layout and messages (properties with
Hypothesis). The exhaustive and sampled corruption tests are in test_link_errors.py."""

import binascii
import struct
import zlib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cuneate.hdl.link.codec import (CRC_RESIDUE, MAX_FRAME, MAX_PAYLOAD, MSG_CONTROL,
                                    MSG_SPIKES, MSG_WRITE, VERSION, CobsError, FrameDecoder,
                                    FrameError, Message, cobs_decode, cobs_encode, crc32,
                                    decode_frame, encode_frame, parse_spikes, write_message)
from cuneate.hdl.link.datapath import crc32_update

frames = st.builds(Message, st.integers(0, 255), st.integers(0, 255),
                   st.integers(0, (1 << 32) - 1), st.binary(max_size=MAX_PAYLOAD))


def test_crc_catalogue_check_value_residue_and_python_stdlib():
    # CRC-32/ISO-HDLC from the CRC catalogue: check 0xCBF43926, residue 0xDEBB20E3
    assert crc32(b"123456789") == 0xCBF43926
    reg = 0xFFFFFFFF
    for b in b"123456789" + (0xCBF43926).to_bytes(4, "little"):
        reg = crc32_update(reg, b)
    assert reg == 0xDEBB20E3 == CRC_RESIDUE
    assert crc32(b"\x00\xff" * 40) == binascii.crc32(b"\x00\xff" * 40)


@given(st.binary(max_size=600))
def test_crc_matches_stdlib(data):
    assert crc32(data) == zlib.crc32(data)


def test_crc_step_on_amaranth_values_equals_the_int_step():
    """The gateware's XOR trees (the same function on Amaranth values) give zlib's CRC."""
    from amaranth.sim import Simulator
    from amaranth.hdl import Module, Signal
    m = Module()
    crc, byte, out = Signal(32), Signal(8), Signal(32)
    m.d.comb += out.eq(crc32_update(crc, byte))
    sim = Simulator(m)
    data = b"123456789" + bytes(range(0, 256, 7))
    got = []

    async def bench(ctx):
        reg = 0xFFFFFFFF
        for b in data:
            ctx.set(crc, reg)
            ctx.set(byte, b)
            reg = ctx.get(out)
        got.append(reg ^ 0xFFFFFFFF)

    sim.add_testbench(bench)
    sim.run()
    assert got == [zlib.crc32(data)]


def test_frame_layout_by_hand():
    """version 1 | type | seq | len | tick u32 LE | payload | CRC-32 LE (zlib's CRC), then COBS:
    ten non-zero bytes (code 0x0B), two zeros (codes 0x01), the CRC (code 0x05), delimiter."""
    msg = Message(MSG_CONTROL, 0x2A, 0x01020304, b"\x03\x10\x00\x00\x00")
    body = bytes([1, 0x02, 0x2A, 5, 0x04, 0x03, 0x02, 0x01, 0x03, 0x10, 0, 0, 0])
    crc = zlib.crc32(body).to_bytes(4, "little")
    assert crc == bytes.fromhex("a3a4da24")
    assert msg.raw() == body + crc
    assert encode_frame(msg) == bytes.fromhex("0b 0102 2a05 0403 0201 0310 01 01 05 a3a4da24 00")
    assert VERSION == 1
    assert decode_frame(body + crc) == msg


def test_version_and_length_field_are_checked_after_the_crc():
    """An intact frame of another version is a version error; an intact frame whose ``len``
    disagrees with its size is a length error; the same frames damaged are CRC errors."""
    def frame(body):
        return body + zlib.crc32(body).to_bytes(4, "little")
    good = bytes([1, MSG_WRITE, 7, 3, 9, 0, 0, 0, 0, 0, 0x55])
    assert decode_frame(frame(good)) == Message(MSG_WRITE, 7, 9, b"\x00\x00\x55")
    cases = {"version": frame(bytes([2]) + good[1:]),
             "length": frame(good[:3] + bytes([2]) + good[4:]),
             "crc": frame(good)[:-1] + b"\x00"}
    for kind, raw in cases.items():
        with pytest.raises(FrameError) as exc:
            decode_frame(raw)
        assert exc.value.kind == kind
        dec = FrameDecoder()
        assert dec.feed(cobs_encode(raw) + b"\x00") == []
        assert dec.errors == dict({"framing": 0, "length": 0, "crc": 0, "version": 0},
                                  **{kind: 1})
    with pytest.raises(FrameError, match="version 2, this end speaks 1"):
        decode_frame(cases["version"])
    assert FrameDecoder().feed(encode_frame(Message(1, 2, 3, b"x"), version=7)) == []


def test_a_long_run_without_delimiter_is_dropped_and_counted():
    dec = FrameDecoder()
    msg = Message(MSG_WRITE, 1, 2, b"ab")
    assert dec.feed(b"\x01" * (2 * MAX_FRAME + 1)) == []
    assert dec.errors["length"] == 1
    assert dec.feed(encode_frame(msg)) == [msg]     # what follows the dropped run still counts


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
    """Flip 1..4 bits of the decoded frame: CRC-32 detects every error of up to four bits in
    frames this short (Hamming distance 5 up to 2974 bits, Koopman 2002; a frame has at most
    2032)."""
    raw = bytearray(msg.raw())
    nbits = len(raw) * 8
    flips = data.draw(st.sets(st.integers(0, nbits - 1), min_size=1, max_size=4))
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
        write_message(0, 0, 0, [0] * 81, 18).raw()          # 12 + 2 + 243 bytes
    assert len(write_message(0, 0, 0, [0] * 80, 18).raw()) == MAX_FRAME


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
