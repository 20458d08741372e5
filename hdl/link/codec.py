"""The host link's wire format: COBS framing, CRC-32 and the message layout (format version 1).

This module is the codec of the host side (:mod:`cuneate.sim.host.uart`) and of the device
model (:mod:`cuneate.hdl.link.twin`); the gateware (:mod:`cuneate.hdl.link.core`) shares its
constants and its CRC step (:mod:`cuneate.hdl.link.datapath`). One frame on the wire is::

    COBS( version u8 | type u8 | seq u8 | len u8 | tick u32 LE | payload (len bytes)
          | crc u32 LE )  0x00

* ``version`` is :data:`VERSION` (1). Every later format keeps the version byte first and the
  CRC-32 trailer, so a receiver can tell an intact frame of another version from a damaged
  one: an intact frame (CRC good) whose version differs is refused and counted as a version
  error. Earlier builds sent unversioned CRC-16 frames; to this format they are CRC errors.
* ``len`` is the number of payload bytes; a frame whose decoded size is not
  ``len + ``:data:`MIN_FRAME` is refused (length error). The length is inside the CRC, so a
  lost or an added byte is refused twice over: by the length and by the CRC.
* **CRC-32** (ISO-HDLC: the CRC of Ethernet and zlib; poly 0x04C11DB7 reflected (0xEDB88320),
  init 0xFFFFFFFF, final xor 0xFFFFFFFF; check value 0xCBF43926 for ``b"123456789"``) over
  ``version .. payload``, appended little-endian. The register run over a whole intact frame,
  CRC included, ends at :data:`CRC_RESIDUE` (0xDEBB20E3), not at zero: zero bytes appended to or
  removed from the end of a frame change it.
* **COBS** (Cheshire and Baker, 1999) removes every zero byte; a zero byte ends a frame. A zero
  in the middle of a COBS block (a truncated frame) or a frame that decodes to fewer than
  :data:`MIN_FRAME` or more than :data:`MAX_FRAME` bytes is a framing or length error.
* **Sequence numbers** count frames per direction modulo 256; a gap is counted (device) or
  raised (host).

Checks, in the order both ends apply them (the first failure names the error; nothing of a
refused frame acts): COBS framing, decoded size (:data:`MIN_FRAME` .. :data:`MAX_FRAME`), CRC,
version, ``len``; then (device) the sequence number and the type's payload layout.

Messages, host to device:

``WRITE`` (0x01)
    ``tick`` = first sweep in which the currents take effect; payload ``first u16 LE`` then
    ``count`` currents of ``current_bytes`` bytes each (two's complement, little-endian, the
    low ``current_width`` bits are used). Applied between sweep ``tick - 1`` and sweep ``tick``;
    a write for a sweep that has already started is refused and counted ``late``.
``CONTROL`` (0x02)
    payload ``op u8, arg u32 LE``: :data:`OP_START` (run freely at the tick rate),
    :data:`OP_STOP`, :data:`OP_STEP` (run ``arg`` more sweeps at the tick rate, then stop and
    send the partial batch), :data:`OP_READ_COUNTERS`, :data:`OP_CLEAR_COUNTERS`.

Device to host:

``SPIKES`` (0x81)
    one per batch of ``batch_sweeps`` sweeps (16 at 16 kHz: one per millisecond), sent even
    when empty; ``tick`` = first sweep of the batch; payload ``dropped u16 LE`` (spikes of this
    batch that did not fit), ``sweeps u8`` (sweeps the batch covers: ``batch_sweeps``, or fewer
    when a step ended) then per spike ``offset u8`` (sweep - tick) and ``neuron u16 LE``,
    in the order the core produced them (sweep, then neuron).
``COUNTERS`` (0x82)
    answer to ``OP_READ_COUNTERS``; ``tick`` = sweeps started so far; payload one u32 LE per
    name of :data:`COUNTER_NAMES`.
"""

from __future__ import annotations

import struct

from dataclasses import dataclass, field

from .datapath import crc32_table

