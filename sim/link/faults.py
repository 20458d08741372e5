"""Line faults for the UART link: what a noisy wire does to a frame's bytes, and frames that
exercise the edge cases of COBS and the CRC.

Used by the link's error-detection tests (host codec, Amaranth simulator, cocotb) and for
fault injection (:class:`~cuneate.sim.host.uart.ModelSerial` takes a ``corrupt`` function). A
*wire* is one encoded frame as sent: its COBS bytes and the 0x00 delimiter
(:func:`~cuneate.hdl.link.codec.encode_frame`). Every corruption works on the wire, delimiter
included, as the UART would deliver it:

``bit``
    one bit flipped (:func:`single_bit_flips` enumerates all ``8 * len(wire)``).
``bits2``, ``bits3``
    two or three distinct bits flipped anywhere in the wire.
``code_bits2``
    two bits flipped in the COBS structure (code bytes and the delimiter): the errors that
    move zeros and block boundaries rather than change data.
``byte``
    one byte replaced by a different random value (a burst within a byte).
``drop``, ``drops``
    one byte lost (:func:`single_byte_drops` enumerates all), or two to four bytes lost
    (a UART stop-bit error discards the byte).
``insert``, ``inserts``
    one random byte inserted (a glitch read as a start bit), or two to four.

A corruption that leaves the frames a receiver would see unchanged (a 0x00 inserted next to
the delimiter is only an idle delimiter) is not a corruption: :func:`corrupt` never returns
one, :func:`is_noop` tells them.
"""

from __future__ import annotations

import random
import struct
from dataclasses import dataclass

from ...hdl.link.codec import (COUNTER_NAMES, CRC_BYTES, MAX_PAYLOAD, MSG_CONTROL, MSG_COUNTERS,
                              MSG_SPIKES, MSG_WRITE, OP_CLEAR_COUNTERS, OP_READ_COUNTERS,
                              OP_START, OP_STEP, Message, cobs_decode, cobs_encode,
                              control_message, encode_frame, write_message)

__all__ = ["KINDS", "flip", "single_bit_flips", "single_byte_drops", "corrupt", "is_noop",
           "chunks", "with_crc_byte", "zero_free", "edge_messages", "wire_of", "Planned",
           "fault_plan", "plan_outcome", "frame_type", "OnFrame", "OnChunk",
           "Recorder"]

KINDS = ("bit", "bits2", "bits3", "code_bits2", "byte", "drop", "drops", "insert", "inserts")


