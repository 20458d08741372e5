"""The host link's frame decoder against the wire format's specification, for every byte
stream of every length (k-induction) or of a bounded length (BMC), with SymbiYosys.

The harness builds :class:`~cuneate.hdl.link.core.HostLink` with its UART receiver and its
receive FIFO's head replaced by free sources (any byte ready in any cycle, any framing error:
every stream a line and the receive buffers can deliver) and watches the bytes the decoder
takes. Beside it runs a reference
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
  the core's write port sees exactly ``n`` writes, to ``first, first + 1, ...`` in that order,
  the tracked value ``k`` (a free constant, so every ``k``) with the frame's value ``k``, no
  write at any other time, and the decoder takes no further byte until the last write is out
  (or the frame is counted as a late write, before any of its writes).

**Why the induction step closes** - the invariants: while the decoder receives, its COBS state
(bytes left in the block, the pending zero, frame started), length, overlong flag, CRC
register, value assembly (shift register, byte phase, value count), the header bytes received
so far and the tracked value in the value RAM equal the reference's; once a frame has ended and
until the next byte, the decoder's frame state is the reset state, and its header, value count
and the tracked value equal the reference's frame; during the writes the write index equals
the reference's count of writes seen; the expected sequence number equals the reference's. The
remaining registers (the decision of the frame end cycles, the write port's pipeline) are a
function of the last few cycles.

**Abstractions.** None in the decoder: the UART receiver and the receive FIFO's head are
replaced by free sources (a superset of what they deliver: the FIFOs are amaranth's library
FIFOs, their overflow counted by the link), the memories start with any contents, the core's
side (busy, spikes) and the tick generator run freely.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from amaranth import Cat, ClockDomain, Const, Elaboratable, Module, Mux, Signal
from amaranth.hdl import Fragment
from amaranth.hdl._ast import AnyConst, AnySeq

from ..flow.sby import SOLVER
from ..lib.formal import (ProofResult, assert_all, assume_all, harness_rtlil, patched,
                          run_proof, signal_named)
from . import core as core_module
from .codec import (CONTROL_PAYLOAD, CRC_INIT, CRC_RESIDUE, HEADER_BYTES, MAX_FRAME,
                    MIN_FRAME, MSG_CONTROL, MSG_WRITE, OP_CLEAR_COUNTERS, OP_START, VERSION)
from .config import LinkConfig, link_config
from .core import HostLink
from .datapath import crc32_update

__all__ = ["DecoderProof", "decoder_harness", "prove_decoder", "decoder_proof_config",
           "induction_depth",
           "MUTANTS", "ABSTRACTIONS", "VERDICTS"]

#: faults the harness can build into its copy of the link (never into the product): the CRC
#: check against a residue one bit off (a corrupted frame accepted); each value stored in its
#: neighbour's word (two values swapped); the writes reading one value ahead (the first lost,
#: the rest shifted)
MUTANTS = ("wrong_residue", "values_swapped", "value_read_ahead")

ABSTRACTIONS = ["UART receiver and receive FIFO head replaced by free byte sources (any "
                "byte, any framing error, any cycle)", "memories with free initial contents",
                "core side and tick generator free"]

#: the counters a frame's verdict increments
VERDICTS = ("frames_ok", "crc_errors", "length_errors", "version_errors", "range_errors")


class _FreeUart(Elaboratable):
    """A UART receiver that delivers any byte with any framing error in any cycle."""

    def __init__(self, clocks_per_bit):
        self.rx = Signal(init=1)
        self.valid, self.data, self.frame_error = Signal(), Signal(8), Signal()

    def elaborate(self, platform):
        m = Module()
        m.d.comb += [self.valid.eq(AnySeq(1)), self.data.eq(AnySeq(8)),
                     self.frame_error.eq(AnySeq(1))]
        return m


class _FreeByteSource(Elaboratable):
    """In place of the receive path's head FIFO: any byte ready in any cycle, any
    back-pressure toward the FIFO before it (every behaviour of the receive buffers)."""

    def __init__(self, width, depth):
        self.w_data, self.w_en, self.w_rdy = Signal(width), Signal(), Signal()
        self.r_data, self.r_rdy, self.r_en = Signal(width), Signal(), Signal()

    def elaborate(self, platform):
        m = Module()
        m.d.comb += [self.r_rdy.eq(AnySeq(1)), self.r_data.eq(AnySeq(len(self.r_data))),
                     self.w_rdy.eq(AnySeq(1))]
        return m


class DecoderProof(Elaboratable):
    """Harness of the link's frame decoder (see the module docstring)."""

    def __init__(self, lcfg: LinkConfig, mutant: str | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.lcfg, self.mutant = lcfg, mutant
        self.latency = None                    # the decision latency, read when elaborated
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]

    def _elaborate_link(self, platform):
        link = HostLink(self.lcfg)
        link._MustUse__silence = True
        mut, made = self.mutant, []

        def memory(orig):
            class Faulty(orig):
                """The link's memories in construction order (the value RAM first); the value
                RAM's writes may go to the neighbouring word (``values_swapped``) or its reads
                one word ahead (``value_read_ahead``)."""

                def __init__(self, *a, **k):
                    super().__init__(*a, **k)
                    made.append(self)

                def _redirect(self, port, fault):
                    if made.index(self) != 0 or mut != fault or getattr(self, "_built", 0):
                        return port
                    fake = Signal.like(port.addr, name=f"mutant_{fault}_addr")
                    self._mutant = getattr(self, "_mutant", []) + [
                        port.addr.eq(fake ^ 1 if fault == "values_swapped" else fake + 1)]
                    return _Readdressed(port, fake)

                def write_port(self, *a, **k):
                    return self._redirect(super().write_port(*a, **k), "values_swapped")

                def read_port(self, *a, **k):
                    return self._redirect(super().read_port(*a, **k), "value_read_ahead")
            return Faulty

        fifos = []

        def fifo(orig):
            def make(*a, **k):
                # the link's FIFOs in construction order: receive buffer, receive head, ...
                fifos.append(_FreeByteSource(*a, **k) if len(fifos) == 1 else orig(*a, **k))
                return fifos[-1]
            return make

        wraps = [("UartRx", lambda orig: _FreeUart), ("Memory", memory),
                 ("SyncFIFOBuffered", fifo)]
        if mut == "wrong_residue":
            # the check compares against a residue one bit off: intact frames fail, frames
            # corrupted to that residue pass
            wraps.append(("CRC_RESIDUE", lambda orig: orig ^ 1))
        with contextlib.ExitStack() as stack:
            for name, w in wraps:
                stack.enter_context(patched(core_module, name, w))
            link_m = link.elaborate(platform)
        for mem in made:
            link_m.d.comb += getattr(mem, "_mutant", [])
            mem._built = True                  # the harness's own ports are not redirected
        if not isinstance(link_m.submodules["rx_head"], _FreeByteSource):
            raise RuntimeError("the link's receive head FIFO was not the second one built")
        return link, link_m

    def elaborate(self, platform):
        lc, m = self.lcfg, Module()
        m.domains.sync = self.cd
        N, W, I = lc.n_written, lc.current_bytes, lc.current_width
        max_vals = (MAX_FRAME - HEADER_BYTES - 2) // W + 1
        link, link_m = self._elaborate_link(platform)
        kt = Signal(range(max_vals), name="tracked_value")
        m.d.comb += kt.eq(AnyConst(len(kt)))
        assume_all(m, [kt < max_vals])
        vport = link_m.submodules["vmem"].read_port(domain="comb")
        m.d.comb += vport.addr.eq(kt)
        rxf, urx = link_m.submodules["rx_head"], link_m.submodules["uart_rx"]
        frag = Fragment.get(link_m, platform)
        m.submodules.link = frag
        for name in ("core_busy", "spike_valid", "sweep_done"):
            m.d.comb += getattr(link, name).eq(AnySeq(1))
        for name in ("spike_index", "spike_sweep"):
            m.d.comb += getattr(link, name).eq(AnySeq(len(getattr(link, name))))
        reg = {name: signal_named(frag, name) for name in
               ("remain", "zero_pending", "started", "flen", "overlong", "crc", "acc", "phase",
                "nvals", "count", "widx", "exp_seq", "rx_fsm_state")}
        hdr = [signal_named(frag, f"hdr{i}") for i in range(HEADER_BYTES + CONTROL_PAYLOAD)]
        inc = {name: signal_named(frag, f"inc_{name}") for name in
               (*VERDICTS, "seq_gaps", "framing_errors", "late_writes")}
        fsm = reg["rx_fsm_state"]
        names = {}
        for i in range(2 ** len(fsm)):
            try:
                label = str(fsm.decoder(i))
            except (KeyError, IndexError):             # not a state's encoding
                continue
            if "/" in label:
                names[label.split("/")[0]] = i
        st = {name: Signal(name=f"in_{name}") for name in ("RECV", "CHECK", "DECIDE", "WAIT",
                                                            "WRITE")}
        m.d.comb += [s.eq(fsm == names[n]) if n in names else s.eq(0) for n, s in st.items()]

        # --- the reference decoder, byte by byte ----------------------------------------------
        take = Signal(name="ref_take")
        b = Signal(8, name="ref_byte")
        m.d.comb += [take.eq(rxf.r_rdy & rxf.r_en), b.eq(rxf.r_data)]
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
        lat = self.latency = 2 if "DECIDE" in names else 1
        cur = {k: delim & x for k, x in v.items()} | {"seq_gaps": gap}
        for step in range(lat):
            nxt = {}
            for k, x in cur.items():
                r = Signal(8 if k == "seq_gaps" else 1, name=f"ref_{k}_d{step + 1}")
                m.d.sync += r.eq(x)
                nxt[k] = r
            cur = nxt
        checks = [(inc[k] == cur[k], f"verdict: {k}") for k in (*VERDICTS, "seq_gaps")]
        checks += [(inc["framing_errors"] == cobs_err + urx.frame_error,
                    "verdict: framing_errors")]
        assert_all(m, checks)

        # --- the writes -------------------------------------------------------------------------
        owed = Signal(name="ref_owed")                   # writes of an accepted frame to come
        wfirst = Signal(16, name="ref_write_first")
        wcount = Signal(range(max_vals + 1), name="ref_write_count")
        wval = Signal(8 * W, name="ref_write_value")
        done = Signal(range(max_vals + 1), name="ref_writes_seen")
        late = inc["late_writes"] != 0
        wr = link.i_wr_en
        with m.If(delim & v["frames_ok"] & write):
            m.d.sync += [owed.eq(n_vals != 0), wfirst.eq(first), wcount.eq(n_vals),
                         done.eq(0), wval.eq(val)]
        with m.If(wr):
            m.d.sync += done.eq(done + 1)
            with m.If(done + 1 == wcount):
                m.d.sync += owed.eq(0)
        with m.If(late):
            m.d.sync += owed.eq(0)
        in_flight = wr & (done + 1 == wcount)              # the frame's last write, leaving
        checks = [(~wr | owed, "writes: only an accepted frame's"),
                  (~wr | (link.i_wr_addr == wfirst + done), "writes: in order, none lost"),
                  (~wr | (done != kt) | (link.i_wr_data == wval[:I]),
                   "writes: the tracked value"),
                  (~late | (done == 0) & (owed | (wcount == 0)),
                   "late write: before any write"),
                  (~take | ~owed | in_flight, "no byte taken while writes are owed")]
        assert_all(m, checks)

        # --- invariants -----------------------------------------------------------------------
        holding = (st["RECV"] & ~ended) | st["CHECK"] | st["DECIDE"]
        reset = (st["RECV"] & ended) | st["WAIT"] | st["WRITE"]
        assembling = holding & ~over & (flen >= HEADER_BYTES + 2)
        pos = flen - (HEADER_BYTES + 2)
        checks = [
            (st["RECV"] | st["CHECK"] | st["DECIDE"] | st["WAIT"] | st["WRITE"],
             "state: a decoder state"),
            (flen <= MAX_FRAME, "reference: length in range"),
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
            (~ended | ~framing | st["RECV"] | st["CHECK"] | st["DECIDE"] | st["WAIT"]
             | st["WRITE"], "state: frame end seen"),
            (~st["RECV"] | ~owed | in_flight, "state: no writes owed while receiving"),
            (~(st["CHECK"] | st["DECIDE"] | st["WAIT"] | st["WRITE"]) | ended & framing
             & (left == 0), "state: past an ended frame"),
            (~st["WAIT"] | (reg["count"] == wcount) & (done == 0) & (owed == (wcount != 0))
             & ~wr & (reg["widx"] == 0), "state: waiting to write"),
            (~st["WRITE"] | (reg["count"] == wcount) & owed
             & (reg["widx"] == done + 1 + wr) & (reg["widx"] <= wcount) & (reg["widx"] != 0),
             "state: writing"),
            (~(st["WAIT"] | st["WRITE"]) | (Cat(hdr[8], hdr[9]) == wfirst), "state: first"),
            (~(st["WAIT"] | st["WRITE"] | owed) | (wfirst + wcount <= N),
             "state: an accepted frame's writes in range"),
        ]
        checks += [(~(flen > i) | (h == rh), f"state: header byte {i}")
                   for i, (h, rh) in enumerate(zip(hdr, rhdr))]
        stored = holding & ~over & (HEADER_BYTES + 2 + W * (kt + 1) <= flen)
        checks += [(~stored | (vport.data == val[:I]), "state: tracked value assembled"),
                   (~(st["WAIT"] | st["WRITE"]) | (kt >= wcount) | (vport.data == wval[:I]),
                    "state: tracked value to write")]
        assert_all(m, checks)
        return m


