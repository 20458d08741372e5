"""The link gateware in the Amaranth simulator, bytes in and out through its UART pins.

The host codec encodes the frames; a bit-level UART model drives ``rx`` and decodes ``tx``;
the device's answers are compared frame for frame with :class:`LinkModel` (the bit-exact twin
behind the same protocol rules), and every injected fault must show up in the right counter.
"""

import numpy as np
import pytest
from amaranth.sim import Simulator
from link_expect import model_frames, twin_spikes

from cuneate.hdl.link import LinkedTop, link_config
from cuneate.hdl.link.codec import (COUNTER_NAMES, MSG_COUNTERS, MSG_SPIKES, OP_READ_COUNTERS, OP_STEP, FrameDecoder, Message,
                                    cobs_encode, control_message, encode_frame, parse_counters,
                                    parse_spikes, write_message)
from cuneate.hdl.link.twin import LinkModel

CPB = 4
CORE = dict(n_neurons=8, clock_hz=16e3 * 32, update_hz=16e3, spike_fifo_depth=16)


def lcfg():
    return link_config(CORE, clocks_per_bit=CPB, batch_sweeps=32, batch_capacity=40)


def run_uart(lc, chunks, total_cycles=None, tail_cycles=0):
    """Send each ``(bytes, gap_cycles)`` chunk over rx, 8N1 bit by bit, to the link's
    ``LinkedTop``; run ``total_cycles`` (or until the chunks and ``tail_cycles`` are done).
    Returns every byte seen on tx and every ``(neuron, raw current)`` the link wrote toward the
    core, in order."""
    dut = LinkedTop(lc)
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    received, writes = bytearray(), []

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
        if tail_cycles:
            await ctx.tick().repeat(tail_cycles)

    async def watch_writes(ctx):
        # the write stream's registers change only at clock edges, and the address steps on
        # every write of a burst: each change with valid set is one write (the core takes
        # every write offered)
        w = dut.link.payload.write
        mask = (1 << lc.current_width) - 1
        async for valid, p in ctx.changed(w.valid, w.payload):
            if valid:
                writes.append((p.addr, p.value & mask))

    async def monitor(ctx):
        while True:
            await ctx.negedge(dut.tx)
            await ctx.tick().repeat(CPB // 2)
            b = 0
            for i in range(8):
                await ctx.tick().repeat(CPB)
                b |= ctx.get(dut.tx) << i
            await ctx.tick().repeat(CPB)
            assert ctx.get(dut.tx) == 1, "stop bit"
            received.append(b)

    sim.add_testbench(host, background=total_cycles is not None)
    sim.add_testbench(watch_writes, background=True)
    sim.add_testbench(monitor, background=True)
    if total_cycles is None:
        sim.run()
    else:
        sim.run_until(total_cycles * 1e-6)
    return bytes(received), writes


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
    truncated = cobs_encode(write_message(4, 200, 0, cur0, W).raw())[:12] + b"\x00"  # in a block
    late = encode_frame(write_message(6, 10, 0, cur0, W))          # seq 5 missing: gap 1
    beyond = encode_frame(write_message(7, 97, 6, cur0[:3], W))    # neurons 6..8 of 8
    runt = encode_frame(Message(0x01, 8, 0, b""))                  # too short for a write
    unknown = encode_frame(Message(0x33, 9, 0, b"\x01"))
    other_version = encode_frame(write_message(10, 200, 0, cur0, W), version=2)  # intact
    read = encode_frame(control_message(11, OP_READ_COUNTERS))
    chunks = [(good[0], 10), (good[1], 10), (good[2], 7000),
              (bad_crc, 20), (truncated, 20), (late, 20), (beyond, 20), (runt, 20),
              (unknown, 20), (other_version, 20), (read, 2000)]
    out, _ = run_uart(lc, chunks, 26000)

    dec = FrameDecoder()
    msgs = dec.feed(out)
    assert dec.errors == {"framing": 0, "crc": 0, "length": 0, "version": 0}
    assert [m.seq for m in msgs] == list(range(len(msgs)))
    spikes = [m for m in msgs if m.type == MSG_SPIKES]
    counters = [m for m in msgs if m.type == MSG_COUNTERS]
    assert len(counters) == 1 and msgs[-1].type == MSG_COUNTERS

    # the spike frames equal the model's, byte for byte
    model = LinkModel(lc)
    assert [(m.tick, m.payload) for m in spikes] == model_frames(model, good, 96)
    assert [m.tick for m in spikes] == [0, 32, 64]
    got = [s for m in spikes for s in parse_spikes(m)[2]]
    assert len(got) > 5

    # and the model's spikes are the twin's with the currents switched at sweep 64
    assert got == twin_spikes(lc.core, cur0, cur1, slice(2, 7), 64, 96)

    c = parse_counters(counters[0])
    assert counters[0].tick == 96
    # accepted: the three good frames, the late write (well formed, refused at its sweep) and
    # the read; seq 3 (CRC), 4 (truncated) and 5 (never sent) are missing before seq 6, and
    # seq 10 (another format version) before the read
    assert c == dict({n: 0 for n in COUNTER_NAMES}, frames_ok=5, crc_errors=1,
                     framing_errors=1, length_errors=2, version_errors=1, seq_gaps=4,
                     late_writes=1, range_errors=1)
    # the model counts the same faults
    model.feed(b"".join(x for x, _ in chunks[3:]))
    assert model.counters == c


# ----------------------------------------------------------------------------------------------
# Damaged frames on the gateware: every one counted, none accepted, no current changed

ERR_CORE = dict(n_neurons=80, clock_hz=16e3 * 96, update_hz=16e3, spike_fifo_depth=16)


# the structured damages in the default lane, the random sample in the long lane
@pytest.mark.parametrize("structured", [True, pytest.param(False, marks=pytest.mark.long)],
                         ids=["structured", "sampled"])
def test_damaged_frames_are_counted_never_accepted(structured):
    """Every damaged frame is refused, every damaged run (a damaged delimiter merges a frame
    with the next) counted exactly once, as the split of the stream at its zero bytes says;
    intact frames are accepted, and the core receives exactly the intact frames' currents.
    Structured: every bit of the first and last code bytes and the delimiter of a frame that
    ends in 0x00 (the truncating flip among them) and the 254-byte one-block frame; sampled:
    four of every corruption class (:data:`~cuneate.sim.link.faults.KINDS`)."""
    import random
    from cuneate.sim.link.faults import fault_plan, plan_outcome
    lc = link_config(ERR_CORE, clocks_per_bit=CPB, batch_sweeps=16, batch_capacity=20)
    if structured:
        plan = fault_plan(lc.current_width, lc.core.n_neurons, random.Random("amaranth"),
                          per_kind=0, code_bytes=("first", "last", "delimiter"),
                          big_frames=True)
    else:
        plan = fault_plan(lc.current_width, lc.core.n_neurons, random.Random("amaranth"),
                          per_kind=4)
    stream = b"".join(p.wire for p in plan)
    arrived, damaged_runs = plan_outcome(plan)
    n_bad = sum(p.msg is None for p in plan)
    out, writes = run_uart(lc, [(stream, 0)], tail_cycles=3000)

    dec = FrameDecoder()
    msgs = dec.feed(out)
    assert sum(dec.errors.values()) == 0
    assert [m.type for m in msgs] == [MSG_COUNTERS]
    c = parse_counters(msgs[0])
    assert msgs[0].tick == 0                      # no damaged STEP or START ran the core
    refused = sum(c[k] for k in ("framing_errors", "crc_errors", "length_errors",
                                 "version_errors"))
    assert refused == damaged_runs and c["version_errors"] == 1
    assert c["frames_ok"] == len(arrived) > 10
    assert c["range_errors"] == c["late_writes"] == c["rx_overflows"] == 0
    assert c["frames_ok"] + c["seq_gaps"] == len(plan)        # every lost frame a gap
    mask = (1 << lc.current_width) - 1                 # the write port is unsigned
    assert writes == [(n, v & mask) for p in arrived for n, v in p.writes]
    # the model counts the same
    model = LinkModel(lc)
    model.feed(stream)
    assert model.counters == c
    print(f"\nAmaranth {'structured' if structured else 'sampled'}: {n_bad} damaged frames "
          f"sent ({len(stream)} bytes), {damaged_runs} damaged runs, counted {refused} "
          f"({', '.join(f'{k}={c[k]}' for k in COUNTER_NAMES if c[k])}), 0 accepted")


# one set in the default lane, sets per core in the long lane
@pytest.mark.parametrize("per_core_sets", [False, pytest.param(True, marks=pytest.mark.long)],
                         ids=["one-set", "sets-per-core"])
def test_the_link_serves_an_array_of_cores(per_core_sets):
    """Two cores of 8 behind the link (global ids 0..15): currents written over the link
    reach the right core, and the spike frames carry, per sweep, exactly the model's spikes
    (between cores the stream's order is the array's arbitration, so each frame's spikes are
    compared as a set per sweep; docs/architecture.md). With sets per core (core 0 RS, core 1
    FS, from the link's ``neuron_sets``) the spikes are those of the model with the same sets,
    and not those of one set everywhere."""
    core = dict(CORE, param_sets=("RS", "FS")) if per_core_sets else CORE
    sets = [0] * 8 + [1] * 8 if per_core_sets else None
    lc = link_config(core, clocks_per_bit=CPB, batch_sweeps=32, batch_capacity=40, n_cores=2,
                     neuron_sets=sets)
    assert (lc.n_cores, lc.n_neurons) == (2, 16)
    rng = np.random.default_rng(9)
    cur = lc.core.I.to_raw(rng.uniform(5.0, 40.0, 16))
    W = lc.current_width
    good = [encode_frame(write_message(0, 0, 0, cur, W)),
            encode_frame(control_message(1, OP_STEP, 64))]
    out, _ = run_uart(lc, [(good[0], 10), (good[1], 6000)], 12000)
    msgs = [m for m in FrameDecoder().feed(out) if m.type == MSG_SPIKES]
    model = LinkModel(lc)
    ref = model.feed(b"".join(good))
    model.advance(64)
    ref += model.feed(b"")
    ref_msgs = FrameDecoder().feed(ref)
    assert [m.tick for m in msgs] == [m.tick for m in ref_msgs] == [0, 32]

    def spikes(ms):
        return [sorted(parse_spikes(m)[2]) for m in ms]
    got = spikes(msgs)
    assert got == spikes(ref_msgs) and sum(map(len, got)) > 10
    assert any(n >= 8 for frame in got for _, n in frame)     # the second core spoke
    if per_core_sets:
        one = LinkModel(link_config(core, clocks_per_bit=CPB, batch_sweeps=32,
                                    batch_capacity=40, n_cores=2))
        alike = one.feed(b"".join(good))
        one.advance(64)
        alike += one.feed(b"")
        assert spikes(FrameDecoder().feed(alike)) != got
