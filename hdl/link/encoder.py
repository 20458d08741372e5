"""The link's frame encoder: batches and counter readings in, COBS-encoded frames out as a
byte stream (:class:`FrameEncoder`).

A frame (the header, then a batch's spikes or the counters, then the CRC-32) is built into a
byte RAM, then COBS-encoded by scanning it, one byte on ``bytes`` every two cycles at most.
A batch on offer goes first, a counters request (``read_counters``) after it; the batch is
taken (``batch.ready``) when its frame's delimiter is out. The RAMs' outputs are registered
before anything decides on them (a read takes two cycles; the encoder six cycles a byte
against a UART's ten bits).
"""

from __future__ import annotations

from amaranth import Cat, Const, Module, Mux, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..lib.fsm import wait_states
from .batcher import batch_layout
from .codec import (COUNTER_NAMES, CRC_BYTES, CRC_INIT, HEADER_BYTES, MAX_FRAME, MSG_COUNTERS,
                    MSG_SPIKES, SPIKE_HEADER, VERSION)
from .config import LinkConfig
from .datapath import crc32_update

__all__ = ["FrameEncoder"]


def _pick(options, index):
    """``options[index]`` as a chain of multiplexers (``index`` beyond the list: the last)."""
    out = options[-1]
    for i in range(len(options) - 2, -1, -1):
        out = Mux(index == i, options[i], out)
    return out


