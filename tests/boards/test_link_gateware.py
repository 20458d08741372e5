"""The link gateware in the Amaranth simulator, bytes in and out through its UART pins.

The host codec encodes the frames; a bit-level UART model drives ``rx`` and decodes ``tx``;
the device's answers are compared frame for frame with :class:`LinkModel` (the bit-exact twin
behind the same protocol rules), and every injected fault must show up in the right counter.
"""

import numpy as np
import pytest
from amaranth.sim import Simulator

from cuneate.hdl.link import LinkedCore, link_config
from cuneate.hdl.link.codec import (COUNTER_NAMES, MSG_COUNTERS, MSG_SPIKES, OP_CLEAR_COUNTERS,
                                    OP_READ_COUNTERS, OP_STEP, FrameDecoder, LinkModel,
                                    Message, cobs_encode, control_message, encode_frame,
                                    parse_counters, parse_spikes, write_message)

CPB = 4
CORE = dict(n_neurons=8, clock_hz=16e3 * 32, update_hz=16e3, spike_fifo_depth=16)


def lcfg():
    return link_config(CORE, clocks_per_bit=CPB, batch_sweeps=32, batch_capacity=40)


def run_link(chunks, total_cycles, lc):
    """Send each ``(bytes, gap_cycles)`` chunk over rx; return every byte seen on tx."""
    dut = LinkedCore(lc)
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    received = bytearray()

    async def host(ctx):
        ctx.set(dut.rx, 1)
        await ctx.tick().repeat(20)
        for data, gap in chunks:
            for b in data:
                for bit in [0] + [(b >> i) & 1 for i in range(8)] + [1]:
                    ctx.set(dut.rx, bit)
                    await ctx.tick().repeat(CPB)
            if gap:
                await ctx.tick().repeat(gap)

    async def monitor(ctx):
        while True:
            await ctx.tick()
            if ctx.get(dut.tx):
                continue
            await ctx.tick().repeat(CPB // 2 - 1)
            b = 0
            for i in range(8):
                await ctx.tick().repeat(CPB)
                b |= ctx.get(dut.tx) << i
            await ctx.tick().repeat(CPB)
            assert ctx.get(dut.tx) == 1, "stop bit"
            received.append(b)

    sim.add_testbench(host)
    sim.add_testbench(monitor, background=True)
    sim.run_until(total_cycles * 1e-6)
    return bytes(received)


def test_currents_in_spikes_out_and_every_fault_counted():
    lc = lcfg()
    rng = np.random.default_rng(5)
    I = lc.core.I
    cur0 = I.to_raw(rng.uniform(5.0, 40.0, 8))
    cur1 = I.to_raw(rng.uniform(0.0, 60.0, 8))
    W = lc.current_width
    good = [encode_frame(write_message(0, 0, 0, cur0, W)),
            encode_frame(control_message(1, OP_STEP, 96)),
            encode_frame(write_message(2, 64, 2, cur1[2:7], W))]
    # faults, after the step has finished (sweep 96)
    bad_crc = bytearray(write_message(3, 200, 0, cur0, W).raw())
    bad_crc[9] ^= 0x10                                             # one bit: CRC must see it
    bad_crc = cobs_encode(bytes(bad_crc)) + b"\x00"
    truncated = cobs_encode(write_message(4, 200, 0, cur0, W).raw())[:9] + b"\x00"
    late = encode_frame(write_message(6, 10, 0, cur0, W))          # seq 5 missing: gap 1
    beyond = encode_frame(write_message(7, 97, 6, cur0[:3], W))    # neurons 6..8 of 8
    runt = encode_frame(Message(0x01, 8, 0, b""))                  # too short for a write
    unknown = encode_frame(Message(0x33, 9, 0, b"\x01"))
    read = encode_frame(control_message(10, OP_READ_COUNTERS))
    chunks = [(good[0], 10), (good[1], 10), (good[2], 7000),
              (bad_crc, 20), (truncated, 20), (late, 20), (beyond, 20), (runt, 20),
              (unknown, 20), (read, 2000)]
    out = run_link(chunks, 26000, lc)

    dec = FrameDecoder()
    msgs = dec.feed(out)
    assert dec.errors == {"framing": 0, "crc": 0, "length": 0}
    assert [m.seq for m in msgs] == list(range(len(msgs)))
    spikes = [m for m in msgs if m.type == MSG_SPIKES]
    counters = [m for m in msgs if m.type == MSG_COUNTERS]
    assert len(counters) == 1 and msgs[-1].type == MSG_COUNTERS

    # the spike frames equal the model's, byte for byte
    model = LinkModel(lc)
    ref = model.feed(b"".join(good))
    model.advance(96)
    ref += model.feed(b"")
    ref_msgs = FrameDecoder().feed(ref)
    assert [(m.tick, m.payload) for m in spikes] == [(m.tick, m.payload) for m in ref_msgs]
    assert [m.tick for m in spikes] == [0, 32, 64]
    got = [s for m in spikes for s in parse_spikes(m)[2]]
    assert len(got) > 5

    # and the model's spikes are the twin's with the currents switched at sweep 64
    from cuneate.hdl.izhikevich import IzhikevichTwin
    twin = IzhikevichTwin(lc.core)
    twin.I[:] = cur0
    expect = []
    for k in range(96):
        if k == 64:
            twin.I[2:7] = cur1[2:7]
        expect += [(k, int(n)) for n in np.flatnonzero(twin.sweep())]
    assert got == expect

    c = parse_counters(counters[0])
    assert counters[0].tick == 96
    # accepted: the three good frames, the late write (well formed, refused at its sweep) and
    # the read; seq 3 (CRC), 4 (truncated) and 5 (never sent) are missing before seq 6
    assert c == dict({n: 0 for n in COUNTER_NAMES}, frames_ok=5, crc_errors=1,
                     framing_errors=1, length_errors=2, seq_gaps=3, late_writes=1,
                     range_errors=1)
    # the model counts the same faults
    model.feed(b"".join(x for x, _ in chunks[3:]))
    assert model.counters == c
