"""The host link's frame decoder against the wire format's specification, for every byte
stream of every length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The harness takes the link's two receiving components as they are, through their ports:
:class:`~cuneate.hdl.link.decoder.FrameDecoder`, its byte stream driven by a free source (any
byte offered in any cycle: every stream a line and the receive buffers can deliver), and
:class:`~cuneate.hdl.link.executor.FrameExecutor` behind it, its tick generator's state, the
payload's ``busy`` and its write stream's ``ready`` free (any back-pressure). Beside them runs a
reference
decoder written from :mod:`cuneate.hdl.link.codec`'s description of a frame, byte by byte:
COBS blocks (a code byte ``c`` announces ``c - 1`` data bytes and, unless ``c`` is 255, a zero
after them; a zero byte ends the frame), the CRC-32 over the decoded bytes
(:func:`~cuneate.hdl.link.datapath.crc32_update`, checked against ``zlib.crc32`` by the codec
tests), the header fields by position, the values by position (``first`` at bytes 8-9, value
``k`` at bytes ``10 + W k ..``), and the checks in the documented order.

**What is proven.**

* *Every frame gets the verdict the specification gives it*: at each frame end the decoder
  counts exactly the counter the reference's checks name (length, CRC, version, length field,
  then sequence gap, range, layout), a zero inside a COBS block is a framing error, and a
  frame is accepted (``frames_ok``) only if its decoded bytes carry the CRC-32 residue, the
  version and a consistent length: **no corrupted frame the CRC detects is accepted**.
* *No accepted write is lost or reordered*: after an accepted ``WRITE`` frame of ``n`` values
  the payload takes exactly ``n`` writes, to ``first, first + 1, ...`` in that order, the
  tracked value ``k`` (a free constant, so every ``k``) with the frame's value ``k``, the last
  marked as the burst's end, no write at any other time, and the decoder takes no further
  byte until the last write is taken (or the frame is counted as a late write, before any of
  its writes).

**Why the induction step closes** - the invariants: while the decoder receives, its COBS state
(bytes left in the block, the pending zero, frame started), length, overlong flag, CRC
register, value assembly (shift register, byte phase, value count), the header bytes received
so far and the tracked value in the value RAM equal the reference's; once a frame has ended and
until the next byte, the decoder's frame state is the reset state, and its header, value count
and the tracked value equal the reference's frame; the executor works only on a frame the
decoder offers, and while it writes, its value index equals the reference's count of writes
taken plus the one on offer; the expected sequence number equals the reference's. The
remaining registers (the decision of the frame end cycles) are a function of the last few
cycles. The decoder's and the executor's registers are read by name from their elaborated
modules (:func:`~cuneate.hdl.lib.formal.signal_named`): observed, not changed.

**Mutants** are subclasses of the decoder through its documented hooks (the CRC residue it
checks against, the value RAM word a value goes to), or a harness wiring (the executor's
reads one value ahead).

**Abstractions.** None in the decoder or the executor: their inputs are free (a superset of
what the link's UART, receive buffers, tick generator and payload give them), the value RAM
starts with any contents.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from amaranth import Cat, ClockDomain, Const, Elaboratable, Module, Mux, Signal
from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import Fragment

from ..flow.sby import SOLVER
from ..lib.formal import (ProofResult, assert_all, assume_all, harness_depth, harness_rtlil,
                          prove_harness, signal_named)
from .codec import (CONTROL_PAYLOAD, CRC_INIT, CRC_RESIDUE, HEADER_BYTES, MAX_FRAME,
                    MIN_FRAME, MSG_CONTROL, MSG_WRITE, OP_CLEAR_COUNTERS, OP_START, VERSION)
from .config import LinkConfig, link_config
from .datapath import crc32_update
from .decoder import FrameDecoder, max_values
from .executor import FrameExecutor

__all__ = ["DecoderProof", "decoder_harness", "prove_decoder", "decoder_proof_config",
           "induction_depth", "MUTANTS", "ABSTRACTIONS", "VERDICTS"]

#: faults the harness builds into its copies of the components (never into the product): the
#: CRC check against a residue one bit off (a corrupted frame accepted); each value stored in
#: its neighbour's word (two values swapped); the writes reading one value ahead (the first
#: lost, the rest shifted)
MUTANTS = ("wrong_residue", "values_swapped", "value_read_ahead")

ABSTRACTIONS = ["the decoder's byte stream free (any byte offered in any cycle)",
                "the executor's tick-generator state, the payload's busy and its write "
                "stream's ready free", "value RAM with free initial contents"]

#: the counters a frame's verdict increments
VERDICTS = ("frames_ok", "crc_errors", "length_errors", "version_errors", "range_errors")


class _WrongResidue(FrameDecoder):
    RESIDUE = CRC_RESIDUE ^ 1


class _ValuesSwapped(FrameDecoder):
    def value_slot(self, n):
        return n ^ 1


DECODERS = {"wrong_residue": _WrongResidue, "values_swapped": _ValuesSwapped}


def _watched(decoder: type) -> type:
    """``decoder`` with a combinational read port of its value RAM for the harness
    (``watch``), added through the RAM it documents (``values``)."""
    class Watched(decoder):
        def elaborate(self, platform):
            m = super().elaborate(platform)
            self.watch = self.values.read_port(domain="comb")
            return m
    return Watched


def _state_flags(m, fsm: Signal, names, prefix: str) -> dict:
    """``{state: flag}``: the FSM register ``fsm`` (its decoder names the states) is in it."""
    enc = {}
    for i in range(2 ** len(fsm)):
        try:
            label = str(fsm.decoder(i))
        except (KeyError, IndexError):             # not a state's encoding
            continue
        if "/" in label:
            enc[label.split("/")[0]] = i
    flags = {n: Signal(name=f"{prefix}_{n}") for n in names}
    m.d.comb += [f.eq(fsm == enc[n]) if n in enc else f.eq(0) for n, f in flags.items()]
    return flags


class DecoderProof(Elaboratable):
    """Harness of the link's frame decoder and executor (see the module docstring)."""

    def __init__(self, lcfg: LinkConfig, mutant: str | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.lcfg, self.mutant = lcfg, mutant
        self.latency = None                    # the decision latency, read when elaborated
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]

    @property
    def induction_depth(self) -> int:
        """The decision latency + 5: the executor's output register and the value RAM's
        pipeline."""
        return self.latency + 5

    def elaborate(self, platform):
        lc, m = self.lcfg, Module()
        m.domains.sync = self.cd
        N, W, I = lc.n_written, lc.current_bytes, lc.current_width
        max_vals = max_values(lc)
        dec = _watched(DECODERS.get(self.mutant, FrameDecoder))(lc)
        exe = FrameExecutor(lc)
        dfrag, efrag = Fragment.get(dec, platform), Fragment.get(exe, platform)
        kt = Signal(range(max_vals), name="tracked_value")
        m.d.comb += kt.eq(AnyConst(len(kt)))
        assume_all(m, [kt < max_vals])
        vport = dec.watch
        m.d.comb += vport.addr.eq(kt)
        m.submodules.decoder, m.submodules.executor = dfrag, efrag
        # the link's wiring between the two, the rest of their inputs free
        ahead = 1 if self.mutant == "value_read_ahead" else 0
        w = exe.write
        m.d.comb += [
            dec.bytes.valid.eq(AnySeq(1)), dec.bytes.payload.eq(AnySeq(8)),
            exe.frame.valid.eq(dec.frame.valid), exe.frame.payload.eq(dec.frame.payload),
            dec.frame.ready.eq(exe.frame.ready),
            dec.value_addr.eq(exe.value_addr + ahead), dec.value_en.eq(exe.value_en),
            exe.value_data.eq(dec.value_data),
            exe.sweeps_started.eq(AnySeq(32)), exe.pending.eq(AnySeq(1)),
            exe.busy.eq(AnySeq(1)), w.ready.eq(AnySeq(1)),
        ]
        reg = {name: signal_named(dfrag, name) for name in
               ("remain", "zero_pending", "started", "flen", "overlong", "crc", "acc", "phase",
                "nvals", "count", "exp_seq", "rx_fsm_state")}
        hdr = [signal_named(dfrag, f"hdr{i}") for i in range(HEADER_BYTES + CONTROL_PAYLOAD)]
        widx = signal_named(efrag, "widx")
        st = _state_flags(m, reg["rx_fsm_state"], ("RECV", "CHECK", "DECIDE", "OFFER"), "dec")
        ex = _state_flags(m, signal_named(efrag, "exec_fsm_state"),
                          ("IDLE", "WAIT", "WRITE", "DRAIN"), "exe")
        h = SimpleNamespace(N=N, W=W, I=I, max_vals=max_vals, dec=dec, exe=exe, w=w, kt=kt,
                            vport=vport, reg=reg, hdr=hdr, widx=widx, st=st, ex=ex)
        r = self._reference(m, h)
        v = self._verdicts(m, h, r)
        o = self._writes(m, h, r, v)
        self._invariants(m, h, r, v, o)
        return m

    def _reference(self, m, h):
        """The reference decoder, byte by byte: its state and the frame it ends."""
        W, kt, dec = h.W, h.kt, h.dec
        hdr = h.hdr
        # --- the reference decoder, byte by byte ----------------------------------------------
        take = Signal(name="ref_take")
        b = Signal(8, name="ref_byte")
        m.d.comb += [take.eq(dec.bytes.valid & dec.bytes.ready), b.eq(dec.bytes.payload)]
        left = Signal(8, name="ref_left")              # data bytes left in the COBS block
        zero = Signal(name="ref_zero")                 # the block ends with a zero
        framing = Signal(name="ref_framing")           # a frame's first byte came
        ended = Signal(name="ref_ended")               # the frame ended; its state is kept
        #                                                until the next byte
        flen = Signal(range(MAX_FRAME + 1), name="ref_len")
        over = Signal(name="ref_overlong")
        crc = Signal(32, init=CRC_INIT, name="ref_crc")
        rhdr = [Signal(8, name=f"ref_hdr{i}") for i in range(len(hdr))]
        last = Signal(8 * W, name="ref_last")          # the last W bytes of the values
        val = Signal(8 * W, name="ref_value")          # the tracked value's bytes
        # the state the next byte starts from (an ended frame's: reset)
        z_left, z_zero, z_framing = (Mux(ended, 0, x) for x in (left, zero, framing))
        z_len, z_over = Mux(ended, 0, flen), Mux(ended, 0, over)
        z_crc = Mux(ended, CRC_INIT, crc)
        emit = Signal(name="ref_emit")
        ebyte = Signal(8, name="ref_ebyte")
        delim = Signal(name="ref_delimiter")
        cobs_err = Signal(name="ref_cobs_error")
        m.d.comb += [delim.eq(take & (b == 0) & (z_left == 0) & z_framing),
                     cobs_err.eq(take & (b == 0) & (z_left != 0))]
        with m.If(take):
            m.d.sync += [ended.eq(0), left.eq(z_left), zero.eq(z_zero), framing.eq(z_framing),
                         flen.eq(z_len), over.eq(z_over), crc.eq(z_crc)]
            with m.If(b == 0):
                with m.If(z_left != 0):
                    m.d.sync += [left.eq(0), zero.eq(0), framing.eq(0), flen.eq(0),
                                 over.eq(0), crc.eq(CRC_INIT)]
                with m.Elif(z_framing):
                    m.d.sync += ended.eq(1)
            with m.Elif(z_left == 0):
                m.d.comb += [emit.eq(z_zero), ebyte.eq(0)]
                m.d.sync += [left.eq(b - 1), zero.eq(b != 0xFF), framing.eq(1)]
            with m.Else():
                m.d.comb += [emit.eq(1), ebyte.eq(b)]
                m.d.sync += left.eq(z_left - 1)
        with m.If(emit):
            m.d.sync += crc.eq(crc32_update(z_crc, ebyte))
            with m.If(z_len == MAX_FRAME):
                m.d.sync += over.eq(1)
            with m.Else():
                m.d.sync += flen.eq(z_len + 1)
            for i, h in enumerate(rhdr):
                with m.If(z_len == i):
                    m.d.sync += h.eq(ebyte)
            with m.If(z_len >= HEADER_BYTES + 2):
                m.d.sync += last.eq(Cat(last[8:], ebyte))
            # the tracked value, whole, when its last byte comes (its first bytes are in last)
            with m.If(~z_over & (z_len == HEADER_BYTES + 2 + W * kt + W - 1)):
                m.d.sync += val.eq(Cat(last[8:], ebyte))
        return SimpleNamespace(take=take, b=b, left=left, zero=zero, framing=framing, ended=ended,
                               flen=flen, over=over, crc=crc, rhdr=rhdr, last=last, val=val, delim=delim,
                               cobs_err=cobs_err)

    def _verdicts(self, m, h, r):
        """The verdict the decoder counts, from the reference's fields."""
        N, W, max_vals, dec, st = h.N, h.W, h.max_vals, h.dec, h.st
        flen, over, crc = r.flen, r.over, r.crc
        rhdr, delim, cobs_err = r.rhdr, r.delim, r.cobs_err
        # the verdict at a frame's end, from the reference's own fields, in the documented
        # order: size, CRC, version, length field; then the type's layout and range
        seq, plen, op = rhdr[2], rhdr[3], rhdr[8]
        first = Cat(rhdr[8], rhdr[9])
        body = Signal(range(MAX_FRAME + 1), name="ref_value_bytes")
        m.d.comb += body.eq(flen - (MIN_FRAME + 2))
        n_vals = Signal(range(max_vals + 1), name="ref_n_values")
        m.d.comb += n_vals.eq(body // W)
        bad_len = over | (flen < MIN_FRAME)
        bad_crc = crc != CRC_RESIDUE
        bad_ver = rhdr[0] != VERSION
        bad_plen = flen != plen + MIN_FRAME
        good = Signal(name="ref_good")
        m.d.comb += good.eq(~bad_len & ~bad_crc & ~bad_ver & ~bad_plen)
        write = good & (rhdr[1] == MSG_WRITE) & (flen >= MIN_FRAME + 2) & (body % W == 0)
        control = good & ~write & (rhdr[1] == MSG_CONTROL) & \
            (flen == MIN_FRAME + CONTROL_PAYLOAD) & (op >= OP_START) & (op <= OP_CLEAR_COUNTERS)
        in_range = first + n_vals <= N
        v = {"length_errors": bad_len | (~bad_crc & ~bad_ver & bad_plen)
             | (good & ~write & ~control),
             "crc_errors": ~bad_len & bad_crc,
             "version_errors": ~bad_len & ~bad_crc & bad_ver,
             "range_errors": write & ~in_range,
             "frames_ok": (write & in_range) | control}
        exp_seq = Signal(8, name="ref_exp_seq")
        gap = Signal(8, name="ref_gap")
        m.d.comb += gap.eq(Mux(delim & good, seq - exp_seq, 0))
        with m.If(delim & good):
            m.d.sync += exp_seq.eq(seq + 1)

        # the decoder counts the verdict its decision latency after the delimiter
        lat = self.latency = 2 if "DECIDE" in st else 1
        cur = {k: delim & x for k, x in v.items()} | {"seq_gaps": gap}
        for step in range(lat):
            nxt = {}
            for k, x in cur.items():
                r = Signal(8 if k == "seq_gaps" else 1, name=f"ref_{k}_d{step + 1}")
                m.d.sync += r.eq(x)
                nxt[k] = r
            cur = nxt
        counted = {k: getattr(dec, f"count_{k}") for k in VERDICTS} | {"seq_gaps": dec.seq_gap}
        checks = [(counted[k] == cur[k], f"verdict: {k}") for k in (*VERDICTS, "seq_gaps")]
        checks += [(dec.count_framing_errors == cobs_err, "verdict: framing_errors")]
        assert_all(m, checks)
        return SimpleNamespace(n_vals=n_vals, first=first, write=write, exp_seq=exp_seq, ok=v)

    def _writes(self, m, h, r, v):
        """The writes the payload takes: an accepted frame's, in order, none lost."""
        W, I, max_vals, kt = h.W, h.I, h.max_vals, h.kt
        exe, w = h.exe, h.w
        take = r.take
        val, delim = r.val, r.delim
        n_vals, first, write = v.n_vals, v.first, v.write
        # --- the writes -------------------------------------------------------------------------
        owed = Signal(name="ref_owed")                   # writes of an accepted frame to come
        wfirst = Signal(16, name="ref_write_first")
        wcount = Signal(range(max_vals + 1), name="ref_write_count")
        wval = Signal(8 * W, name="ref_write_value")
        done = Signal(range(max_vals + 1), name="ref_writes_seen")
        late = exe.count_late_writes
        wr = w.valid & w.ready                           # a write the payload takes
        with m.If(delim & v.ok["frames_ok"] & write):
            m.d.sync += [owed.eq(n_vals != 0), wfirst.eq(first), wcount.eq(n_vals),
                         done.eq(0), wval.eq(val)]
        with m.If(wr):
            m.d.sync += done.eq(done + 1)
            with m.If(done + 1 == wcount):
                m.d.sync += owed.eq(0)
        with m.If(late):
            m.d.sync += owed.eq(0)
        checks = [(~wr | owed, "writes: only an accepted frame's"),
                  (~wr | (w.payload.addr == wfirst + done), "writes: in order, none lost"),
                  (~wr | (done != kt) | (w.payload.value.as_unsigned() == wval[:I]),
                   "writes: the tracked value"),
                  (~wr | (w.payload.last == (done + 1 == wcount)), "writes: the burst's end"),
                  (~late | (done == 0) & (owed | (wcount == 0)),
                   "late write: before any write"),
                  (~take | ~owed, "no byte taken while writes are owed")]
        assert_all(m, checks)
        return SimpleNamespace(owed=owed, wfirst=wfirst, wcount=wcount, wval=wval, done=done)

    def _invariants(self, m, h, r, v, o):
        """The invariants that make the properties inductive."""
        N, W, I, kt, max_vals = h.N, h.W, h.I, h.kt, h.max_vals
        dec, w, vport = h.dec, h.w, h.vport
        reg, hdr, widx, st, ex = h.reg, h.hdr, h.widx, h.st, h.ex
        ended, flen, over, crc = r.ended, r.flen, r.over, r.crc
        rhdr, last, val = r.rhdr, r.last, r.val
        left, zero, framing = r.left, r.zero, r.framing
        exp_seq = v.exp_seq
        owed, wfirst, wcount, wval, done = o.owed, o.wfirst, o.wcount, o.wval, o.done
        # --- invariants -----------------------------------------------------------------------
        holding = (st["RECV"] & ~ended) | st["CHECK"] | st["DECIDE"]
        reset = (st["RECV"] & ended) | st["OFFER"]
        working = ex["WAIT"] | ex["WRITE"] | ex["DRAIN"]
        offered_write = st["OFFER"] & dec.frame.payload.write
        assembling = holding & ~over & (flen >= HEADER_BYTES + 2)
        pos = flen - (HEADER_BYTES + 2)
        checks = [
            (st["RECV"] | st["CHECK"] | st["DECIDE"] | st["OFFER"], "state: a decoder state"),
            (ex["IDLE"] | working, "state: an executor state"),
            (~working | offered_write, "state: the executor works on the offered write"),
            (flen <= MAX_FRAME, "reference: length in range"),
            (wcount < max_vals, "reference: a frame's values fit a frame"),
            (framing | (flen == 0) & ~over & (crc == CRC_INIT) & (left == 0) & ~zero,
             "reference: nothing before a frame's first byte"),
            (~holding | (reg["remain"] == left), "state: block bytes left"),
            (~holding | (reg["zero_pending"] == zero), "state: pending zero"),
            (~holding | (reg["started"] == framing), "state: frame started"),
            (~holding | (reg["flen"] == flen), "state: length"),
            (~holding | (reg["overlong"] == over), "state: overlong"),
            (~holding | (reg["crc"] == crc), "state: crc"),
            (~holding | over | (reg["phase"] == Mux(flen >= HEADER_BYTES + 2, pos % W, 0)),
             "state: value byte phase"),
            (~holding | over | (reg["nvals"] == Mux(flen >= HEADER_BYTES + 2, pos // W, 0)),
             "state: values assembled"),
            # the bytes of the value being assembled (the top ones: bytes enter at the top)
            (~assembling | _same_top_bytes(reg["acc"], last, pos % W, W), "state: value bytes"),
            (~reset | ((reg["remain"] == 0) & ~reg["zero_pending"] & ~reg["started"]
                       & (reg["flen"] == 0) & ~reg["overlong"] & (reg["crc"] == CRC_INIT)
                       & (reg["phase"] == 0) & (reg["nvals"] == 0)),
             "state: reset after a frame"),
            (st["CHECK"] | st["DECIDE"] | (reg["exp_seq"] == exp_seq),
             "state: expected sequence number"),
            (~st["RECV"] | ~owed, "state: no writes owed while receiving"),
            (~(st["CHECK"] | st["DECIDE"] | st["OFFER"]) | ended & framing & (left == 0),
             "state: past an ended frame"),
            (~(st["CHECK"] | st["DECIDE"]) | ex["IDLE"] & ~w.valid,
             "state: the executor idle while a frame is decided"),
            (~ex["IDLE"] | ~w.valid, "state: nothing on offer while idle"),
            (~w.valid | (w.payload.addr == wfirst + done)
             & (w.payload.last == (done + 1 == wcount))
             & ((done != kt) | (w.payload.value.as_unsigned() == wval[:I])),
             "state: the write on offer"),
            # the value RAM's read register holds the value the next load takes
            (~ex["WRITE"] | (widx != kt + 1) | (dec.value_data == wval[:I]),
             "state: the tracked value read"),
            (~(st["OFFER"] & ex["IDLE"]) | Mux(dec.frame.payload.write,
                                               (done == 0) & (owed == (wcount != 0))
                                               & (reg["count"] == wcount),
                                               ~owed),
             "state: a frame offered"),
            (~ex["WAIT"] | (reg["count"] == wcount) & (done == 0) & (owed == (wcount != 0))
             & ~w.valid & (widx == 0), "state: waiting to write"),
            (~ex["WRITE"] | (reg["count"] == wcount) & owed
             & (widx == done + 1 + w.valid) & (widx <= wcount) & (widx != 0),
             "state: writing"),
            (~ex["DRAIN"] | (reg["count"] == wcount) & owed & w.valid
             & (done + 1 == wcount) & (widx == wcount + 1), "state: the last write on offer"),
            (~offered_write | (Cat(hdr[8], hdr[9]) == wfirst), "state: first"),
            (~(offered_write | owed) | (wfirst + wcount <= N),
             "state: an accepted frame's writes in range"),
        ]
        checks += [(~(flen > i) | (h == rh), f"state: header byte {i}")
                   for i, (h, rh) in enumerate(zip(hdr, rhdr))]
        stored = holding & ~over & (HEADER_BYTES + 2 + W * (kt + 1) <= flen)
        checks += [(~stored | (vport.data == val[:I]), "state: tracked value assembled"),
                   (~offered_write | (kt >= wcount) | (vport.data == wval[:I]),
                    "state: tracked value to write")]
        assert_all(m, checks)


def _same_top_bytes(a, b, n, width: int):
    """``a`` and ``b`` (``width`` bytes each) agree in their top ``n`` bytes."""
    out = Const(1, 1)
    for p in range(1, width):
        out = out & ((n != p) | (a[8 * (width - p):] == b[8 * (width - p):]))
    return out


def decoder_proof_config(n_neurons: int = 8, **kwargs) -> LinkConfig:
    """A small link for the decoder proof: ``n_neurons`` (default 8), ``kwargs`` to
    :func:`~cuneate.hdl.link.config.link_config`."""
    kw = dict(rx_fifo_depth=4, tx_fifo_depth=4, batch_capacity=2)
    kw.update(kwargs)
    return link_config(dict(n_neurons=n_neurons, clock_hz=n_neurons * 16e3 * 4), **kw)


#: memories of the harness that start with any contents
MEMORIES = ("vmem",)


def decoder_harness(lcfg: LinkConfig, mutant: str | None = None) -> str:
    """RTLIL of the harness (top ``decoder_eq``), the memories' initial contents removed."""
    return harness_rtlil(DecoderProof(lcfg, mutant), "decoder_eq", MEMORIES)


def induction_depth(lcfg: LinkConfig) -> int:
    """The k of the k-induction: the decoder's decision latency (cycles from the delimiter to
    the verdict, read from its states) + 5 (the executor's output register and the value
    RAM's pipeline)."""
    return harness_depth(DecoderProof(lcfg), "decoder_eq", MEMORIES)


def prove_decoder(lcfg: LinkConfig, workdir: Path, mode: str = "prove",
                  depth: int | None = None, mutant: str | None = None,
                  timeout_s: float = 3600, engine: str = "smtbmc",
                  solver: str = SOLVER) -> ProofResult:
    """Prove (``mode="prove"``, k-induction of ``depth`` steps, default
    :func:`induction_depth`) or check to a bound (``mode="bmc"``) that the link's frame
    decoder gives every frame its specified verdict and its executor loses or reorders no
    accepted write."""
    return prove_harness("link frame decoder meets the wire format", DecoderProof(lcfg, mutant),
                         "decoder_eq", MEMORIES, workdir, mode, depth, timeout_s, engine,
                         ABSTRACTIONS, solver)
