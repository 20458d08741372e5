"""The channel fan-out's RTL: channel samples in, every afferent's current out to a core's
current memory, and its Verilog.

Per run, for afferent ``n = 0 .. n_neurons - 1`` (configuration and formats:
:class:`~cuneate.hdl.fanout.config.FanoutConfig`)::

    entry = table[n]                                (channel, gain, threshold, mode, gate)
    s     = samples[entry.channel]
    I_n   = to_current(product(rectify_gate(s, ...), entry.gain))

The host writes channel samples (``ch_wr_valid`` / ``ch_wr_ready``, ``ch_wr_addr``,
``ch_wr_data``, raw in the sample format) into a channel memory; ``start`` runs the table over
them. The table is a ROM in block RAM, one word per afferent (it is part of the bitstream).

Schedule: a five-stage pipeline, one afferent per cycle. Cycle 1 issues the table read of
afferent ``n``; cycle 2 has its entry and issues the channel read; cycle 3 rectifies and gates
the sample (:func:`~cuneate.hdl.fanout.datapath.rectify_gate`); cycle 4 multiplies
(:func:`~cuneate.hdl.fanout.datapath.product`); cycle 5 rounds and clamps
(:func:`~cuneate.hdl.fanout.datapath.to_current`), and ``i_wr_en`` / ``i_wr_addr`` /
``i_wr_data`` carry the current on the next cycle: the host write port of an Izhikevich or LIF
core. A run writes every afferent once, in order, and takes ``n_neurons + 5`` cycles from
``start`` to ``done`` (one cycle, with the last write).

Channel writes are refused while a run is in flight (``ch_wr_ready`` low, the writer holds
them), so a run reads exactly the samples written before its ``start``; a ``start`` during a
run is ignored and counted in ``overrun_count``, never silently merged. Clamps that act are
counted per kind (``clamp_low_count``, ``clamp_high_count``) and set the sticky
``clamp_flags`` (cleared by ``clamp_clear``).
"""

from __future__ import annotations

from amaranth import Cat, Module, Signal, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..flow.verilog import verilog_text, write_block
from .config import CLAMP_KINDS, FanoutConfig
from .datapath import product, rectify_gate, to_current

__all__ = ["ChannelFanout", "fanout_verilog", "generate_fanout", "COUNTER_BITS"]

COUNTER_BITS = 32


