"""Protocol proofs of the bus faces by k-induction (SymbiYosys): each harness takes one
component as it is, through its ports, its inputs free (``AnySeq``: every sequence the far end
can give), and checks it against the protocol's rules and a reference written here.

``axi-stream-out`` (:class:`~cuneate.hdl.axi.stream.StreamSpikes`, the AXI4-Stream master)
    TDATA, TLAST and TUSER held unchanged while TVALID and not TREADY, TVALID never withdrawn;
    no spike lost, duplicated or reordered (a spike picked at random when it is taken - every
    spike, for the proof - is the next spike beat after those ahead of it, with its id and
    sweep); exactly one TLAST per sweep, after the block's ``sweep_done`` and
    :data:`~cuneate.hdl.lib.payload.SPIKES_SETTLE` cycles without a spike; a marker beat
    (TUSER) only for a sweep without a spike. Assumed: a tick only while no sweep is open (the
    face holds it); the payload's contract (spikes only within their sweep, each offered at
    the latest ``SPIKES_SETTLE`` cycles after ``sweep_done`` and held until taken).
``axi-stream-in`` (:class:`~cuneate.hdl.axi.stream.StreamWrites`, the AXI4-Stream slave)
    under any TVALID/TDATA/TLAST pattern and any back-pressure of the block: every beat taken is
    written once, in order, with its address, value and last flag, or refused and counted when
    its address or value is out of range; the write offered to the block is held until taken;
    a burst's first beat is taken only while the block is idle and no tick waits, and the
    ticks are held from it until its last beat is taken and written.
``axi-lite`` (:class:`~cuneate.hdl.axi.lite.AxiLiteRegisters`)
    BVALID and RVALID (with BRESP, RDATA, RRESP) held until taken; a register access exactly
    once per write (address and data together) and per read, with their address, data and
    byte enables; one response per request, none without one, carrying the register file's
    answer of its own access (in order: one request at a time per direction). Assumed: the
    master holds AWVALID, WVALID and ARVALID with their payloads until taken (AXI4 A3.2.1).

The Wishbone bank's proof is :mod:`cuneate.hdl.wishbone.formal`. **Mutants** are subclasses of
the components through their documented hooks (``loads``, ``keep_b``): a beat
register loaded while stalled, a write register overwritten while the block holds it, a write
response withdrawn before it is taken; each proof must fail on its mutant.
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Cat, Const, Mux, Signal
from amaranth.hdl import Fragment

from ..flow.sby import SOLVER
from ..lib.formal import (ClockedHarness, ProofResult, assert_all, assume_all, harness_rtlil,
                          run_proof, signal_named)
from ..lib.payload import SPIKES_SETTLE, payload_spec
from ..lib.regmap import MAP_BYTES, stream_format
from ..wishbone.formal import PROOFS as WB_PROOFS
from .lite import SLVERR, AxiLiteRegisters
from .stream import StreamSpikes, StreamWrites

__all__ = ["PROOFS", "MUTANTS", "prove_face", "proof_info", "face_harness"]


def proof_info(n_neurons: int = 8):
    """The payload the stream proofs are sized for: an Izhikevich core of ``n_neurons``
    (8: ids of 3 bits, 16-bit sweep numbers, 18-bit values)."""
    from ..izhikevich import IzhikevichConfig
    cfg = IzhikevichConfig(n_neurons=n_neurons, clock_hz=16e3 * 64, update_hz=16e3,
                           tick_source="external")
    return payload_spec(cfg).info


def _loads_always(side):
    """The mutant of a stream side (``StreamSpikes``, ``StreamWrites``): its register on offer
    loaded whatever its state (a beat loaded while stalled, a write overwritten while the block
    holds it)."""
    class LoadsAlways(side):
        def loads(self, reg):
            return Const(1)
    return LoadsAlways


_StallLoads = _loads_always(StreamSpikes)


class SpikesProof(ClockedHarness):
    """The AXI4-Stream master (see the module docstring)."""

    def elaborate(self, platform):
        dut = self.dut
        frag = Fragment.get(dut, platform)
        m = self.module(frag)
        sp, out = dut.spikes, dut.m_axis
        self.free(m, sp.valid, sp.payload.as_value(), dut.sweep_done, dut.tick, out.ready)
        assume_all(m, [~dut.tick | ~dut.sweep_open])
        F = 8 * stream_format(dut.info)["spike_field_bytes"]
        take = sp.valid & sp.ready
        shake = out.valid & out.ready
        beat = out.payload
        # --- stability: a beat once offered stays, unchanged, until taken
        stalled = self.reg(m, out.valid & ~out.ready, "ref_stalled")
        before = self.reg(m, beat.as_value(), "ref_beat")
        # --- the reference sweep: opened by a tick, closed by its TLAST beat
        ref_open, ref_done, ref_any = (Signal(name=f"ref_{n}") for n in ("open", "done", "any"))
        quiet = Signal(range(SPIKES_SETTLE + 1), name="ref_quiet")   # cycles without a spike
        with m.If(dut.tick):
            m.d.sync += [ref_open.eq(1), ref_done.eq(0), ref_any.eq(0)]
        with m.If(shake & beat.tlast):
            m.d.sync += ref_open.eq(0)
        with m.If(dut.sweep_done & ref_open):
            m.d.sync += [ref_done.eq(1), quiet.eq(0)]
        with m.Elif(take):
            m.d.sync += quiet.eq(0)
        with m.Elif(quiet != SPIKES_SETTLE):
            m.d.sync += quiet.eq(quiet + 1)
        with m.If(take):
            m.d.sync += ref_any.eq(1)
        # the payload's side (lib/payload.py): spikes only within their sweep, each offered
        # at the latest SPIKES_SETTLE cycles after sweep_done and held until taken
        since = Signal(range(SPIKES_SETTLE + 1), name="ref_since_done")
        with m.If(dut.sweep_done & ref_open):
            m.d.sync += since.eq(0)
        with m.Elif(since != SPIKES_SETTLE):
            m.d.sync += since.eq(since + 1)
        waiting = self.reg(m, sp.valid & ~sp.ready, "ref_spike_waiting")
        offered = self.reg(m, sp.payload.as_value(), "ref_spike_offered")
        assume_all(m, [~sp.valid | ref_open,
                       ~(sp.valid & ~waiting) | ~(ref_done & (since == SPIKES_SETTLE)),
                       ~waiting | sp.valid & (sp.payload.as_value() == offered)])
        # the sweep may end now: done, settled, no spike offered
        may_end = self.reg(m, ref_open & ref_done & (quiet == SPIKES_SETTLE) & ~sp.valid,
                           "ref_may_end")
        # --- a tracked spike: any spike taken may be the one
        tracking = Signal(name="ref_tracking")
        ahead = Signal(name="ref_ahead")            # a spike beat is due before it
        n_index = len(sp.payload.index)
        t_index = Signal(n_index, name="ref_index")
        t_sweep = Signal(len(sp.payload.sweep), name="ref_sweep")
        pick = Signal(name="ref_pick")
        self.free(m, pick)
        spike_beat = shake & ~beat.tuser
        held = signal_named(frag, "held_valid")
        with m.If(take & pick & ~tracking):
            m.d.sync += [tracking.eq(1), t_index.eq(sp.payload.index),
                         t_sweep.eq(sp.payload.sweep), ahead.eq(held)]
        with m.Elif(spike_beat & tracking):
            with m.If(ahead):
                m.d.sync += ahead.eq(0)
            with m.Else():
                m.d.sync += tracking.eq(0)
        is_tracked = (beat.tdata[:F] == t_index) & (beat.tdata[F:] == t_sweep)
        assert_all(m, [
            (~stalled | out.valid, "stream: TVALID held until TREADY"),
            (~stalled | (beat.as_value() == before), "stream: the beat unchanged while stalled"),
            (~(spike_beat & tracking & ~ahead) | is_tracked, "stream: the tracked spike next"),
            (~(shake & beat.tuser & tracking), "stream: no marker before the tracked spike"),
            (~(out.valid & ~stalled & beat.tlast) | may_end,
             "sweep: TLAST after sweep_done and the settling"),
            (~(shake & beat.tlast) | ref_open, "sweep: one TLAST per sweep"),
            (~(shake & beat.tuser) | ~ref_any & beat.tlast, "sweep: a marker for an empty sweep"),
            (~(shake & beat.tlast & ~beat.tuser) | ref_any, "sweep: TLAST on a spike's beat"),
        ])
        # --- invariants
        hid, hsw = signal_named(frag, "held_id"), signal_named(frag, "held_sweep")
        ended, done = signal_named(frag, "ended"), signal_named(frag, "done_seen")
        in_held = held & (hid == t_index) & (hsw == t_sweep)
        spike_out = out.valid & ~beat.tuser
        assert_all(m, [
            (dut.sweep_open == ref_open, "state: the sweep open"),
            (~ref_open | (done == ref_done), "state: sweep_done seen"),
            (ended == (out.valid & beat.tlast), "state: the TLAST beat on offer"),
            (~ended | ~held, "state: nothing held behind TLAST"),
            (~(out.valid & beat.tuser) | beat.tlast, "state: a marker ends its sweep"),
            (~held | ref_any, "state: a held spike is the sweep's"),
            (~(out.valid & ~beat.tlast) | held, "state: a spike held behind a beat not last"),
            ((hid[n_index:] == 0) & (~spike_out | (beat.tdata[n_index:F] == 0)),
             "state: ids in range"),
            (~(ref_open & ref_any & ~ended) | held, "state: the sweep's last spike held"),
            (~ended | (beat.tuser == ~ref_any), "state: the TLAST beat a marker if empty"),
            (ref_open | ~held & ~out.valid, "state: nothing between sweeps"),
            (~(tracking & ahead) | spike_out & in_held, "state: the tracked spike held"),
            (~(tracking & ~ahead) | (spike_out & is_tracked) | (in_held & ~spike_out),
             "state: the tracked spike next"),
        ])
        return m


_Overwrites = _loads_always(StreamWrites)


class WritesProof(ClockedHarness):
    """The AXI4-Stream slave (see the module docstring)."""

    def elaborate(self, platform):
        dut = self.dut
        info = dut.info
        m = self.module(Fragment.get(dut, platform))
        s, w = dut.s_axis, dut.write
        self.free(m, s.valid, s.payload.as_value(), w.ready, dut.busy, dut.pending)
        F = 8 * stream_format(info)["write_field_bytes"]
        fmt = info.value_format
        take = s.valid & s.ready
        value, addr = s.payload.tdata[:F].as_signed(), s.payload.tdata[F:]
        ok = (addr < info.n_written) & (value >= fmt.min_raw) & (value <= fmt.max_raw)
        # --- the reference burst and a tracked beat
        ref_burst = Signal(name="ref_burst")
        with m.If(take):
            m.d.sync += ref_burst.eq(~s.payload.tlast)
        tracking = Signal(name="ref_tracking")
        t_addr, t_value = Signal(len(w.payload.addr), name="ref_addr"), \
            Signal(fmt.width, name="ref_value")
        t_last = Signal(name="ref_last")
        pick = Signal(name="ref_pick")
        self.free(m, pick)
        shake = w.valid & w.ready
        with m.If(take & ok & pick & ~tracking):
            m.d.sync += [tracking.eq(1), t_addr.eq(addr), t_value.eq(value),
                         t_last.eq(s.payload.tlast)]
        with m.Elif(shake & tracking):
            m.d.sync += tracking.eq(0)
        stalled = self.reg(m, w.valid & ~w.ready, "ref_stalled")
        before = self.reg(m, w.payload.as_value(), "ref_write")
        is_tracked = (w.payload.addr == t_addr) & (w.payload.value.as_unsigned() == t_value) \
            & (w.payload.last == t_last)
        assert_all(m, [
            (~stalled | w.valid, "write: offered until taken"),
            (~stalled | (w.payload.as_value() == before), "write: unchanged until taken"),
            (~(shake & tracking) | is_tracked, "write: the tracked beat, in order"),
            (~tracking | w.valid & is_tracked, "write: the tracked beat on offer"),
            (dut.count_writes == take & ok, "count: written"),
            (dut.count_refused == take & ~ok, "count: refused"),
            (dut.count_bursts == take & s.payload.tlast, "count: bursts"),
            (~take | ref_burst | ~dut.busy & ~dut.pending, "rule: a burst starts between sweeps"),
            (dut.burst_open == ref_burst, "rule: the burst open"),
            (dut.hold == ref_burst | w.valid, "rule: ticks held while a burst or a write is "
                                               "in flight"),
        ])
        return m


class _DropsB(AxiLiteRegisters):
    def keep_b(self):
        return Const(0)


class LiteProof(ClockedHarness):
    """The AXI4-Lite slave (see the module docstring)."""

    def elaborate(self, platform):
        m = self.module()
        d, r = self.dut, self.dut.regs
        self.free(m, d.awaddr, d.awvalid, d.wdata, d.wstrb, d.wvalid, d.bready, d.araddr,
                  d.arvalid, d.rready, r.r_data, r.err)
        # the master holds a valid request, unchanged, until it is taken
        held = []
        for valid, ready, payload, name in ((d.awvalid, d.awready, d.awaddr, "aw"),
                                            (d.wvalid, d.wready, Cat(d.wdata, d.wstrb), "w"),
                                            (d.arvalid, d.arready, d.araddr, "ar")):
            was = self.reg(m, valid & ~ready, f"ref_{name}_waiting")
            pay = self.reg(m, payload, f"ref_{name}_payload")
            held += [~was | valid & (payload == pay)]
        assume_all(m, held)
        aw, w, ar = d.awvalid & d.awready, d.wvalid & d.wready, d.arvalid & d.arready
        b, rd = d.bvalid & d.bready, d.rvalid & d.rready
        top = MAP_BYTES // 4
        exp_w, exp_r = Signal(range(top + 1), name="ref_w_word"), \
            Signal(range(top + 1), name="ref_r_word")
        m.d.comb += [exp_w.eq(Mux(d.awaddr[2:] < top, d.awaddr[2:], top)),
                     exp_r.eq(Mux(d.araddr[2:] < top, d.araddr[2:], top))]
        owed_b, owed_r = Signal(name="ref_owed_b"), Signal(name="ref_owed_r")
        b_err, r_err = Signal(name="ref_b_err"), Signal(name="ref_r_err")
        r_word = Signal(32, name="ref_r_data")
        with m.If(aw):
            m.d.sync += [owed_b.eq(1), b_err.eq(r.err)]
        with m.Elif(b):
            m.d.sync += owed_b.eq(0)
        with m.If(ar):
            m.d.sync += [owed_r.eq(1), r_err.eq(r.err), r_word.eq(r.r_data)]
        with m.Elif(rd):
            m.d.sync += owed_r.eq(0)
        b_wait = self.reg(m, d.bvalid & ~d.bready, "ref_b_waiting")
        b_was = self.reg(m, d.bresp, "ref_bresp")
        r_wait = self.reg(m, d.rvalid & ~d.rready, "ref_r_waiting")
        r_was = self.reg(m, Cat(d.rdata, d.rresp), "ref_r_beat")
        assert_all(m, [
            (~b_wait | d.bvalid & (d.bresp == b_was), "B: held until BREADY"),
            (~r_wait | d.rvalid & (Cat(d.rdata, d.rresp) == r_was), "R: held until RREADY"),
            (aw == w, "W: address and data taken together"),
            (~aw | ~owed_b, "W: one write at a time"),
            (~ar | ~owed_r, "R: one read at a time"),
            (d.bvalid == owed_b, "B: one response per write, none without one"),
            (d.rvalid == owed_r, "R: one response per read, none without one"),
            (~d.bvalid | (d.bresp == Cat(Const(0, 1), b_err)), "B: the access's answer"),
            (~d.rvalid | (d.rresp == Cat(Const(0, 1), r_err)) & (d.rdata == r_word),
             "R: the access's answer"),
            ((r.en & r.w_en) == aw, "access: one write per write request"),
            ((r.en & ~r.w_en) == ar, "access: one read per read request"),
            (~aw | (r.w_data == d.wdata) & (r.w_strb == d.wstrb) & (r.addr == exp_w),
             "access: the write's address, data and byte enables"),
            (~ar | (r.addr == exp_r), "access: the read's address"),
        ])
        return m


#: target -> (harness, component, its mutant's class, the mutant's name, k)
PROOFS = {
    "axi-stream-out": (SpikesProof, lambda: StreamSpikes(proof_info()),
                       lambda: _StallLoads(proof_info()), "beat_loaded_while_stalled",
                       SPIKES_SETTLE + 1),
    "axi-stream-in": (WritesProof, lambda: StreamWrites(proof_info()),
                      lambda: _Overwrites(proof_info()), "write_overwritten", 4),
    "axi-lite": (LiteProof, AxiLiteRegisters, _DropsB, "bvalid_withdrawn", 4),
}
MUTANTS = {v[3]: k for k, v in PROOFS.items()}


def face_harness(target: str, mutant: str | None = None) -> str:
    """RTLIL of ``target``'s harness (with its mutant when ``mutant`` names it)."""
    return harness_rtlil(_harness(target, mutant), "face_proof")


def _harness(target: str, mutant: str | None):
    harness, make, make_mutant, mname, _ = _table(target)
    if mutant is not None and mutant != mname:
        raise ValueError(f"{target}: unknown mutant {mutant!r} (its mutant: {mname})")
    return harness(make_mutant() if mutant else make())


def _table(target: str):
    table = PROOFS | WB_PROOFS
    if target not in table:
        raise ValueError(f"unknown face proof {target!r}; known: {', '.join(table)}")
    return table[target]


def prove_face(target: str, workdir: Path, mode: str = "prove", depth: int | None = None,
               mutant: str | None = None, timeout_s: float = 600,
               solver: str = SOLVER) -> ProofResult:
    """Prove (k-induction of ``depth`` steps, default the target's) or check to a bound
    (``mode="bmc"``) the protocol of ``target`` (a key of :data:`PROOFS` or of
    :data:`cuneate.hdl.wishbone.formal.PROOFS`), on the component or its ``mutant``."""
    k = depth or _table(target)[4]
    il = face_harness(target, mutant)
    return run_proof(f"{target} protocol", il, Path(workdir), "face_proof", mode, k,
                     timeout_s, "smtbmc", ["the far ends' signals free (AnySeq)"], solver)