__all__ = [
    "crc32", "cobs_encode", "cobs_decode", "CobsError", "FrameError",
    "Message", "encode_frame", "decode_frame", "FrameDecoder", "FRAME_ERRORS",
    "write_message", "control_message", "parse_spikes", "parse_counters", "current_bytes",
    "MSG_WRITE", "MSG_CONTROL", "MSG_SPIKES", "MSG_COUNTERS", "OP_START", "OP_STOP",
    "OP_STEP", "OP_READ_COUNTERS", "OP_CLEAR_COUNTERS", "SPIKE_HEADER", "CONTROL_PAYLOAD",
    "COUNTER_NAMES", "VERSION", "HEADER_BYTES", "CRC_BYTES", "CRC_INIT", "CRC_RESIDUE",
    "MIN_FRAME", "MAX_FRAME", "MAX_PAYLOAD",
]

VERSION = 1               # frame format version (byte 0 of every frame)
MSG_WRITE, MSG_CONTROL, MSG_SPIKES, MSG_COUNTERS = 0x01, 0x02, 0x81, 0x82
OP_START, OP_STOP, OP_STEP, OP_READ_COUNTERS, OP_CLEAR_COUNTERS = 1, 2, 3, 4, 5
SPIKE_HEADER = 3          # dropped u16, sweeps u8
CONTROL_PAYLOAD = 5
HEADER_BYTES = 8          # version, type, seq, len, tick u32
CRC_BYTES = 4             # CRC-32, little-endian
CRC_INIT = 0xFFFFFFFF     # CRC register before the first byte
CRC_RESIDUE = 0xDEBB20E3  # CRC register after an intact frame, its CRC included
MIN_FRAME = HEADER_BYTES + CRC_BYTES
MAX_FRAME = 254           # decoded bytes, CRC included (one COBS block at most)
MAX_PAYLOAD = MAX_FRAME - MIN_FRAME

#: Device counters, in the order of the ``COUNTERS`` payload.
COUNTER_NAMES = (
    "frames_ok",        # frames accepted (CRC good, well formed)
    "crc_errors",       # frames whose CRC failed
    "framing_errors",   # truncated COBS blocks, UART stop-bit errors
    "length_errors",    # frames too short or too long, a len field that disagrees with the
                        # frame's size, an unknown type or a payload size wrong for the type
    "version_errors",   # intact frames (CRC good) of another format version
    "seq_gaps",         # host frames missing between two accepted ones (sum of gaps)
    "late_writes",      # writes refused because their sweep had started
    "range_errors",     # writes past the last neuron
    "rx_overflows",     # bytes dropped because the receive FIFO was full
    "spikes_dropped",   # spikes that found no room in their batch
    "batches_dropped",  # spike batches lost because the transmitter was still busy
    "tick_overruns",    # ticks skipped because a sweep was still being issued
)


class CobsError(ValueError):
    """A byte sequence that is not valid COBS."""


#: Kinds of damaged or refused frames a receiver counts (:attr:`FrameDecoder.errors`).
FRAME_ERRORS = ("framing", "length", "crc", "version")


class FrameError(ValueError):
    """A frame that fails its CRC, its version, its length or its layout; ``kind`` is one of
    :data:`FRAME_ERRORS` (``"length"`` for layout errors)."""

    def __init__(self, message: str, kind: str = "length"):
        super().__init__(message)
        self.kind = kind


# ----------------------------------------------------------------------------------------------
# CRC-32 (ISO-HDLC) over whole frames, by the table of the shared step

def _crc32_register(data: bytes, crc: int = CRC_INIT) -> int:
    """The register after ``data`` (:func:`crc32_update` byte by byte, by its table)."""
    table = crc32_table()
    for b in data:
        crc = (crc >> 8) ^ table[(crc ^ b) & 0xFF]
    return crc


def crc32(data: bytes) -> int:
    """CRC-32 of ``data`` as appended to a frame (init 0xFFFFFFFF, final xor 0xFFFFFFFF; equal
    to :func:`zlib.crc32`)."""
    return _crc32_register(data) ^ 0xFFFFFFFF


