"""The link's spike batcher: the payload's spike stream in, batches of ``batch_sweeps``
sweeps out (:class:`SpikeBatcher`).

Spikes go into one of two buffers of ``batch_capacity`` entries (ping-pong): one accumulates
while the other is sent. A batch closes after ``batch_sweeps`` sweeps (counted on
``sweep_done``), or at the end of a step (the tick generator stopped after the last sweep
started), and is offered on ``batch`` (its first sweep, spikes, spikes dropped, sweeps),
empty or not, until the sender takes it (``ready``: the frame is sent); its spikes are read
through ``spike_addr``/``spike_data`` (``offset u8`` from the batch's first sweep, then the
id). A spike that does not fit is counted in the batch and pulses ``count_spikes_dropped``; a
batch that closes while both buffers are busy is dropped whole (``count_batches_dropped``:
the host sees the gap in sweeps). The spike stream is registered once before the batch logic
(a core's spike FIFO is a block RAM with a slow clock-to-output); a spike of the next batch
waits there until the batch has closed.
"""

from __future__ import annotations

from amaranth import Array, Cat, Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..lib.payload import SPIKES_SETTLE, spike_layout
from .config import LinkConfig

__all__ = ["SpikeBatcher", "batch_layout"]

#: cycles a batch waits after its last sweep's ``sweep_done`` for spikes still on their way
DRAIN_CYCLES = SPIKES_SETTLE


def batch_layout(lcfg: LinkConfig) -> data.StructLayout:
    return data.StructLayout({"tick": 32, "count": range(lcfg.batch_capacity + 1),
                              "drop": 16, "sweeps": 8})


class SpikeBatcher(wiring.Component):
    """See the module docstring; ``free``, ``steps``, ``pending`` and ``sweeps_started`` are
    the tick generator's."""

    def __init__(self, lcfg: LinkConfig):
        self.lcfg = lcfg
        cap = lcfg.batch_capacity
        super().__init__({
            "spikes": In(stream.Signature(spike_layout(lcfg.info))),
            "sweep_done": In(1), "free": In(1), "steps": In(32), "pending": In(1),
            "sweeps_started": In(32),
            "batch": Out(stream.Signature(batch_layout(lcfg))),
            "spike_addr": In(range(cap)), "spike_data": Out(24),
            "count_spikes_dropped": Out(1), "count_batches_dropped": Out(1),
        })

    def elaborate(self, platform):
        lc = self.lcfg
        B, CAP, sw = lc.batch_sweeps, lc.batch_capacity, lc.info.sweep_width
        m = Module()
        m.submodules.smem = smem = Memory(shape=24, depth=2 * CAP, init=[])
        swr, srd = smem.write_port(), smem.read_port()
        acc_half, tx_half = Signal(), Signal()
        scount = Signal(range(CAP + 1))
        sdrop = Signal(16)
        bt = Signal(32)                                    # first sweep of the current batch
        in_batch = Signal(range(B + 1))                    # sweeps of the batch done
        closing = Signal()
        drain = Signal(range(DRAIN_CYCLES + 1))
        half_pending = Signal(2)
        half_tick = Array(Signal(32, name=f"half_tick{i}") for i in range(2))
        half_count = Array(Signal(range(CAP + 1), name=f"half_count{i}") for i in range(2))
        half_drop = Array(Signal(16, name=f"half_drop{i}") for i in range(2))
        half_sweeps = Array(Signal(8, name=f"half_sweeps{i}") for i in range(2))
        sv, si = Signal(), Signal(range(max(lc.info.n_spike_ids, 2)))
        ss = Signal(sw)
        offset = Signal(sw)
        m.d.comb += offset.eq(ss - bt[:sw])
        next_batch = offset >= B
        # a step's end closes the batch at the sweep_done of the last sweep started: when the
        # ticks come as fast as the sweeps (cycles per tick near the block's work) the step's
        # last tick goes before the previous sweep is done
        last_started = (bt + in_batch + 1)[:32] == self.sweeps_started
        last_of_batch = (in_batch == B - 1) | \
            (~self.free & (self.steps == 0) & ~self.pending & last_started)
        sp = self.spikes
        m.d.comb += sp.ready.eq(~sv | ~next_batch)
        with m.If(sp.ready):
            m.d.sync += [sv.eq(sp.valid), si.eq(sp.payload.index), ss.eq(sp.payload.sweep)]
        with m.If(sv & ~next_batch):
            with m.If(scount < CAP):
                m.d.comb += [swr.en.eq(1), swr.addr.eq(Mux(acc_half, CAP, 0) + scount),
                             swr.data.eq(Cat(offset[:8], si.as_unsigned()))]
                m.d.sync += scount.eq(scount + 1)
            with m.Else():
                m.d.comb += self.count_spikes_dropped.eq(1)
                m.d.sync += sdrop.eq(Mux(sdrop == 0xFFFF, sdrop, sdrop + 1))
        with m.If(self.sweep_done & ~closing):
            m.d.sync += in_batch.eq(in_batch + 1)
            with m.If(last_of_batch):
                m.d.sync += [closing.eq(1), drain.eq(DRAIN_CYCLES)]
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
                    m.d.comb += self.count_batches_dropped.eq(1)
        # the batch on offer: the next buffer to send, in order
        b = self.batch
        m.d.comb += [
            b.valid.eq(half_pending.bit_select(tx_half, 1)),
            b.payload.tick.eq(Mux(tx_half, half_tick[1], half_tick[0])),
            b.payload.count.eq(Mux(tx_half, half_count[1], half_count[0])),
            b.payload.drop.eq(Mux(tx_half, half_drop[1], half_drop[0])),
            b.payload.sweeps.eq(Mux(tx_half, half_sweeps[1], half_sweeps[0])),
            srd.addr.eq(Mux(tx_half, CAP, 0) + self.spike_addr),
            self.spike_data.eq(srd.data),
        ]
        with m.If(b.valid & b.ready):
            m.d.sync += [half_pending.bit_select(tx_half, 1).eq(0), tx_half.eq(~tx_half)]
        return m