def _same_top_bytes(a, b, n, width: int):
    """``a`` and ``b`` (``width`` bytes each) agree in their top ``n`` bytes."""
    out = Const(1, 1)
    for p in range(1, width):
        out = out & ((n != p) | (a[8 * (width - p):] == b[8 * (width - p):]))
    return out


class _Readdressed:
    """A memory port whose address the harness drives (a mutant's redirection)."""

    def __init__(self, port, addr):
        self._port, self.addr = port, addr

    def __getattr__(self, name):
        return getattr(self._port, name)


def decoder_proof_config(n_neurons: int = 8, **kwargs) -> LinkConfig:
    """A small link for the decoder proof: ``n_neurons`` (default 8), a 4-byte receive FIFO,
    ``kwargs`` to :func:`~cuneate.hdl.link.config.link_config`."""
    kw = dict(rx_fifo_depth=4, tx_fifo_depth=4, batch_capacity=2)
    kw.update(kwargs)
    return link_config(dict(n_neurons=n_neurons, clock_hz=n_neurons * 16e3 * 4), **kw)


#: memories of the link that start with any contents
MEMORIES = ("vmem", "smem", "tmem")


def decoder_harness(lcfg: LinkConfig, mutant: str | None = None) -> str:
    """RTLIL of the harness (top ``decoder_eq``), the memories' initial contents removed."""
    return harness_rtlil(DecoderProof(lcfg, mutant), "decoder_eq", MEMORIES)


