"""The host link's wire format: COBS framing, CRC-32 and the message layout (format version 1).

This module is the bit-exact model of the link gateware (:mod:`cuneate.hdl.link`) and the codec
of the host side (:mod:`cuneate.boards.link`). One frame on the wire is::

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

import numpy as np
from dataclasses import dataclass, field

__all__ = [
    "crc32_update", "crc32", "cobs_encode", "cobs_decode", "CobsError", "FrameError",
    "Message", "encode_frame", "decode_frame", "FrameDecoder", "FRAME_ERRORS",
    "write_message", "control_message", "parse_spikes", "parse_counters", "current_bytes",
    "MSG_WRITE", "MSG_CONTROL", "MSG_SPIKES", "MSG_COUNTERS", "OP_START", "OP_STOP",
    "OP_STEP", "OP_READ_COUNTERS", "OP_CLEAR_COUNTERS", "SPIKE_HEADER", "CONTROL_PAYLOAD",
    "COUNTER_NAMES", "VERSION", "HEADER_BYTES", "CRC_BYTES", "CRC_INIT", "CRC_RESIDUE",
    "MIN_FRAME", "MAX_FRAME", "MAX_PAYLOAD", "LinkModel",
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
# CRC-32 (ISO-HDLC), one byte at a time, written once for ints and Amaranth values.

_POLY_REFLECTED = 0xEDB88320      # 0x04C11DB7 with its bits reversed (LSB-first register)


def _crc32_step_int(crc: int, byte: int) -> int:
    crc ^= byte
    for _ in range(8):
        crc = (crc >> 1) ^ _POLY_REFLECTED if crc & 1 else crc >> 1
    return crc


# The step is linear over GF(2) in (crc, byte): output bit i is the XOR of the input bits in
# _CRC_TAPS[i] (bits 0-31 of crc, then bits 0-7 of the byte as 32-39), derived from the
# bitwise definition above so that the RTL cannot disagree with it.
_CRC_TAPS = tuple(
    tuple(j for j in range(40)
          if (_crc32_step_int(1 << j if j < 32 else 0, 1 << (j - 32) if j >= 32 else 0)
              >> i) & 1)
    for i in range(32))
# the step on the byte values, for the host's byte loop: step(crc, b) is
# (crc >> 8) ^ _CRC_TABLE[(crc ^ b) & 0xFF] because the step is linear
_CRC_TABLE = tuple(_crc32_step_int(i, 0) for i in range(256))


def crc32_update(crc, byte):
    """CRC-32 register (32 bits, reflected: LSB first) after one more byte; no init, no final
    xor. On ints: the bitwise definition; on Amaranth values: one XOR tree per output bit from
    the same definition (the gateware uses this function)."""
    from amaranth.hdl import Cat
    from .fixed import is_hdl
    if not (is_hdl(crc) or is_hdl(byte)):
        return _crc32_step_int(int(crc), int(byte))
    bits = Cat(crc, byte)
    out = []
    for taps in _CRC_TAPS:
        x = bits[taps[0]]
        for t in taps[1:]:
            x = x ^ bits[t]
        out.append(x)
    return Cat(*out)


def _crc32_register(data: bytes, crc: int = CRC_INIT) -> int:
    """The register after ``data`` (:func:`crc32_update` byte by byte, by its table)."""
    table = _CRC_TABLE
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


# ----------------------------------------------------------------------------------------------
# Device model: what the link gateware answers, sweep for sweep, when no timing loss occurs

class LinkModel:
    """Behavioural model of :class:`cuneate.hdl.link.LinkedCore` on the bit-exact twin.

    Feed it the host's bytes (:meth:`feed`); it returns the bytes the device sends. It follows
    the gateware's rules (framing, length, CRC, version, sequence, range and late-write checks,
    the same counters, saturating at ``counter_width`` bits; writes take effect exactly at
    their sweep; one ``SPIKES`` frame per batch) for a device fast enough that no tick, batch
    or FIFO is lost. A ``WRITE`` for a future sweep runs
    the core up to that sweep when steps allow it (as the device does while stepping).
    """

    def __init__(self, lcfg):
        from .izhikevich import IzhikevichTwin
        self.lcfg = lcfg
        self.twin = IzhikevichTwin(lcfg.core)
        self.counters = {n: 0 for n in COUNTER_NAMES}
        self.S = 0
        self.free = False
        self.steps = 0
        self.exp_seq = 0
        self.tx_seq = 0
        self._rx = bytearray()
        self._batch: list[tuple[int, int]] = []
        self._batch_tick = 0
        self._in_batch = 0
        self._dropped = 0
        self._out = bytearray()

    def _send(self, typ: int, tick: int, payload: bytes):
        self._out += encode_frame(Message(typ, self.tx_seq, tick & 0xFFFFFFFF, payload))
        self.tx_seq = (self.tx_seq + 1) & 0xFF

    def _sweep(self):
        spk = np.flatnonzero(self.twin.sweep())
        cap = self.lcfg.batch_capacity
        for n in spk:
            if len(self._batch) < cap:
                self._batch.append((self.S - self._batch_tick, int(n)))
            else:
                self._dropped += 1
                self.counters["spikes_dropped"] += 1
        self.S += 1
        if not self.free:
            self.steps -= 1
        self._in_batch += 1
        if self._in_batch == self.lcfg.batch_sweeps or (not self.free and self.steps == 0):
            payload = struct.pack("<HB", min(self._dropped, 0xFFFF), self._in_batch)
            for off, n in self._batch:
                payload += struct.pack("<BH", off, n)
            self._send(MSG_SPIKES, self._batch_tick, payload)
            self._batch_tick += self._in_batch
            self._batch, self._in_batch, self._dropped = [], 0, 0

    def advance(self, n: int):
        """Run ``n`` sweeps (free running or within the current step)."""
        for _ in range(n):
            if not (self.free or self.steps > 0):
                break
            self._sweep()

    def feed(self, data: bytes) -> bytes:
        for b in data:
            if b:
                self._rx.append(b)
                continue
            chunk, self._rx = bytes(self._rx), bytearray()
            if chunk:
                self._frame(chunk)
        out, self._out = bytes(self._out), bytearray()
        return out

    def _frame(self, chunk: bytes):
        c = self.counters
        try:
            raw = cobs_decode(chunk)
        except CobsError:
            c["framing_errors"] += 1
            return
        try:
            msg = decode_frame(raw)
        except FrameError as exc:
            c[f"{exc.kind}_errors"] += 1
            return
        c["seq_gaps"] += (msg.seq - self.exp_seq) & 0xFF
        self.exp_seq = (msg.seq + 1) & 0xFF
        W = self.lcfg.current_bytes
        n = len(msg.payload) - 2
        if msg.type == MSG_WRITE and n >= 0 and n % W == 0:
            first = struct.unpack_from("<H", msg.payload)[0]
            vals = [int.from_bytes(msg.payload[2 + i:2 + i + W], "little")
                    for i in range(0, n, W)]
            w = self.lcfg.current_width
            vals = [((v & ((1 << w) - 1)) ^ (1 << (w - 1))) - (1 << (w - 1)) for v in vals]
            if first + len(vals) > self.lcfg.core.n_neurons:
                c["range_errors"] += 1
                return
            c["frames_ok"] += 1
            while self.S < msg.tick:
                if not (self.free or self.steps > 0):
                    raise RuntimeError(f"write for sweep {msg.tick} waits forever: the core is "
                                       f"stopped at sweep {self.S}")
                self._sweep()
            if self.S > msg.tick:
                c["late_writes"] += 1
                return
            self.twin.I[first:first + len(vals)] = vals
        elif (msg.type == MSG_CONTROL and len(msg.payload) == CONTROL_PAYLOAD
              and OP_START <= msg.payload[0] <= OP_CLEAR_COUNTERS):
            c["frames_ok"] += 1
            op, arg = struct.unpack("<BI", msg.payload)
            if op == OP_START:
                self.free = True
            elif op == OP_STOP:
                self.free, self.steps = False, 0
            elif op == OP_STEP:
                self.free, self.steps = False, arg
            elif op == OP_READ_COUNTERS:
                top = (1 << self.lcfg.counter_width) - 1       # saturated, as the device's
                self._send(MSG_COUNTERS, self.S,
                           struct.pack(f"<{len(COUNTER_NAMES)}I",
                                       *(min(c[k], top) for k in COUNTER_NAMES)))
            elif op == OP_CLEAR_COUNTERS:
                for k in c:
                    c[k] = 0
        else:
            c["length_errors"] += 1