def flip(wire: bytes, bits) -> bytes:
    """``wire`` with the given bit positions (``8 * byte + bit``, bit 0 = LSB) inverted."""
    out = bytearray(wire)
    for b in bits:
        out[b // 8] ^= 1 << (b % 8)
    return bytes(out)


def single_bit_flips(wire: bytes):
    """Every wire with exactly one bit flipped, in order of bit position."""
    for b in range(8 * len(wire)):
        yield flip(wire, (b,))


def single_byte_drops(wire: bytes):
    """Every wire with exactly one byte removed, in order of position."""
    for i in range(len(wire)):
        yield wire[:i] + wire[i + 1:]


def chunks(stream: bytes) -> list[bytes]:
    """The non-empty runs between 0x00 bytes that a receiver decodes as frames (the bytes
    after the last delimiter are not a frame yet)."""
    return [c for c in bytes(stream).split(b"\x00")[:-1] if c]


def is_noop(wire: bytes, damaged: bytes) -> bool:
    """True when ``damaged`` delivers exactly the frames ``wire`` does."""
    return chunks(wire) == chunks(damaged) and \
        bytes(wire).split(b"\x00")[-1] == bytes(damaged).split(b"\x00")[-1]


def _code_positions(wire: bytes) -> list[int]:
    """Positions of the COBS code bytes and of the delimiter in an intact wire."""
    pos, i, n = [], 0, len(wire) - 1
    while i < n:
        pos.append(i)
        i += wire[i]
    return pos + [n]


def corrupt(wire: bytes, kind: str, rng: random.Random) -> bytes:
    """One random corruption of class ``kind`` (see :data:`KINDS`) of an intact ``wire``,
    never a no-op."""
    if kind not in KINDS:
        raise ValueError(f"unknown corruption class {kind!r}; the classes are {', '.join(KINDS)}")
    wire = bytes(wire)
    n = len(wire)
    while True:
        if kind in ("bit", "bits2", "bits3"):
            k = {"bit": 1, "bits2": 2, "bits3": 3}[kind]
            out = flip(wire, rng.sample(range(8 * n), k))
        elif kind == "code_bits2":
            pos = _code_positions(wire)
            bits = [8 * p + b for p in pos for b in range(8)]
            out = flip(wire, rng.sample(bits, 2))
        elif kind == "byte":
            i = rng.randrange(n)
            out = wire[:i] + bytes([rng.choice([v for v in range(256) if v != wire[i]])]) + \
                wire[i + 1:]
        elif kind in ("drop", "drops"):
            k = 1 if kind == "drop" else rng.randint(2, 4)
            gone = set(rng.sample(range(n), min(k, n - 1)))
            out = bytes(b for i, b in enumerate(wire) if i not in gone)
        else:
            k = 1 if kind == "insert" else rng.randint(2, 4)
            out = bytearray(wire)
            for _ in range(k):
                out.insert(rng.randrange(len(out) + 1), rng.randrange(256))
            out = bytes(out)
        if not is_noop(wire, out):
            return out


# ----------------------------------------------------------------------------------------------
# Frames for the edge cases

def with_crc_byte(msg: Message, index: int, value: int = 0, start: int = 1) -> Message:
    """``msg`` with the first ``tick`` from ``start`` on that puts ``value`` in byte ``index``
    (0 = least significant, sent first) of its CRC."""
    for tick in range(start, start + (1 << 20)):
        m = Message(msg.type, msg.seq, tick & 0xFFFFFFFF, msg.payload)
        if m.raw()[-CRC_BYTES + index] == value:
            return m
    raise ValueError(f"no tick in {start}..{start + (1 << 20) - 1} gives CRC byte {index} "
                     f"= {value:#04x}")


def zero_free(msg: Message, rng: random.Random) -> Message:
    """``msg`` with a sequence number and a tick that leave no zero byte in the whole frame
    (one COBS block); its payload must be free of zeros and not empty (``len`` is a byte)."""
    if not msg.payload or 0 in msg.payload:
        raise ValueError("a frame without zero bytes needs a non-empty payload without zeros")
    while True:
        m = Message(msg.type, rng.randrange(1, 256), rng.randrange(1 << 32), msg.payload)
        if 0 not in m.raw():
            return m


def _payloads(size: int, rng: random.Random):
    """Random, all-zero and zero-free payloads of ``size`` bytes."""
    yield "random", bytes(rng.randrange(256) for _ in range(size))
    yield "zeros", bytes(size)
    yield "nonzero", bytes(rng.randrange(1, 256) for _ in range(size))


def edge_messages(sizes=None, seed: int = 0) -> list[tuple[str, Message]]:
    """Frames of every message type over a range of payload sizes, each as ``(label, msg)``.

    Per type and size: random, all-zero and zero-free payloads; the zero-free one with a tick
    that leaves no zero byte anywhere in the frame (a single COBS block: code 0xFF for the
    254-byte frame); and four random ones whose CRC has a 0x00 in byte 0, 1, 2 and 3 (byte 3,
    the frame's last, ends the COBS encoding with the code byte 0x01, one bit from a
    delimiter). ``sizes`` are payload sizes (default: 0..5, Fibonacci steps to 144, and the
    two largest: 253- and 254-byte frames). Each type takes the sizes its layout allows:
    ``WRITE`` any (8-bit currents; below 2 bytes a runt the device refuses), ``SPIKES``
    ``3 + 3k``, ``CONTROL`` 5 (every opcode), ``COUNTERS`` 4 per counter."""
    rng = random.Random(seed)
    if sizes is None:
        sizes = sorted({0, 1, 2, 3, 4, 5, 8, 13, 21, 34, 55, 89, 144,
                        MAX_PAYLOAD - 1, MAX_PAYLOAD})
    layouts = {MSG_WRITE: list(sizes),
               MSG_SPIKES: sorted({3 + 3 * ((s - 3) // 3) for s in sizes if s >= 3}),
               MSG_CONTROL: [5], MSG_COUNTERS: [4 * len(COUNTER_NAMES)]}
    out = []
    seq = 0
    for typ, ss in layouts.items():
        for size in ss:
            if typ == MSG_CONTROL:
                contents = [(f"op{op}", struct.pack("<BI", op, rng.randrange(1 << 32)))
                            for op in range(OP_START, OP_CLEAR_COUNTERS + 1)]
                contents += [("zeros", bytes(5)),
                             ("nonzero", struct.pack("<BI", OP_START, 0x01010101))]
            else:
                contents = list(_payloads(size, rng))
            for label, payload in contents:
                seq = (seq + 1) & 0xFF
                msg = Message(typ, seq, rng.randrange(1 << 32), payload)
                if label == "nonzero" and size:
                    msg = zero_free(msg, rng)
                out.append((f"{typ:#04x}/{size}/{label}", msg))
            for index in range(CRC_BYTES):
                seq = (seq + 1) & 0xFF
                base = Message(typ, seq, 0, contents[0][1])
                msg = with_crc_byte(base, index, 0, rng.randrange(1 << 31))
                out.append((f"{typ:#04x}/{size}/crc{index}=0", msg))
    return out


def wire_of(msg: Message) -> bytes:
    """The intact wire of ``msg`` (COBS and delimiter)."""
    return cobs_encode(msg.raw()) + b"\x00"


def frame_type(wire: bytes) -> int:
    """The message type of an intact wire."""
    return cobs_decode(bytes(wire).rstrip(b"\x00"))[1]


class _OnNth:
    """A line fault on the ``nth`` (from 0) piece of bytes that :meth:`matches`:
    ``damage(bytes) -> bytes``; ``hit`` once it acted."""

    def __init__(self, damage, nth: int):
        self.damage, self.nth, self.seen, self.hit = damage, nth, 0, False

    def matches(self, data: bytes) -> bool:
        raise NotImplementedError

    def __call__(self, data: bytes) -> bytes:
        if self.matches(data):
            self.seen += 1
            if self.seen == self.nth + 1:
                self.hit = True
                return self.damage(data)
        return data


class OnFrame(_OnNth):
    """A line fault on the ``nth`` (from 0) frame of type ``typ`` the host writes (a transport
    writes one frame a call): ``damage(wire) -> wire``; ``hit`` once it acted."""

    def __init__(self, typ: int, damage, nth: int = 0):
        super().__init__(damage, nth)
        self.typ = typ

    def matches(self, data: bytes) -> bool:
        return frame_type(data) == self.typ


class OnChunk(_OnNth):
    """A line fault on the ``nth`` (from 0) non-empty chunk of bytes a device sends."""

    def matches(self, data: bytes) -> bool:
        return bool(data)


class Recorder:
    """No fault: passes a direction's bytes on unchanged and keeps a copy (``data``)."""

    def __init__(self):
        self.data = bytearray()

    def __call__(self, data: bytes) -> bytes:
        self.data += data
        return data


# ----------------------------------------------------------------------------------------------
# A host-to-device stream of intact and damaged frames, and what a correct receiver makes of it

@dataclass(frozen=True)
class Planned:
    """One frame of a :func:`fault_plan` as sent: ``wire`` (damaged or intact), ``msg`` (the
    intact message, ``None`` for a damaged frame) and the ``(neuron, raw current)`` pairs an
    intact ``WRITE`` applies."""

    wire: bytes
    msg: Message | None = None
    writes: tuple = ()


def fault_plan(current_width: int, n_neurons: int, rng: random.Random, per_kind: int = 4,
               code_bytes=(), big_frames: bool = False,
               read_counters: bool = True) -> list[Planned]:
    """Damaged host frames between intact ones, sequence numbers 0, 1, 2, ... over all.

    Intact frames are ``WRITE`` s of two random currents for sweep 0 (applied at once on a
    stopped core). Damaged frames, each mostly followed by an intact one:

    * ``per_kind`` of each class of :data:`KINDS`, on ``WRITE`` s of one to eight random
      currents and ``CONTROL`` frames that would run the core (``START``, ``STEP``) or read or
      clear its counters;
    * every bit of the ``code_bytes`` (any of ``"first"``, ``"last"``, ``"delimiter"``) of a
      write whose frame ends in 0x00: its last code byte is 0x01, one bit from a delimiter
      that would cut the frame's last byte;
    * with ``big_frames``, three flips of a 254-byte one-block frame (code 0xFF; 3-byte
      currents only; intact it would write neurons 257 to 336, out of range for smaller cores).

    Then an intact frame of format version 3 (refused as a version error), an intact write,
    and (``read_counters``) ``READ_COUNTERS``."""
    W = (current_width + 7) // 8
    lo, hi = -(1 << (current_width - 1)), (1 << (current_width - 1)) - 1
    plan: list[Planned] = []

    def seq():
        return len(plan) & 0xFF

    def good():
        first = rng.randrange(n_neurons - 1)
        vals = [rng.randint(lo, hi) for _ in range(2)]
        msg = write_message(seq(), 0, first, vals, current_width)
        plan.append(Planned(wire_of(msg), msg, tuple((first + i, v)
                                                     for i, v in enumerate(vals))))

    def bad(wire):
        plan.append(Planned(bytes(wire)))

    def victim():
        if rng.random() < 0.3:
            op = rng.choice([OP_START, OP_STEP, OP_STEP, OP_CLEAR_COUNTERS, OP_READ_COUNTERS])
            return control_message(seq(), op, rng.randrange(1, 1 << 16))
        n = rng.randint(1, min(8, n_neurons))
        first = rng.randrange(n_neurons - n + 1)
        return write_message(seq(), 0, first, [rng.randint(lo, hi) for _ in range(n)],
                             current_width)

    def ends_in_zero():
        first = max(0, n_neurons - 8)
        vals = [rng.randint(1, hi) for _ in range(min(8, n_neurons))]
        w = wire_of(with_crc_byte(write_message(seq(), 0, first, vals, current_width),
                                  CRC_BYTES - 1))
        assert w[-2:] == b"\x01\x00"
        return w

    good()
    for kind in KINDS:
        for _ in range(per_kind):
            bad(corrupt(wire_of(victim()), kind, rng))
            if rng.random() < 0.5:
                good()
        if per_kind:
            good()
    unknown = set(code_bytes) - {"first", "last", "delimiter"}
    if unknown:
        raise ValueError(f"unknown code bytes {sorted(unknown)}: first, last or delimiter")
    for where in ("first", "last", "delimiter"):
        if where in code_bytes:
            for b in range(8):
                w = ends_in_zero()
                at = {"first": 0, "last": len(w) - 2, "delimiter": len(w) - 1}[where]
                bad(flip(w, (8 * at + b,)))
                good()
    if big_frames and W == 3:
        for b in (0, 7, 8 * 100 + 3):         # the code byte 0xFF -> 0xFE, 0x7F; a data bit
            vals = [rng.randint(1, 255) | 0x010100 for _ in range(80)]
            big = zero_free(write_message(0, 0, 0x0101, vals, current_width), rng)
            w = wire_of(Message(big.type, seq(), big.tick, big.payload))
            if len(w) == 256 and w[0] == 0xFF and 0 not in w[:-1]:
                bad(flip(w, (b,)))
                good()
    bad(encode_frame(write_message(seq(), 0, 0, [1, 2], current_width), version=3))
    good()
    if read_counters:
        msg = control_message(seq(), OP_READ_COUNTERS)
        plan.append(Planned(wire_of(msg), msg))
    return plan


def plan_outcome(plan: list[Planned]) -> tuple[list[Planned], int]:
    """What a correct receiver makes of a plan's stream, by byte comparison alone: the intact
    frames that arrive (a damaged delimiter merges the next frame into a damaged run) and the
    number of damaged runs (each refused and counted once)."""
    intact = {p.wire[:-1]: p for p in plan if p.msg is not None}
    runs = chunks(b"".join(p.wire for p in plan))
    return [intact[r] for r in runs if r in intact], sum(r not in intact for r in runs)