class FrameEncoder(wiring.Component):
    """See the module docstring. ``counters``: every counter of
    :data:`~cuneate.hdl.link.codec.COUNTER_NAMES` as 32 bits, the first lowest;
    ``sweeps_started``: the counters frame's tick; ``spike_addr``/``spike_data``: the
    batcher's spike buffer."""

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        super().__init__({
            "batch": In(stream.Signature(batch_layout(lcfg))),
            "spike_addr": Out(range(lcfg.batch_capacity)), "spike_data": In(24),
            "read_counters": In(1), "counters": In(32 * len(COUNTER_NAMES)),
            "sweeps_started": In(32),
            "bytes": Out(stream.Signature(8)),
        })

    def elaborate(self, platform):
        lc = self.lcfg
        CAP = lc.batch_capacity
        m = Module()
        m.submodules.tmem = tmem = Memory(shape=8, depth=MAX_FRAME, init=[])
        twr, trd = tmem.write_port(), tmem.read_port()
        tdat = Signal(8)
        m.d.sync += tdat.eq(trd.data)
        sdat = Signal(24)
        m.d.sync += sdat.eq(self.spike_data)
        counters_req = Signal()
        with m.If(self.read_counters):
            m.d.sync += counters_req.eq(1)
        tx_seq = Signal(8)
        kind_spikes = Signal()
        j = Signal(range(MAX_FRAME + 1))                  # bytes built
        k = Signal(range(CAP + 1))                        # spike index
        tcrc = Signal(32)
        cb = Signal(range(CRC_BYTES))                     # CRC byte being written
        L = Signal(range(MAX_FRAME + 1))
        start = Signal(range(MAX_FRAME + 1))
        code = Signal(8)
        p = Signal(range(MAX_FRAME + 1))
        q = Signal(range(MAX_FRAME + 1))
        zero_end = Signal()
        put = Signal()
        pbyte = Signal(8)
        # the byte chosen in one cycle is written and added to the CRC in the next (a
        # register stage between the byte multiplexers and the CRC tree)
        put_r, pbyte_r, jw = Signal(), Signal(8), Signal(range(MAX_FRAME + 1))
        m.d.sync += [put_r.eq(put), pbyte_r.eq(pbyte), jw.eq(j)]
        with m.If(put):
            m.d.sync += j.eq(j + 1)
        with m.If(put_r):
            m.d.sync += tcrc.eq(crc32_update(tcrc, pbyte_r))
        bp = self.batch.payload
        cur_tick = Mux(kind_spikes, bp.tick, self.sweeps_started)
        # payload bytes: the spike header and three bytes per spike, or the counters
        tx_len = Mux(kind_spikes, SPIKE_HEADER + (bp.count << 1) + bp.count,
                     4 * len(COUNTER_NAMES))
        head = [Const(VERSION, 8), Mux(kind_spikes, MSG_SPIKES, MSG_COUNTERS), tx_seq,
                tx_len[0:8], cur_tick[0:8], cur_tick[8:16], cur_tick[16:24], cur_tick[24:32]]
        head_spk = [bp.drop[0:8], bp.drop[8:16], bp.sweeps]
        hi = Signal(range(4 * len(COUNTER_NAMES)))       # byte index after the header
        m.d.comb += self.spike_addr.eq(k)
        out = self.bytes

        with m.FSM(name="tx_fsm") as fsm:
            with m.State("IDLE"):
                m.d.sync += [j.eq(0), k.eq(0), tcrc.eq(CRC_INIT), hi.eq(0), cb.eq(0)]
                with m.If(self.batch.valid):
                    m.d.sync += kind_spikes.eq(1)
                    m.next = "HEAD"
                with m.Elif(counters_req):
                    m.d.sync += [kind_spikes.eq(0), counters_req.eq(0)]
                    m.next = "HEAD"
            with m.State("HEAD"):
                m.d.comb += [put.eq(1), pbyte.eq(_pick(head, j))]
                with m.If(j == HEADER_BYTES - 1):
                    m.next = "HEAD2"
            with m.State("HEAD2"):
                m.d.sync += hi.eq(hi + 1)
                with m.If(kind_spikes):
                    m.d.comb += [put.eq(1), pbyte.eq(_pick(head_spk, hi))]
                    with m.If(j == HEADER_BYTES + SPIKE_HEADER - 1):
                        m.next = "SPK_READ"
                with m.Else():
                    m.d.comb += [put.eq(1), pbyte.eq(self.counters.word_select(hi, 8))]
                    with m.If(j == HEADER_BYTES + 4 * len(COUNTER_NAMES) - 1):
                        m.next = "CRC_WAIT"
            with m.State("SPK_READ"):
                with m.If(k == bp.count):
                    m.next = "CRC_WAIT"
                with m.Else():
                    m.next = "SPK_WAIT"
            with m.State("SPK_WAIT"):
                m.next = "SPK0"
            for n_, (lo, nxt) in enumerate([(0, "SPK1"), (8, "SPK2"), (16, "SPK_NEXT")]):
                with m.State(f"SPK{n_}"):
                    m.d.comb += [put.eq(1), pbyte.eq(sdat[lo:lo + 8])]
                    m.next = nxt
            with m.State("SPK_NEXT"):
                m.d.sync += k.eq(k + 1)
                m.next = "SPK_READ"
            with m.State("CRC_WAIT"):
                m.next = "CRC"
            with m.State("CRC"):
                # the CRC's bytes, inverted (final xor), least significant first
                m.d.sync += [j.eq(j + 1), cb.eq(cb + 1)]
                with m.If(cb == CRC_BYTES - 1):
                    m.d.sync += [L.eq(j + 1), start.eq(0), p.eq(0), code.eq(1)]
                    m.next = "SCAN"
            # COBS encoder: find the block [start, p), emit p - start + 1, then the block
            # (code = p - start + 1 kept as p advances: no subtractor before the decisions)
            wait_states(m, "SCAN", "SCAN_RD", "SCAN_CHK")
            with m.State("SCAN_CHK"):
                with m.If((p < L) & (tdat != 0) & (code != 255)):
                    m.d.sync += [p.eq(p + 1), code.eq(code + 1)]
                    m.next = "SCAN"
                with m.Else():
                    m.d.sync += [zero_end.eq((p < L) & (tdat == 0) & (code != 255)),
                                 q.eq(start)]
                    m.next = "CODE"
            with m.State("CODE"):
                m.d.comb += [out.valid.eq(1), out.payload.eq(code)]
                with m.If(out.ready):
                    m.next = "EMIT_RD"
            with m.State("EMIT_RD"):
                with m.If(q == p):
                    with m.If(zero_end):
                        m.d.sync += [start.eq(p + 1), p.eq(p + 1), code.eq(1)]
                        m.next = "SCAN"
                    with m.Elif(p < L):
                        m.d.sync += [start.eq(p), code.eq(1)]
                        m.next = "SCAN"
                    with m.Else():
                        m.next = "DELIM"
                with m.Else():
                    m.next = "EMIT_WAIT"
            with m.State("EMIT_WAIT"):
                m.next = "EMIT"
            with m.State("EMIT"):
                m.d.comb += [out.valid.eq(1), out.payload.eq(tdat)]
                with m.If(out.ready):
                    m.d.sync += q.eq(q + 1)
                    m.next = "EMIT_RD"
            with m.State("DELIM"):
                m.d.comb += [out.valid.eq(1), out.payload.eq(0)]
                with m.If(out.ready):
                    m.d.sync += tx_seq.eq(tx_seq + 1)
                    m.d.comb += self.batch.ready.eq(kind_spikes)
                    m.next = "IDLE"
        # frame RAM ports as continuous assignments (see the decoder's bytes.ready)
        crc_st = fsm.ongoing("CRC")
        m.d.comb += [
            twr.en.eq(put_r | crc_st), twr.addr.eq(Mux(crc_st, j, jw)),
            twr.data.eq(Mux(crc_st, ~tcrc.word_select(cb, 8), pbyte_r)),
            trd.addr.eq(Mux(fsm.ongoing("EMIT_RD") | fsm.ongoing("EMIT_WAIT")
                            | fsm.ongoing("EMIT"), q, p)),
        ]
        return m
