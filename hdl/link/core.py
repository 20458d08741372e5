"""UART host link gateware: framed current writes in, spike batches and counters out.

:class:`HostLink` sits between a UART and an :class:`~cuneate.hdl.izhikevich.IzhikevichCore`
configured with ``tick_source="external"``; :class:`LinkedCore` is the two wired together
(the unit a board top instantiates and the cocotb bench drives through its ``rx``/``tx`` pins).
The wire format is :mod:`cuneate.hdl.link.codec` (its functions are the model: the CRC step
is the same function in RTL and host, the COBS encoder scans as the model does).

Receive path
    UART -> FIFO (``rx_fifo_depth`` bytes; a byte arriving when it is full is dropped and
    counted ``rx_overflows``) -> streaming COBS decoder with running CRC-32; the header is kept
    in registers and the currents are assembled into a value RAM as they arrive, so nothing
    acts before the frame is checked (size, CRC residue, version, ``len`` against the size, in
    that order, then the sequence number and the type's layout). After the delimiter the
    checks' outcomes are registered in one cycle and acted on, in that order, in the next. A
    good frame is then executed while the FIFO holds further bytes (back-pressure).
    ``WRITE`` waits until the core is between sweep ``tick - 1`` and sweep ``tick`` and writes
    one current per cycle; the tick generator holds the next tick while a write is in progress
    (jitter of at most ``count + 1`` cycles, no drift), so the currents are in effect exactly
    from sweep ``tick``. A write whose sweep has started is refused (``late_writes``).
Tick generator
    Divider of ``cycles_per_tick``; runs freely (``OP_START``), for ``arg`` sweeps
    (``OP_STEP``) or not at all (``OP_STOP``, the state after reset). A tick due while the
    previous one is still waiting is lost and counted (``tick_overruns``).
Transmit path
    Spikes from the core's spike stream go into one of two batch buffers of
    ``batch_capacity`` entries (ping-pong): one accumulates while the other is sent. A batch
    closes after ``batch_sweeps`` sweeps (or when a step ends) and is sent as one ``SPIKES``
    frame, empty or not; spikes that do not fit are counted in the frame and in
    ``spikes_dropped``; a batch that closes while both buffers are busy is dropped whole and
    counted ``batches_dropped`` (the host sees the gap in ticks). Frames are built into a byte
    RAM with their CRC-32, then COBS-encoded by scanning, into a small FIFO feeding the UART
    (the spike and frame RAMs' outputs are registered before anything decides on them: a
    read takes two cycles, and the encoder six cycles a byte against the UART's ten bits).

Counters (``counter_width`` bits, 32 by default, saturating, never wrapping; each counts its
events one cycle after them, its increment registered): :data:`~cuneate.hdl.link.codec
.COUNTER_NAMES`.
"""

from __future__ import annotations

from amaranth import Array, Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..izhikevich import ConfigError, IzhikevichArray, IzhikevichConfig, IzhikevichCore
from ..flow.verilog import verilog_text
from ..lib.uart import UartRx, UartTx
from .codec import (COUNTER_NAMES, CRC_BYTES, CRC_INIT, CRC_RESIDUE, MAX_FRAME, MIN_FRAME,
                    MSG_CONTROL, MSG_COUNTERS, MSG_SPIKES, MSG_WRITE, OP_CLEAR_COUNTERS,
                    OP_READ_COUNTERS, OP_START, OP_STEP, OP_STOP, SPIKE_HEADER, CONTROL_PAYLOAD,
                    HEADER_BYTES, VERSION)
from .config import LinkConfig
from .datapath import crc32_update

__all__ = ["HostLink", "LinkedCore", "link_verilog", "link_core_wiring", "linked_core_module"]


def _pick(options, index):
    """``options[index]`` as a chain of multiplexers (``index`` beyond the list: the last)."""
    out = options[-1]
    for i in range(len(options) - 2, -1, -1):
        out = Mux(index == i, options[i], out)
    return out


