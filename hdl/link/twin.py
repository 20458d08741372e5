"""The link's bit-exact model (:class:`LinkModel`): what the link gateware answers, sweep for
sweep, on the twin of the block behind it, when no timing loss occurs."""

from __future__ import annotations

import struct

from .codec import (CONTROL_PAYLOAD, COUNTER_NAMES, MSG_CONTROL, MSG_COUNTERS, MSG_SPIKES,
                    MSG_WRITE, OP_CLEAR_COUNTERS, OP_READ_COUNTERS, OP_START, OP_STEP, OP_STOP,
                    CobsError, FrameError, Message, cobs_decode, decode_frame, encode_frame)

__all__ = ["LinkModel"]

class LinkModel:
    """Behavioural model of :class:`cuneate.hdl.link.LinkedTop` on the block's bit-exact twin
    (:meth:`~cuneate.hdl.lib.payload.PayloadSpec.twin`).

    Feed it the host's bytes (:meth:`feed`); it returns the bytes the device sends. It follows
    the gateware's rules (framing, length, CRC, version, sequence, range and late-write checks,
    the same counters, saturating at ``counter_width`` bits; writes take effect exactly at
    their sweep; one ``SPIKES`` frame per batch) for a device fast enough that no tick, batch
    or FIFO is lost. A ``WRITE`` for a future sweep runs
    the core up to that sweep when steps allow it (as the device does while stepping).
    """

    def __init__(self, lcfg):
        self.lcfg = lcfg
        self.twin = lcfg.payload.twin()
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
        spk = self.twin.sweep()
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
            if first + len(vals) > self.lcfg.n_written:
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
            for n, raw in enumerate(vals, start=first):
                self.twin.write(n, raw)
            if vals:                          # the burst's last value ends it
                self.twin.end_burst()
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
