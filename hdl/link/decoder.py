"""The link's frame decoder: a byte stream in, checked frames out
(:class:`FrameDecoder`).

Bytes are COBS-decoded as they arrive with a running CRC-32; the header is kept in registers
and the values are assembled into a value RAM, so nothing acts before the frame is checked:
after the delimiter the checks' outcomes (size, CRC residue, version, ``len`` against the
size, in that order, then the sequence number and the type's layout) are registered in one
cycle and decided in the next. A good ``WRITE`` or ``CONTROL`` frame is then offered on
``frame`` and held until the consumer takes it (``ready``: it has acted on the frame, read
its values through ``value_*`` included); the decoder takes no byte meanwhile (the receive
buffer before it holds them: back-pressure). Every verdict pulses one ``count_*`` output
(``seq_gap`` carries the sequence gap of an intact frame).
"""

from __future__ import annotations

from amaranth import Array, Cat, Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .codec import (CONTROL_PAYLOAD, CRC_BYTES, CRC_INIT, CRC_RESIDUE, HEADER_BYTES,
                    MAX_FRAME, MIN_FRAME, MSG_CONTROL, MSG_WRITE, OP_CLEAR_COUNTERS, OP_START,
                    VERSION)
from .config import LinkConfig
from .datapath import crc32_update

__all__ = ["FrameDecoder", "frame_layout", "VERDICTS"]

#: the verdicts a frame's end counts (one of them per frame, after ``framing`` for a COBS
#: error inside a frame)
VERDICTS = ("frames_ok", "crc_errors", "length_errors", "version_errors", "range_errors",
            "framing_errors")


def max_values(lcfg: LinkConfig) -> int:
    """Values a frame's bytes after ``first`` can assemble: one more than the longest write
    holds (the CRC's bytes are assembled too, then discounted)."""
    return (MAX_FRAME - HEADER_BYTES - 2) // lcfg.current_bytes + 1


def frame_layout(lcfg: LinkConfig) -> data.StructLayout:
    """A checked frame: ``write`` (else a control), its ``tick``, ``first`` and ``count``
    values, or its ``op`` and ``arg``."""
    return data.StructLayout({"write": 1, "tick": 32, "first": 16,
                              "count": range(max_values(lcfg) + 1), "op": 8, "arg": 32})