# ----------------------------------------------------------------------------------------------
# COBS

def cobs_encode(data: bytes) -> bytes:
    """COBS encoding of ``data`` (no zero byte in the result, delimiter not included).

    Written as the gateware encoder does it: scan a block of at most 254 non-zero bytes, emit
    its length + 1, then the block; a block ended by a zero skips the zero, and a zero as the
    last byte leaves one more (empty) block."""
    out = bytearray()
    n, start = len(data), 0
    while True:
        p = start
        while p < n and data[p] != 0 and p - start < 254:
            p += 1
        out.append(p - start + 1)
        out += data[start:p]
        if p < n and data[p] == 0 and p - start < 254:
            start = p + 1           # the zero is implied; an empty block may follow
        elif p < n:
            start = p               # a full 254-byte block: no implied zero
        else:
            break
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Inverse of :func:`cobs_encode`; raises :class:`CobsError` on a zero byte or a block
    longer than the data."""
    out = bytearray()
    i, n = 0, len(data)
    while i < n:
        code = data[i]
        if code == 0:
            raise CobsError(f"zero byte at offset {i} inside a COBS frame")
        block = data[i + 1:i + code]
        if len(block) != code - 1:
            raise CobsError(f"COBS block at offset {i} wants {code - 1} bytes, "
                            f"{len(block)} remain (truncated frame)")
        if 0 in block:
            raise CobsError(f"zero byte inside the COBS block at offset {i}")
        out += block
        i += code
        if code < 0xFF and i < n:
            out.append(0)
    return bytes(out)


# ----------------------------------------------------------------------------------------------
# Messages

@dataclass(frozen=True)
class Message:
    """One frame's content: ``type``, ``seq`` and ``tick`` of the header and the payload (the
    version, ``len`` and CRC are the frame's, added by :meth:`raw`)."""

    type: int
    seq: int
    tick: int
    payload: bytes = b""

    def raw(self, version: int = VERSION) -> bytes:
        """The decoded frame: ``version type seq len tick payload`` and the CRC-32 (LE).
        ``version`` other than :data:`VERSION` only to test receivers."""
        if not (0 <= self.type < 256 and 0 <= self.seq < 256 and 0 <= self.tick < 1 << 32
                and 0 <= version < 256):
            raise FrameError(f"message header out of range: version {version}, type "
                             f"{self.type}, seq {self.seq}, tick {self.tick}")
        n = len(self.payload)
        if n > MAX_PAYLOAD:
            raise FrameError(f"frame of {n + MIN_FRAME} bytes exceeds {MAX_FRAME}")
        body = struct.pack("<BBBBI", version, self.type, self.seq, n, self.tick) + \
            bytes(self.payload)
        return body + struct.pack("<I", crc32(body))


def encode_frame(msg: Message, version: int = VERSION) -> bytes:
    """Bytes on the wire: COBS of the raw frame and the 0x00 delimiter."""
    return cobs_encode(msg.raw(version)) + b"\x00"


def decode_frame(raw: bytes) -> Message:
    """A message from a decoded (un-COBSed) frame; :class:`FrameError` names what is wrong
    (its ``kind``: ``"length"``, ``"crc"`` or ``"version"``), checked in this order: size,
    CRC, version, ``len``."""
    n = len(raw)
    if n < MIN_FRAME:
        raise FrameError(f"frame of {n} bytes is shorter than {MIN_FRAME}", "length")
    if n > MAX_FRAME:
        raise FrameError(f"frame of {n} bytes exceeds {MAX_FRAME}", "length")
    if _crc32_register(raw) != CRC_RESIDUE:
        raise FrameError(f"CRC error in a {n}-byte frame", "crc")
    version, t, seq, length, tick = struct.unpack_from("<BBBBI", raw)
    if version != VERSION:
        raise FrameError(f"frame of format version {version}, this end speaks {VERSION}",
                         "version")
    if length != n - MIN_FRAME:
        raise FrameError(f"frame of {n} bytes says {length} payload bytes, "
                         f"not {n - MIN_FRAME}", "length")
    return Message(t, seq, tick, bytes(raw[HEADER_BYTES:-CRC_BYTES]))