class ChannelFanout(wiring.Component):
    """The channel fan-out as RTL (see the module docstring for the schedule and the ports).

    Its three stages are the methods :meth:`rectify_gate`, :meth:`product` and
    :meth:`to_current` (the datapath's functions): the hooks through which a proof takes the
    arithmetic the pipeline composes, and a subclass replaces one (a fault the proof must
    catch, :mod:`cuneate.hdl.fanout.formal`).
    """

    #: the ports' meanings, for the Verilog's header (:func:`~cuneate.hdl.flow.verilog
    #: .verilog_header`)
    PORT_MEANINGS = {
        "ch_wr_valid": "channel sample write: valid", "ch_wr_ready": "ready (low during a run)",
        "ch_wr_addr": "the channel", "ch_wr_data": "its sample, raw in the sample format",
        "start": "run the table over the samples written", "i_wr_en": "to the core: write",
        "i_wr_addr": "to the core: the afferent",
        "i_wr_data": "to the core: its current, raw in the current format",
        "done": "pulse with a run's last write", "run_count": "runs started",
        "overrun_count": "starts ignored during a run", "clamp_low_count": "low clamps",
        "clamp_high_count": "high clamps"}

    def __init__(self, cfg: FanoutConfig):
        self.cfg = cfg
        S, I = cfg.S, cfg.I
        super().__init__({
            "ch_wr_valid": In(1), "ch_wr_ready": Out(1), "ch_wr_addr": In(cfg.chan_bits),
            "ch_wr_data": In(S.shape()), "start": In(1),
            "i_wr_en": Out(1), "i_wr_addr": Out(cfg.neuron_bits), "i_wr_data": Out(I.shape()),
            "busy": Out(1), "done": Out(1),
            "run_count": Out(COUNTER_BITS), "overrun_count": Out(COUNTER_BITS),
            "clamp_low_count": Out(COUNTER_BITS), "clamp_high_count": Out(COUNTER_BITS),
            "clamp_flags": Out(len(CLAMP_KINDS)), "clamp_clear": In(1),
        })

    @staticmethod
    def rectify_gate(s, mode, gated, theta):
        """Stage 3: :func:`~cuneate.hdl.fanout.datapath.rectify_gate`."""
        return rectify_gate(s, mode, gated, theta)

    @staticmethod
    def product(r, g):
        """Stage 4: :func:`~cuneate.hdl.fanout.datapath.product`."""
        return product(r, g)

    @staticmethod
    def to_current(cfg: FanoutConfig, p):
        """Stage 5: :func:`~cuneate.hdl.fanout.datapath.to_current`."""
        return to_current(cfg, p)

    def elaborate(self, platform):
        cfg = self.cfg
        m = Module()
        N, S = cfg.n_neurons, cfg.S
        m.submodules.table = table = Memory(shape=unsigned(cfg.entry_width), depth=N,
                                            init=cfg.table())
        m.submodules.samples = samples = Memory(shape=S.shape(), depth=cfg.n_channels, init=[])
        tab_rd = table.read_port()
        ch_rd, ch_wr = samples.read_port(), samples.write_port()

        # channel writes: only between runs
        m.d.comb += [self.ch_wr_ready.eq(~self.busy),
                     ch_wr.addr.eq(self.ch_wr_addr), ch_wr.data.eq(self.ch_wr_data),
                     ch_wr.en.eq(self.ch_wr_valid & self.ch_wr_ready)]

        # stage 1: issue afferent n
        n = Signal(range(max(N, 2)))
        issuing = Signal()
        m.d.comb += tab_rd.addr.eq(n)
        with m.If(issuing):
            with m.If(n == N - 1):
                m.d.sync += [issuing.eq(0), n.eq(0)]
            with m.Else():
                m.d.sync += n.eq(n + 1)
        with m.Elif(self.start & ~self.busy):
            m.d.sync += [issuing.eq(1), n.eq(0), self.run_count.eq(self.run_count + 1)]
        with m.If(self.start & self.busy):
            m.d.sync += self.overrun_count.eq(self.overrun_count + 1)

        # stage 2: the entry; issue the channel read
        v1, n1 = Signal(), Signal.like(n)
        m.d.sync += [v1.eq(issuing), n1.eq(n)]
        fields, pos = {}, 0
        for name, w in cfg.entry_fields:
            fields[name] = tab_rd.data[pos:pos + w]
            pos += w
        m.d.comb += ch_rd.addr.eq(fields["channel"])
        v2, n2 = Signal(), Signal.like(n)
        g2 = Signal(signed(cfg.gain_width))
        theta2, mode2, gated2 = Signal(S.shape()), Signal(2), Signal()
        m.d.sync += [v2.eq(v1), n2.eq(n1), g2.eq(fields["gain"].as_signed()),
                     theta2.eq(fields["theta"].as_signed()), mode2.eq(fields["mode"]),
                     gated2.eq(fields["gated"])]

        # stage 3: rectify and gate the sample
        s = ch_rd.data.as_signed() if S.signed else ch_rd.data
        r = self.rectify_gate(s, mode2, gated2, theta2)
        v3, n3 = Signal(), Signal.like(n)
        r3 = Signal(signed(cfg.r_width))
        g3 = Signal.like(g2)
        m.d.sync += [v3.eq(v2), n3.eq(n2), r3.eq(r), g3.eq(g2)]

        # stage 4: the product
        p = self.product(r3, g3)
        v4, n4 = Signal(), Signal.like(n)
        p4 = Signal(signed(cfg.p_width))
        m.d.sync += [v4.eq(v3), n4.eq(n3), p4.eq(p)]

        # stage 5: round, clamp (flagged), write the current
        cur, below, above = self.to_current(cfg, p4)
        m.d.sync += [self.i_wr_en.eq(v4), self.i_wr_addr.eq(n4), self.i_wr_data.eq(cur),
                     self.done.eq(v4 & (n4 == N - 1))]
        with m.If(v4):
            m.d.sync += [self.clamp_low_count.eq(self.clamp_low_count + below),
                         self.clamp_high_count.eq(self.clamp_high_count + above)]
        flags = Cat(below, above)
        with m.If(self.clamp_clear):
            m.d.sync += self.clamp_flags.eq(0)
        with m.Elif(v4):
            m.d.sync += self.clamp_flags.eq(self.clamp_flags | flags)
        m.d.comb += self.busy.eq(issuing | v1 | v2 | v3 | v4)
        return m


def fanout_verilog(cfg: FanoutConfig, name: str = "channel_fanout", lowered: bool = False) -> str:
    """Verilog of the fan-out (deterministic bytes); ``lowered``: the yosys-lowered netlist
    Icarus 11 simulates (see :func:`cuneate.hdl.flow.verilog.lowered_verilog`)."""
    return verilog_text(ChannelFanout(cfg), name, lowered)


def generate_fanout(out, cfg: FanoutConfig, name: str = "channel_fanout") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json`` (formats, gains and their errors, latency,
    ports, table size); returns the paths."""
    return write_block(out, ChannelFanout(cfg), cfg.to_dict(), name)
