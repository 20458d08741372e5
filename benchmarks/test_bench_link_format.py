"""Why the link's frames carry a length and a CRC-32: single-bit wire errors accepted by three
candidate formats over the same frames.

* ``crc16`` the unversioned format of earlier builds: ``type seq tick payload`` and
  CRC-16/CCITT (init 0xFFFF, no final xor) big-endian, no length;
* ``crc16+len`` CRC-16/CCITT with a final xor 0xFFFF (CRC-16/GENIBUS, residue not zero), the
  version byte and the length field of the current format;
* ``crc32+len`` the current format (:mod:`cuneate.hdl.link.codec`, decoded by its
  ``FrameDecoder``).

Frames: ``WRITE`` payloads of every even size from 0 to 242 bytes, random, all-zero and
zero-free, each once with a random tick and once with the first tick that makes the frame's
last byte 0x00 in that format (the frames whose COBS encoding ends in the code byte 0x01, one
bit from a delimiter). Every bit of every encoded frame (delimiter included) is flipped; a
damaged frame counts as accepted when some run of the stream decodes, passes the format's
checks and differs from the intact frame (for the current format, the codec's ``FrameDecoder``
must agree). Runs that pass every check but the CRC and differ from the intact frame beyond
what the CRC catches with certainty (fewer bits than its Hamming distance, or a burst within
its width) pass the CRC with probability 2**-width: their count times that is the expected
number accepted. References: ``binascii.crc_hqx`` and ``zlib.crc32``. Prints the counts and
writes ``benchmarks/results/link_format.json``; asserts only that the current format accepted
none.
"""

from __future__ import annotations

import binascii
import random
import struct
import time
import zlib

import pytest

from cuneate.sim.link.faults import single_bit_flips
from cuneate.hdl.link.codec import (MAX_PAYLOAD, MSG_WRITE, CobsError, FrameDecoder, Message,
                                    cobs_decode, cobs_encode)

from .conftest import report

pytestmark = pytest.mark.benchmark


def _crc16(data: bytes) -> int:
    return binascii.crc_hqx(data, 0xFFFF)


class Format:
    """A candidate: ``make`` builds the decoded frame, ``plausible`` checks everything but the
    CRC (size, version, length), ``crc_ok`` the CRC; ``bits`` is the CRC's width and ``hd`` its
    Hamming distance at these lengths (errors of fewer bits, or within a burst of ``bits``
    bits, are detected with certainty)."""

    def __init__(self, name, make, plausible, crc_ok, bits, hd):
        self.name, self.make, self.plausible, self.crc_ok = name, make, plausible, crc_ok
        self.bits, self.hd = bits, hd

    def certain(self, raw: bytes, orig: bytes) -> bool:
        if len(raw) != len(orig):
            return False
        diff = [i for i, (a, b) in enumerate(zip(raw, orig)) if a != b]
        weight = (int.from_bytes(raw, "little") ^ int.from_bytes(orig, "little")).bit_count()
        return weight < self.hd or diff[-1] - diff[0] < self.bits // 8


FORMATS = [
    Format("crc16",
           lambda t, s, k, p: (lambda b: b + struct.pack(">H", _crc16(b)))(
               struct.pack("<BBI", t, s, k) + p),
           lambda r: 8 <= len(r) <= 254, lambda r: _crc16(r) == 0, 16, 4),
    Format("crc16+len",
           lambda t, s, k, p: (lambda b: b + struct.pack(">H", _crc16(b) ^ 0xFFFF))(
               struct.pack("<BBBBI", 1, t, s, len(p), k) + p),
           lambda r: 10 <= len(r) <= 254 and r[0] == 1 and r[3] == len(r) - 10,
           lambda r: _crc16(r[:-2]) ^ 0xFFFF == struct.unpack(">H", r[-2:])[0], 16, 4),
    Format("crc32+len",
           lambda t, s, k, p: Message(t, s, k, p).raw(),
           lambda r: 12 <= len(r) <= 254 and r[0] == 1 and r[3] == len(r) - 12,
           lambda r: zlib.crc32(r) == 0x2144DF1C, 32, 5),
]


def _frames(make, last_zero: bool, rng: random.Random):
    for size in range(0, MAX_PAYLOAD + 1, 2):
        for payload in (bytes(rng.randrange(256) for _ in range(size)), bytes(size),
                        bytes(rng.randrange(1, 256) for _ in range(size))):
            seq = rng.randrange(1, 256)
            if not last_zero:
                yield seq, rng.randrange(1 << 32), payload
                continue
            start = rng.randrange(1 << 31)
            for tick in range(start, start + (1 << 16)):
                if make(MSG_WRITE, seq, tick, payload)[-1] == 0:
                    yield seq, tick, payload
                    break


def test_single_bit_flips_accepted_by_candidate_formats():
    rows = []
    for f in FORMATS:
        t0 = time.perf_counter()
        frames = flips = accepted = uncertain = decoder_accepted = 0
        for last_zero in (False, True):
            for seq, tick, payload in _frames(f.make, last_zero, random.Random(7)):
                frames += 1
                raw = f.make(MSG_WRITE, seq, tick, payload)
                for damaged in single_bit_flips(cobs_encode(raw) + b"\x00"):
                    flips += 1
                    hit = False
                    for run in damaged.split(b"\x00"):
                        try:
                            got = cobs_decode(run) if run else None
                        except CobsError:
                            continue
                        if got is None or got == raw or not f.plausible(got):
                            continue
                        uncertain += not f.certain(got, raw)
                        hit |= f.crc_ok(got)
                    accepted += hit
                    if f.name == "crc32+len":
                        msg = Message(MSG_WRITE, seq, tick, payload)
                        decoder_accepted += any(m != msg for m in FrameDecoder().feed(damaged))
        rows.append({"format": f.name, "frames": frames, "single-bit flips": flips,
                     "accepted": accepted,
                     "reach the CRC, not certainly caught": uncertain,
                     "expected accepted": uncertain * 2.0 ** -f.bits,
                     "per flip": uncertain / flips * 2.0 ** -f.bits,
                     "seconds": time.perf_counter() - t0})
    report("link_format", "Single-bit wire flips accepted by candidate link frame formats", rows)
    assert rows[-1]["accepted"] == 0 and decoder_accepted == 0
    assert all(r["single-bit flips"] > 0 for r in rows)