@dataclass
class FrameDecoder:
    """Incremental receiver: feed bytes, get the intact messages; every damaged or refused
    frame is counted in :attr:`errors` by kind (:data:`FRAME_ERRORS`), never raised.

    A run of more than ``2 * MAX_FRAME`` bytes without a delimiter is dropped and counted as a
    length error (the bytes after it start a new frame)."""

    errors: dict = field(default_factory=lambda: {k: 0 for k in FRAME_ERRORS})
    _buf: bytearray = field(default_factory=bytearray)

    def feed(self, data: bytes) -> list[Message]:
        out = []
        *chunks, rest = bytes(data).split(b"\x00")
        for part in chunks:
            chunk = self._trim(bytes(self._buf) + part)
            self._buf = bytearray()
            if not chunk:
                continue
            try:
                out.append(decode_frame(cobs_decode(chunk)))
            except CobsError:
                self.errors["framing"] += 1
            except FrameError as exc:
                self.errors[exc.kind] += 1
        self._buf = bytearray(self._trim(bytes(self._buf) + rest))
        return out

    def _trim(self, buf: bytes) -> bytes:
        """Drop (and count) each leading run of ``2 * MAX_FRAME + 1`` bytes without a
        delimiter, as a byte-by-byte receiver with a buffer of ``2 * MAX_FRAME`` does."""
        limit = 2 * MAX_FRAME + 1
        while len(buf) >= limit:
            buf = buf[limit:]
            self.errors["length"] += 1
        return buf


def current_bytes(width: int) -> int:
    """Bytes per current on the wire for a current format of ``width`` bits."""
    return (width + 7) // 8


def write_message(seq: int, tick: int, first: int, raw, width: int) -> Message:
    """A ``WRITE`` of raw currents (each must fit ``width`` signed bits)."""
    nb = current_bytes(width)
    lo, hi = -(1 << (width - 1)), (1 << (width - 1)) - 1
    payload = bytearray(struct.pack("<H", first))
    for x in raw:
        x = int(x)
        if not lo <= x <= hi:
            raise FrameError(f"current {x} does not fit {width} signed bits")
        payload += (x & ((1 << (8 * nb)) - 1)).to_bytes(nb, "little")
    return Message(MSG_WRITE, seq & 0xFF, tick, bytes(payload))


def control_message(seq: int, op: int, arg: int = 0, tick: int = 0) -> Message:
    return Message(MSG_CONTROL, seq & 0xFF, tick, struct.pack("<BI", op, arg))


def parse_spikes(msg: Message) -> tuple[int, int, list[tuple[int, int]]]:
    """``(dropped, sweeps, [(sweep, neuron), ...])`` of a ``SPIKES`` message."""
    h = SPIKE_HEADER
    if msg.type != MSG_SPIKES or len(msg.payload) < h or (len(msg.payload) - h) % 3:
        raise FrameError(f"not a spikes message: type {msg.type:#x}, "
                         f"{len(msg.payload)} payload bytes")
    dropped, sweeps = struct.unpack_from("<HB", msg.payload)
    spikes = [(msg.tick + msg.payload[i], msg.payload[i + 1] | msg.payload[i + 2] << 8)
              for i in range(h, len(msg.payload), 3)]
    return dropped, sweeps, spikes


def parse_counters(msg: Message) -> dict[str, int]:
    n = len(COUNTER_NAMES)
    if msg.type != MSG_COUNTERS or len(msg.payload) != 4 * n:
        raise FrameError(f"not a counters message: type {msg.type:#x}, "
                         f"{len(msg.payload)} payload bytes")
    return dict(zip(COUNTER_NAMES, struct.unpack(f"<{n}I", msg.payload)))