def _depth(top: DecoderProof) -> int:
    # the decision latency + 5: the write port's and the value RAM's pipelines, the receive
    # FIFO's head
    return top.latency + 5


def induction_depth(lcfg: LinkConfig) -> int:
    """The k of the k-induction: the decoder's decision latency (cycles from the delimiter to
    the verdict, read from its states) + 5 (the write port's and the value RAM's pipelines,
    the receive FIFO's head)."""
    top = DecoderProof(lcfg)
    harness_rtlil(top, "decoder_eq", MEMORIES)
    return _depth(top)


def prove_decoder(lcfg: LinkConfig, workdir: Path, mode: str = "prove",
                  depth: int | None = None, mutant: str | None = None,
                  timeout_s: float = 3600, engine: str = "smtbmc",
                  solver: str = SOLVER) -> ProofResult:
    """Prove (``mode="prove"``, k-induction of ``depth`` steps, default
    :func:`induction_depth`) or check to a bound (``mode="bmc"``) that the link's frame
    decoder gives every frame its specified verdict and loses or reorders no accepted
    write."""
    top = DecoderProof(lcfg, mutant)
    il = harness_rtlil(top, "decoder_eq", MEMORIES)         # one elaboration: the RTLIL and k
    return run_proof("link frame decoder meets the wire format", il, workdir, "decoder_eq",
                     mode, depth or _depth(top), timeout_s, engine, ABSTRACTIONS, solver)