class FrameDecoder(wiring.Component):
    """See the module docstring. ``bytes``: the received bytes; ``frame``: the checked
    frames; ``value_addr``/``value_en``/``value_data``: the value RAM's read port (synchronous:
    ``value_data`` is the word of the previous cycle's address, held while ``value_en`` is
    low).

    For a proof harness: after elaboration the value RAM is the attribute ``values`` (a
    harness adds a read port to watch it); :attr:`RESIDUE` and :meth:`value_slot` are what a
    harness's faulty subclass changes (the proof's mutants)."""

    #: the CRC register's value after an intact frame (its CRC included)
    RESIDUE = CRC_RESIDUE

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        nv = max_values(lcfg)
        members = {
            "bytes": In(stream.Signature(8)),
            "frame": Out(stream.Signature(frame_layout(lcfg))),
            "value_addr": In(range(nv)), "value_en": In(1, init=1),
            "value_data": Out(lcfg.current_width),
            "seq_gap": Out(8),
        }
        members |= {f"count_{v}": Out(1) for v in VERDICTS}
        super().__init__(members)

    def value_slot(self, n):
        """The value RAM word that holds a frame's value ``n``."""
        return n

    def elaborate(self, platform):
        lc = self.lcfg
        N, W = lc.n_written, lc.current_bytes
        m = Module()
        max_vals = max_values(lc)
        m.submodules.vmem = self.values = vmem = Memory(shape=lc.current_width,
                                                        depth=max_vals, init=[])
        vwr, vrd = vmem.write_port(), vmem.read_port()
        m.d.comb += [vrd.addr.eq(self.value_addr), vrd.en.eq(self.value_en),
                     self.value_data.eq(vrd.data)]
        flen = Signal(range(MAX_FRAME + 2))
        remain = Signal(8)
        zero_pending = Signal()
        started = Signal()
        overlong = Signal()
        crc = Signal(32, init=CRC_INIT)
        hdr = Array(Signal(8, name=f"hdr{i}") for i in range(HEADER_BYTES + CONTROL_PAYLOAD))
        acc = Signal(8 * W)
        phase = Signal(range(W))
        nvals = Signal(range(max_vals + 1))
        ver, typ, seq, plen = hdr[0], hdr[1], hdr[2], hdr[3]
        op = hdr[8]
        exp_seq = Signal(8)
        count = Signal(range(max_vals + 1))
        is_write = Signal()
        f = self.frame.payload
        first = Cat(hdr[8], hdr[9])
        m.d.comb += [f.tick.eq(Cat(hdr[4], hdr[5], hdr[6], hdr[7])), f.first.eq(first),
                     f.op.eq(op), f.arg.eq(Cat(hdr[9], hdr[10], hdr[11], hdr[12])),
                     f.count.eq(count), f.write.eq(is_write)]

        emit = Signal()
        ebyte = Signal(8)
        with m.If(emit):
            m.d.sync += crc.eq(crc32_update(crc, ebyte))
            with m.If(flen == MAX_FRAME):
                m.d.sync += overlong.eq(1)
            with m.Else():
                m.d.sync += flen.eq(flen + 1)
            with m.If(flen < len(hdr)):
                m.d.sync += hdr[flen].eq(ebyte)
            with m.If(flen >= HEADER_BYTES + 2):
                new_acc = Cat(acc[8:], ebyte)
                m.d.sync += acc.eq(new_acc)
                with m.If(phase == W - 1):
                    m.d.sync += [phase.eq(0), nvals.eq(nvals + 1)]
                    with m.If(nvals < max_vals):
                        m.d.comb += [vwr.en.eq(1), vwr.addr.eq(self.value_slot(nvals)),
                                     vwr.data.eq(new_acc[:lc.current_width])]
                with m.Else():
                    m.d.sync += phase.eq(phase + 1)

        def frame_reset():
            return [flen.eq(0), remain.eq(0), zero_pending.eq(0), started.eq(0),
                    overlong.eq(0), crc.eq(CRC_INIT), phase.eq(0), nvals.eq(0)]

        # the checks' outcomes, registered in CHECK for DECIDE
        bad_size, bad_crc, bad_version, bad_len = Signal(), Signal(), Signal(), Signal()
        out_of_range, is_control = Signal(), Signal()
        gap = Signal(8)
        b = Mux(self.bytes.valid, self.bytes.payload, 0)

        with m.FSM(name="rx_fsm") as fsm:
            with m.State("RECV"):
                # no undefined byte reaches the decoder while the stream has none
                with m.If(self.bytes.valid):
                    with m.If(b == 0):
                        with m.If(remain != 0):
                            m.d.comb += self.count_framing_errors.eq(1)
                            m.d.sync += frame_reset()
                        with m.Elif(started):
                            m.next = "CHECK"
                    with m.Elif(remain == 0):
                        m.d.comb += [emit.eq(zero_pending), ebyte.eq(0)]
                        m.d.sync += [remain.eq(b - 1), zero_pending.eq(b != 0xFF),
                                     started.eq(1)]
                    with m.Else():
                        m.d.comb += [emit.eq(1), ebyte.eq(b)]
                        m.d.sync += remain.eq(remain - 1)
            with m.State("CHECK"):
                # every check's outcome registered (from registered operands only); DECIDE
                # acts on them in the next cycle, in the order of the checks
                m.d.sync += [
                    bad_size.eq(overlong | (flen < MIN_FRAME)),
                    bad_crc.eq(crc != self.RESIDUE),
                    bad_version.eq(ver != VERSION),
                    bad_len.eq(flen != plen + MIN_FRAME),
                    gap.eq(seq - exp_seq),
                    is_write.eq((typ == MSG_WRITE) & (flen >= MIN_FRAME + 2)
                                & (phase == (CRC_BYTES % W))),
                    # first + values > N, values = nvals - CRC_BYTES // W (the CRC's bytes
                    # were assembled as values too)
                    out_of_range.eq(first + nvals > N + CRC_BYTES // W),
                    count.eq(nvals - (CRC_BYTES // W)),
                    is_control.eq((typ == MSG_CONTROL)
                                  & (flen == MIN_FRAME + CONTROL_PAYLOAD)
                                  & (op >= OP_START) & (op <= OP_CLEAR_COUNTERS)),
                ]
                m.next = "DECIDE"
            with m.State("DECIDE"):
                m.d.sync += frame_reset()
                m.next = "RECV"
                with m.If(bad_size):
                    m.d.comb += self.count_length_errors.eq(1)
                with m.Elif(bad_crc):
                    m.d.comb += self.count_crc_errors.eq(1)
                with m.Elif(bad_version):
                    m.d.comb += self.count_version_errors.eq(1)
                with m.Elif(bad_len):
                    m.d.comb += self.count_length_errors.eq(1)
                with m.Else():
                    m.d.comb += self.seq_gap.eq(gap)
                    m.d.sync += exp_seq.eq(seq + 1)
                    with m.If(is_write & out_of_range):
                        m.d.comb += self.count_range_errors.eq(1)
                    with m.Elif(is_write | is_control):
                        m.d.comb += self.count_frames_ok.eq(1)
                        m.next = "OFFER"
                    with m.Else():
                        m.d.comb += self.count_length_errors.eq(1)
            with m.State("OFFER"):
                # the frame (header registers, values in the RAM) held until taken
                m.d.comb += self.frame.valid.eq(1)
                with m.If(self.frame.ready):
                    m.next = "RECV"
        # a continuous assignment (not a process of the FSM): simulators that start
        # combinational processes only on an input change see it from time 0
        m.d.comb += self.bytes.ready.eq(fsm.ongoing("RECV"))
        return m