class HostLink(wiring.Component):
    """The link proper; see the module docstring. Ports toward the core mirror its host port,
    tick, busy flag, spike stream and ``sweep_done``."""

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        cfg = lcfg.core
        N = lcfg.n_written
        super().__init__({
            "rx": In(1, init=1), "tx": Out(1, init=1),
            "i_wr_en": Out(1), "i_wr_addr": Out(range(N)), "i_wr_data": Out(lcfg.current_width),
            "tick": Out(1), "core_busy": In(1),
            "spike_valid": In(1), "spike_ready": Out(1),
            "spike_index": In(range(lcfg.n_spike_ids)),
            "spike_sweep": In(cfg.sweep_number_width), "sweep_done": In(1),
            "running": Out(1), "sweeps_started": Out(32),
        })

    def elaborate(self, platform):
        lc, cfg = self.lcfg, self.lcfg.core
        N, W, B, CAP = lc.n_written, lc.current_bytes, lc.batch_sweeps, lc.batch_capacity
        m = Module()

        # --- counters ---------------------------------------------------------------------
        cw = lc.counter_width
        ctr = {name: Signal(cw, name=f"ctr_{name}") for name in COUNTER_NAMES}
        inc = {name: Signal(8, name=f"inc_{name}") for name in COUNTER_NAMES}
        clear = Signal()
        # increments and the clear are registered before the adders: the conditions that
        # raise them (decoder, tick generator, batch logic) would otherwise lead into each
        # counter's carry chain. A counter lags its event by one cycle; the counters frame
        # reads them at least ten cycles after the frame that asked for it was decided.
        inc_r = {name: Signal(8, name=f"inc_r_{name}") for name in COUNTER_NAMES}
        clear_r = Signal()
        m.d.sync += [inc_r[name].eq(inc[name]) for name in COUNTER_NAMES]
        m.d.sync += clear_r.eq(clear)
        for name in COUNTER_NAMES:
            total = ctr[name] + inc_r[name]
            m.d.sync += ctr[name].eq(Mux(clear_r, 0, Mux(total[cw], (1 << cw) - 1, total[:cw])))

        # --- UART and receive FIFO --------------------------------------------------------
        m.submodules.uart_rx = urx = UartRx(lc.clocks_per_bit)
        m.submodules.uart_tx = utx = UartTx(lc.clocks_per_bit)
        m.submodules.rx_fifo = rx_store = SyncFIFOBuffered(width=8, depth=lc.rx_fifo_depth)
        # a two-entry register FIFO after the receive buffer: the decoder reads registers, not
        # the block RAM's output (its clock-to-output would start the decoder's paths)
        m.submodules.rx_head = rxf = SyncFIFOBuffered(width=8, depth=2)
        m.d.comb += [rxf.w_data.eq(rx_store.r_data), rxf.w_en.eq(rx_store.r_rdy),
                     rx_store.r_en.eq(rxf.w_rdy)]
        m.submodules.tx_fifo = txf = SyncFIFOBuffered(width=8, depth=lc.tx_fifo_depth)
        m.d.comb += [urx.rx.eq(self.rx), self.tx.eq(utx.tx),
                     rx_store.w_data.eq(urx.data), rx_store.w_en.eq(urx.valid),
                     utx.data.eq(txf.r_data), utx.valid.eq(txf.r_rdy), txf.r_en.eq(utx.ready)]
        m.d.comb += inc["rx_overflows"].eq(urx.valid & ~rx_store.w_rdy)
        cobs_error = Signal()
        m.d.comb += inc["framing_errors"].eq(cobs_error + urx.frame_error)

        # --- tick generator ---------------------------------------------------------------
        free = Signal()
        steps = Signal(32)
        div = Signal(range(cfg.cycles_per_tick))
        pending = Signal()
        writing = Signal()
        S = self.sweeps_started
        active = free | (steps != 0)
        m.d.comb += self.running.eq(active)
        tick_out = Signal()
        m.d.comb += [tick_out.eq(pending & ~self.core_busy & ~writing), self.tick.eq(tick_out)]
        fire = active & (div == cfg.cycles_per_tick - 1)
        with m.If(active):
            m.d.sync += div.eq(Mux(div == cfg.cycles_per_tick - 1, 0, div + 1))
        with m.If(tick_out):
            m.d.sync += S.eq(S + 1)
            with m.If(~free & (steps != 0)):
                m.d.sync += steps.eq(steps - 1)
        with m.If(fire):
            m.d.sync += pending.eq(1)
            with m.If(pending & ~tick_out):
                m.d.comb += inc["tick_overruns"].eq(1)
        with m.Elif(tick_out):
            m.d.sync += pending.eq(0)

        # --- receive: COBS decoder, CRC, header registers, value RAM -----------------------
        # values assembled from every byte after ``first`` (the CRC's bytes included, then
        # discounted): one more than the longest write holds
        max_vals = (MAX_FRAME - HEADER_BYTES - 2) // W + 1
        m.submodules.vmem = vmem = Memory(shape=lc.current_width, depth=max_vals, init=[])
        vwr, vrd = vmem.write_port(), vmem.read_port()
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
        ftick = Cat(hdr[4], hdr[5], hdr[6], hdr[7])
        first = Cat(hdr[8], hdr[9])
        op = hdr[8]
        arg = Cat(hdr[9], hdr[10], hdr[11], hdr[12])
        exp_seq = Signal(8)

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
                        m.d.comb += [vwr.en.eq(1), vwr.addr.eq(nvals),
                                     vwr.data.eq(new_acc[:lc.current_width])]
                with m.Else():
                    m.d.sync += phase.eq(phase + 1)

        def frame_reset():
            return [flen.eq(0), remain.eq(0), zero_pending.eq(0), started.eq(0),
                    overlong.eq(0), crc.eq(CRC_INIT), phase.eq(0), nvals.eq(0)]

        count = Signal(range(max_vals + 1))
        widx = Signal(range(max_vals + 1))
        # the checks' outcomes, registered in CHECK for DECIDE
        bad_size, bad_crc, bad_version, bad_len = Signal(), Signal(), Signal(), Signal()
        is_write, out_of_range, is_control = Signal(), Signal(), Signal()
        gap = Signal(8)
        counters_req = Signal()
        m.d.comb += vrd.addr.eq(widx)
        m.d.sync += self.i_wr_en.eq(0)

        with m.FSM(name="rx_fsm") as rx_fsm:
            with m.State("RECV"):
                # no undefined FIFO data reaches the decoder while the FIFO is empty
                b = Mux(rxf.r_rdy, rxf.r_data, 0)
                with m.If(rxf.r_rdy):
                    with m.If(b == 0):
                        with m.If(remain != 0):
                            m.d.comb += cobs_error.eq(1)
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
                    bad_crc.eq(crc != CRC_RESIDUE),
                    bad_version.eq(ver != VERSION),
                    bad_len.eq(flen != plen + MIN_FRAME),
                    gap.eq(seq - exp_seq),
                    is_write.eq((typ == MSG_WRITE) & (flen >= MIN_FRAME + 2)
                                & (phase == (CRC_BYTES % W))),
                    # first + values > N, values = nvals - CRC_BYTES // W (the CRC's bytes
                    # were assembled as values too)
                    out_of_range.eq(first + nvals > N + CRC_BYTES // W),
                    # set for every frame: only WAIT and WRITE read it, and only an accepted
                    # write leads there
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
                    m.d.comb += inc["length_errors"].eq(1)
                with m.Elif(bad_crc):
                    m.d.comb += inc["crc_errors"].eq(1)
                with m.Elif(bad_version):
                    m.d.comb += inc["version_errors"].eq(1)
                with m.Elif(bad_len):
                    m.d.comb += inc["length_errors"].eq(1)
                with m.Else():
                    m.d.comb += inc["seq_gaps"].eq(gap)
                    m.d.sync += exp_seq.eq(seq + 1)
                    with m.If(is_write):
                        with m.If(out_of_range):
                            m.d.comb += inc["range_errors"].eq(1)
                        with m.Else():
                            m.d.comb += inc["frames_ok"].eq(1)
                            m.d.sync += widx.eq(0)
                            m.next = "WAIT"
                    with m.Elif(is_control):
                        m.d.comb += inc["frames_ok"].eq(1)
                        with m.Switch(op):
                            with m.Case(OP_START):
                                m.d.sync += free.eq(1)
                            with m.Case(OP_STOP):
                                m.d.sync += [free.eq(0), steps.eq(0)]
                            with m.Case(OP_STEP):
                                m.d.sync += [free.eq(0), steps.eq(arg)]
                            with m.Case(OP_READ_COUNTERS):
                                m.d.sync += counters_req.eq(1)
                            with m.Case(OP_CLEAR_COUNTERS):
                                m.d.comb += clear.eq(1)
                    with m.Else():
                        m.d.comb += inc["length_errors"].eq(1)
            with m.State("WAIT"):
                with m.If(S > ftick):
                    m.d.comb += inc["late_writes"].eq(1)
                    m.next = "RECV"
                with m.Elif((S == ftick) & ~self.core_busy & ~pending):
                    with m.If(count == 0):
                        m.next = "RECV"
                    with m.Else():
                        m.d.sync += widx.eq(1)
                        m.next = "WRITE"
            with m.State("WRITE"):
                # vrd.data holds value widx-1 (read in the previous cycle)
                m.d.comb += writing.eq(1)
                m.d.sync += [self.i_wr_en.eq(1), self.i_wr_addr.eq(first + widx - 1),
                             self.i_wr_data.eq(vrd.data), widx.eq(widx + 1)]
                with m.If(widx == count):
                    m.next = "RECV"
        # a continuous assignment (not a process of the FSM): simulators that start
        # combinational processes only on an input change see it from time 0
        m.d.comb += rxf.r_en.eq(rx_fsm.ongoing("RECV"))
        # the held tick may go once the last write is registered toward the core (the write
        # lands one cycle later, before the fetch of that neuron, which is at least one cycle
        # after the tick). writing is WRITE alone: in the cycle WAIT leaves for WRITE no tick
        # is pending (a condition of leaving), so the tick does not wait on WAIT's compares.

        # --- spike batches ----------------------------------------------------------------
        m.submodules.smem = smem = Memory(shape=24, depth=2 * CAP, init=[])
        swr = smem.write_port()
        acc_half = Signal()
        scount = Signal(range(CAP + 1))
        sdrop = Signal(16)
        bt = Signal(32)                                    # first sweep of the current batch
        in_batch = Signal(range(B + 1))                    # sweeps of the batch done
        closing = Signal()
        drain = Signal(range(8))
        half_pending = Signal(2)
        half_tick = Array(Signal(32, name=f"half_tick{i}") for i in range(2))
        half_count = Array(Signal(range(CAP + 1), name=f"half_count{i}") for i in range(2))
        half_drop = Array(Signal(16, name=f"half_drop{i}") for i in range(2))
        half_sweeps = Array(Signal(8, name=f"half_sweeps{i}") for i in range(2))
        # one register stage on the spike stream (the core's FIFO is a block RAM with a slow
        # clock-to-out): the batch logic works on sv/si/ss
        sv, si = Signal(), Signal(range(lc.n_spike_ids))
        ss = Signal(cfg.sweep_number_width)
        offset = Signal(cfg.sweep_number_width)
        m.d.comb += offset.eq(ss - bt[:cfg.sweep_number_width])
        next_batch = offset >= B
        # a step's end closes the batch at the sweep_done of the last sweep started: when the
        # ticks come as fast as the sweeps (cycles per tick near n_neurons + the pipeline) the
        # step's last tick goes before the previous sweep is done
        last_started = (bt + in_batch + 1)[:32] == S
        last_of_batch = (in_batch == B - 1) | (~free & (steps == 0) & ~pending & last_started)
        m.d.comb += self.spike_ready.eq(~sv | ~next_batch)
        with m.If(self.spike_ready):
            m.d.sync += [sv.eq(self.spike_valid), si.eq(self.spike_index),
                         ss.eq(self.spike_sweep)]
        with m.If(sv & ~next_batch):
            with m.If(scount < CAP):
                m.d.comb += [swr.en.eq(1), swr.addr.eq(Mux(acc_half, CAP, 0) + scount),
                             swr.data.eq(Cat(offset[:8], si.as_unsigned()))]
                m.d.sync += scount.eq(scount + 1)
            with m.Else():
                m.d.comb += inc["spikes_dropped"].eq(1)
                m.d.sync += sdrop.eq(Mux(sdrop == 0xFFFF, sdrop, sdrop + 1))
        with m.If(self.sweep_done & ~closing):
            m.d.sync += in_batch.eq(in_batch + 1)
            with m.If(last_of_batch):
                m.d.sync += [closing.eq(1), drain.eq(7)]
        with m.If(closing):
            m.d.sync += drain.eq(drain - 1)
            done = (drain == 0) | (sv & next_batch)
            with m.If(done):
                m.d.sync += [closing.eq(0), in_batch.eq(0), scount.eq(0), sdrop.eq(0),
                             bt.eq(bt + in_batch)]
                with m.If(~half_pending.bit_select(acc_half, 1)):
                    m.d.sync += [half_pending.bit_select(acc_half, 1).eq(1),
                                 half_tick[acc_half].eq(bt), half_count[acc_half].eq(scount),
                                 half_drop[acc_half].eq(sdrop),
                                 half_sweeps[acc_half].eq(in_batch),
                                 acc_half.eq(~acc_half)]
                with m.Else():
                    m.d.comb += inc["batches_dropped"].eq(1)

        # --- transmit: frame builder and COBS encoder -------------------------------------
        m.submodules.tmem = tmem = Memory(shape=8, depth=MAX_FRAME, init=[])
        twr, trd = tmem.write_port(), tmem.read_port()
        # the frame RAM's output registered once more before the encoder decides on it (a
        # block RAM's clock-to-output would start those paths): a read takes two cycles
        tdat = Signal(8)
        m.d.sync += tdat.eq(trd.data)
        srd = smem.read_port()
        # the spike RAM's output registered once more (as the frame RAM's below): a spike
        # is read in two cycles
        sdat = Signal(24)
        m.d.sync += sdat.eq(srd.data)
        tx_half = Signal()
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
        # selections by explicit multiplexers (continuous assignments in the Verilog)
        h_tick = Mux(tx_half, half_tick[1], half_tick[0])
        h_count = Mux(tx_half, half_count[1], half_count[0])
        h_drop = Mux(tx_half, half_drop[1], half_drop[0])
        h_sweeps = Mux(tx_half, half_sweeps[1], half_sweeps[0])
        cur_tick = Mux(kind_spikes, h_tick, S)
        # payload bytes: the spike header and three bytes per spike, or the counters
        tx_len = Mux(kind_spikes, SPIKE_HEADER + (h_count << 1) + h_count,
                     4 * len(COUNTER_NAMES))
        head = [Const(VERSION, 8), Mux(kind_spikes, MSG_SPIKES, MSG_COUNTERS), tx_seq,
                tx_len[0:8], cur_tick[0:8], cur_tick[8:16], cur_tick[16:24], cur_tick[24:32]]
        head_spk = [h_drop[0:8], h_drop[8:16], h_sweeps]
        ctr_all = Cat(*[Cat(ctr[n], Const(0, 32 - cw)) for n in COUNTER_NAMES])
        hi = Signal(range(4 * len(COUNTER_NAMES)))       # byte index after the header
        m.d.comb += srd.addr.eq(Mux(tx_half, CAP, 0) + k)
        push = Signal()
        # room for a byte, registered (at most one byte is pushed per two cycles, so a margin
        # of two entries covers the cycle of latency); the encoder waits on it
        room = Signal()
        m.d.sync += room.eq(txf.w_level < lc.tx_fifo_depth - 2)
        m.d.comb += [txf.w_en.eq(push & room)]

        with m.FSM(name="tx_fsm") as tx_fsm:
            with m.State("IDLE"):
                m.d.sync += [j.eq(0), k.eq(0), tcrc.eq(CRC_INIT), hi.eq(0), cb.eq(0)]
                with m.If(half_pending.bit_select(tx_half, 1)):
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
                    m.d.comb += [put.eq(1), pbyte.eq(ctr_all.word_select(hi, 8))]
                    with m.If(j == HEADER_BYTES + 4 * len(COUNTER_NAMES) - 1):
                        m.next = "CRC_WAIT"
            with m.State("SPK_READ"):
                with m.If(k == h_count):
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
            with m.State("SCAN"):
                m.next = "SCAN_RD"
            with m.State("SCAN_RD"):
                m.next = "SCAN_CHK"
            with m.State("SCAN_CHK"):
                with m.If((p < L) & (tdat != 0) & (code != 255)):
                    m.d.sync += [p.eq(p + 1), code.eq(code + 1)]
                    m.next = "SCAN"
                with m.Else():
                    m.d.sync += [zero_end.eq((p < L) & (tdat == 0) & (code != 255)),
                                 q.eq(start)]
                    m.next = "CODE"
            with m.State("CODE"):
                m.d.comb += [push.eq(1), txf.w_data.eq(code)]
                with m.If(room):
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
                m.d.comb += [push.eq(1), txf.w_data.eq(tdat)]
                with m.If(room):
                    m.d.sync += q.eq(q + 1)
                    m.next = "EMIT_RD"
            with m.State("DELIM"):
                m.d.comb += [push.eq(1), txf.w_data.eq(0)]
                with m.If(room):
                    m.d.sync += tx_seq.eq(tx_seq + 1)
                    with m.If(kind_spikes):
                        m.d.sync += [half_pending.bit_select(tx_half, 1).eq(0),
                                     tx_half.eq(~tx_half)]
                    m.next = "IDLE"
        # frame RAM ports as continuous assignments (see rx_fifo.r_en above)
        crc_st = tx_fsm.ongoing("CRC")
        m.d.comb += [
            twr.en.eq(put_r | crc_st), twr.addr.eq(Mux(crc_st, j, jw)),
            twr.data.eq(Mux(crc_st, ~tcrc.word_select(cb, 8), pbyte_r)),
            trd.addr.eq(Mux(tx_fsm.ongoing("EMIT_RD") | tx_fsm.ongoing("EMIT_WAIT")
                            | tx_fsm.ongoing("EMIT"), q, p)),
        ]
        return m


class LinkedCore(wiring.Component):
    """An Izhikevich core (or, with ``lcfg.n_cores > 1``, an :class:`~cuneate.hdl.izhikevich
    .array.IzhikevichArray` over global ids) behind a :class:`HostLink`: the pins are ``rx``
    and ``tx``; status outputs ``running`` and ``overflow`` (core spike FIFO or overrun flag)
    for LEDs. The two parts are the attributes ``core`` and ``link``."""

    def __init__(self, lcfg: LinkConfig):
        self._MustUse__silence = True           # until checked: a refused top is never used
        if not isinstance(lcfg.core, IzhikevichConfig):
            raise ConfigError(f"a linked core is an Izhikevich core (a LIF core's board top is "
                              f"LinkedLif), not {type(lcfg.core).__name__}")
        if lcfg.fanout is not None:
            raise ConfigError("a link with a channel fan-out writes channel samples: its board "
                              "top is LinkedFanoutCore")
        self._MustUse__silence = False
        self.lcfg = lcfg
        super().__init__({"rx": In(1, init=1), "tx": Out(1, init=1), "running": Out(1),
                          "overflow": Out(1)})
        # built here so that a simulation can watch the writes toward the core
        self.core = IzhikevichArray(lcfg.core, lcfg.n_cores, neuron_sets=lcfg.neuron_sets) \
            if lcfg.n_cores > 1 else \
            IzhikevichCore(lcfg.core)
        self.link = HostLink(lcfg)

    def elaborate(self, platform):
        return linked_core_module(self, self.core, self.link)


def link_core_wiring(top, core, link) -> list:
    """The connections every board top of one time-multiplexed core behind a
    :class:`HostLink` shares: the pins, the tick, the spike stream and ``sweep_done`` (the
    core's ports of :mod:`cuneate.hdl.lib.bookkeeping`); the host write port, ``core_busy`` and
    the status pins are the top's own."""
    return [
        link.rx.eq(top.rx), top.tx.eq(link.tx), top.running.eq(link.running),
        core.tick.eq(link.tick),
        link.spike_valid.eq(core.spike_valid), core.spike_ready.eq(link.spike_ready),
        link.spike_index.eq(core.spike_index), link.spike_sweep.eq(core.spike_sweep),
        link.sweep_done.eq(core.sweep_done),
    ]


def linked_core_module(top, core, link) -> Module:
    """``core`` behind ``link`` as the board top ``top``: the link writes the core's currents,
    waits on its ``busy``, and ``overflow`` is its spike FIFO or overrun flag
    (:class:`LinkedCore`, :class:`~cuneate.hdl.link.LinkedLif`)."""
    m = Module()
    m.submodules.core = core
    m.submodules.link = link
    m.d.comb += link_core_wiring(top, core, link) + [
        top.overflow.eq(core.spike_overflow | core.overrun),
        core.i_wr_en.eq(link.i_wr_en), core.i_wr_addr.eq(link.i_wr_addr),
        core.i_wr_data.eq(link.i_wr_data), link.core_busy.eq(core.busy),
    ]
    return m


def link_verilog(lcfg: LinkConfig, name: str = "linked_core", lowered: bool = False) -> str:
    """Verilog of :class:`LinkedCore`; ``lowered`` gives the yosys-lowered netlist for Icarus 11
    (see :func:`cuneate.hdl.flow.verilog.lowered_verilog`: it mis-schedules some combinational
    processes of the link's transmit FSM in the direct output)."""
    return verilog_text(LinkedCore(lcfg), name, lowered)
