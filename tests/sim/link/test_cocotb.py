"""The host link on Icarus and Verilator: frames in through a UART model, spikes out.

The generated :class:`LinkedTop` Verilog (a core behind the link) receives host frames from cocotbext-uart. Checked:
the spike frames equal the protocol model's byte for byte and the twin's spikes with a current
change at its sweep; a corrupted, a truncated, a late, an out-of-range, a runt and an unknown
frame and a missing sequence number are each counted in the right counter; and a burst that
overruns the receive FIFO while a write waits for its sweep (back-pressure) is counted as
dropped bytes, with every frame it damaged missing from the accepted count (no silent loss);
and damaged frames of every corruption class (:mod:`cuneate.sim.link.faults`) are each
counted, never accepted, while the core's write port receives only intact currents; the
learning layer behind the link learns from a presentation sent as WRITE frames, its CN spikes
and the weights of its readout sweeps equal to its twin's (long lane, both simulators).
Icarus 11 runs the yosys-lowered netlist of the same design (``link_verilog(lowered=True)``):
it mis-schedules some combinational processes of the transmit FSM in the direct output.
"""

import json

import numpy as np
import pytest
from link_expect import model_frames, twin_spikes

from cuneate.hdl.izhikevich import IzhikevichTwin
from cuneate.hdl.link import LinkConfig, link_config, link_verilog
from cuneate.hdl.link.codec import (COUNTER_NAMES, MSG_COUNTERS, MSG_SPIKES, OP_READ_COUNTERS,
                                    OP_STEP, FrameDecoder, Message, cobs_encode,
                                    control_message, encode_frame, parse_counters, parse_spikes,
                                    write_message)
from cuneate.hdl.link.twin import LinkModel
from cuneate.hdl.plasticity.payload import weights_from_ids
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.plasticity.engines import face_schedule, run_learning
from learning_case import small_layer


CPB = 8
CPT = 240     # cycles per sweep: a 16-sweep batch lasts 3840 cycles, 48 bytes at 8 clocks/bit
CORE = dict(n_neurons=12, clock_hz=16e3 * CPT, update_hz=16e3, spike_fifo_depth=16)


def build(lc, build_dir, simulator):
    """Icarus 11 gets the yosys-lowered netlist (see :func:`link_verilog`)."""
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "linked_core.v"
    src.write_text(link_verilog(lc, "linked_core", lowered=simulator == "icarus"))
    return src


def play(simulator, lc, chunks, total_cycles, build_dir, watch_writes=False):
    src = build(lc, build_dir, simulator)
    from cuneate.hdl.lib.payload import write_layout
    layout = write_layout(lc.info)
    cfg = {"clocks_per_bit": CPB, "total_cycles": total_cycles, "watch_writes": watch_writes,
           "write_layout": {"addr_bits": layout["addr"].width,
                            "value_offset": layout["value"].offset,
                            "value_bits": layout["value"].width},
           "chunks": [[bytes(c).hex(), g] for c, g in chunks]}
    run = run_cocotb(simulator, [src], "linked_core", "cuneate.sim.link.bench",
                     build_dir, config=cfg, testcase="play")
    dec = FrameDecoder()
    msgs = dec.feed(bytes.fromhex(run.report["received"]))
    assert dec.errors == {"framing": 0, "crc": 0, "length": 0, "version": 0}
    assert [m.seq for m in msgs] == list(range(len(msgs)))   # device sequence unbroken
    return msgs, run.report


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_link_round_trip_and_faults(simulator, build_root):
    lc = link_config(CORE, clocks_per_bit=CPB, batch_sweeps=16, batch_capacity=60)
    rng = np.random.default_rng(8)
    W, N = lc.current_width, lc.core.n_neurons
    cur0 = lc.core.I.to_raw(rng.uniform(5.0, 50.0, N))
    cur1 = lc.core.I.to_raw(rng.uniform(0.0, 80.0, N))
    good = [encode_frame(write_message(0, 0, 0, cur0, W)),
            encode_frame(control_message(1, OP_STEP, 80)),
            encode_frame(write_message(2, 40, 3, cur1[3:10], W))]
    bad = bytearray(write_message(3, 500, 0, cur0, W).raw())
    bad[12] ^= 0x04
    faults = [cobs_encode(bytes(bad)) + b"\x00",                              # CRC
              cobs_encode(write_message(4, 500, 0, cur0, W).raw())[:7] + b"\x00",  # truncated
              encode_frame(write_message(6, 3, 0, cur0, W)),                  # gap 3, late
              encode_frame(write_message(7, 90, 10, cur0[:3], W)),            # 10..12 of 12
              encode_frame(Message(0x01, 8, 0, b"\x00")),                     # runt write
              encode_frame(Message(0x7E, 9, 0, b"")),                         # unknown type
              encode_frame(control_message(10, OP_READ_COUNTERS))]
    chunks = [(good[0], 0), (good[1], 0), (good[2], 80 * CPT + 3000)] + \
        [(f, 30) for f in faults]
    msgs, rep = play(simulator, lc, chunks, 8000, build_root / f"link_{simulator}")

    spikes = [m for m in msgs if m.type == MSG_SPIKES]
    model = LinkModel(lc)
    assert [(m.tick, m.payload) for m in spikes] == model_frames(model, good, 80)
    got = [s for m in spikes for s in parse_spikes(m)[2]]
    assert got == twin_spikes(lc.core, cur0, cur1, slice(3, 10), 40, 80) and len(got) > 10
    assert [parse_spikes(m)[1] for m in spikes] == [16] * 5

    counters = [m for m in msgs if m.type == MSG_COUNTERS]
    assert len(counters) == 1 and counters[0].tick == 80
    c = parse_counters(counters[0])
    # the truncated frame ends on a COBS block boundary or inside a block: a length or a
    # framing error; the runt and the unknown type are length errors
    assert c["framing_errors"] + c["length_errors"] == 3
    assert c == dict({n: 0 for n in COUNTER_NAMES}, frames_ok=5, crc_errors=1,
                     framing_errors=c["framing_errors"], length_errors=c["length_errors"],
                     seq_gaps=3, late_writes=1, range_errors=1)
    model.feed(b"".join(faults))
    assert model.counters == c
    assert rep["overflow_pin"] == 0 and rep["running_pin"] == 0


@pytest.mark.cocotb
# Icarus in the default lane, Verilator in the long lane
@pytest.mark.parametrize("simulator", [pytest.param(s, marks=pytest.mark.long)
                                       if s == "verilator" else s for s in SIMULATORS])
def test_link_receive_overflow_is_counted(simulator, build_root):
    """A write waits for sweep 50 while the host keeps sending: the 32-byte receive FIFO
    overflows; the dropped bytes are counted, the frames they broke are counted as framing,
    CRC or length errors, every frame not accepted shows as a sequence gap, and the write
    itself still lands at its sweep."""
    lc = link_config(CORE, clocks_per_bit=CPB, batch_sweeps=16, batch_capacity=60,
                     rx_fifo_depth=32)
    W, N = lc.current_width, lc.core.n_neurons
    cur = lc.core.I.to_raw(np.full(N, 30.0))
    burst = [encode_frame(write_message(2 + i, 51 + i, 0, cur[:2], W)) for i in range(6)]
    chunks = [(encode_frame(control_message(0, OP_STEP, 80)), 0),
              (encode_frame(write_message(1, 50, 0, cur, W)), 0)] + \
        [(b, 0) for b in burst[:-1]] + [(burst[-1], 80 * CPT)] + \
        [(encode_frame(control_message(8, OP_READ_COUNTERS)), 0)]
    sent_bytes = sum(len(c) for c, _ in chunks)
    msgs, _ = play(simulator, lc, chunks, 8000, build_root / f"link_ovf_{simulator}")
    c = parse_counters([m for m in msgs if m.type == MSG_COUNTERS][-1])
    assert c["rx_overflows"] > 0
    damaged = c["framing_errors"] + c["crc_errors"] + c["length_errors"]
    assert damaged > 0 and c["frames_ok"] < 9
    assert c["seq_gaps"] + c["frames_ok"] == 9       # nothing missing goes unseen
    # spikes from sweep 30 on follow the written current, as the twin says
    twin = IzhikevichTwin(lc.core)
    expect = []
    for k in range(80):
        if k == 50:
            twin.I[:] = cur
        expect += [(k, int(n)) for n in np.flatnonzero(twin.sweep())]
    got = [s for m in msgs if m.type == MSG_SPIKES for s in parse_spikes(m)[2]]
    assert got == expect and len(got) > 0
    print(f"\n{simulator}: sent {sent_bytes} bytes, counters {json.dumps(c)}")


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_link_damaged_frames_counted_never_accepted(simulator, build_root):
    """Damaged host frames between intact writes (two of every corruption class, every bit of
    the last COBS code byte 0x01 of a frame ending in 0x00, an intact frame of another format
    version), then a STEP: every damaged run is refused and counted once, the core receives
    exactly the intact frames' currents (watched at its write port) and spikes as the twin
    with those currents says."""
    import random
    from cuneate.sim.link.faults import fault_plan, plan_outcome, wire_of
    lc = link_config(CORE, clocks_per_bit=CPB, batch_sweeps=16, batch_capacity=60)
    N, W = lc.core.n_neurons, lc.current_width
    plan = fault_plan(W, N, random.Random("cocotb"), per_kind=2, code_bytes=("last",),
                      read_counters=False)
    arrived, damaged_runs = plan_outcome(plan)
    n_bad = sum(p.msg is None for p in plan)
    tail = [wire_of(control_message(len(plan), OP_STEP, 32)),
            wire_of(control_message(len(plan) + 1, OP_READ_COUNTERS))]
    stream = b"".join(p.wire for p in plan)
    msgs, rep = play(simulator, lc, [(stream, 0), (tail[0], 32 * CPT + 1000), (tail[1], 0)],
                     8000, build_root / f"link_damage_{simulator}", watch_writes=True)

    mask = (1 << W) - 1
    assert rep["writes"] == [[n, v & mask] for p in arrived for n, v in p.writes]
    counters = [m for m in msgs if m.type == MSG_COUNTERS]
    assert len(counters) == 1 and counters[0].tick == 32
    c = parse_counters(counters[0])
    refused = sum(c[k] for k in ("framing_errors", "crc_errors", "length_errors",
                                 "version_errors"))
    assert refused == damaged_runs and c["version_errors"] == 1
    assert c["frames_ok"] == len(arrived) + 2 and len(arrived) > 10
    assert c["frames_ok"] + c["seq_gaps"] == len(plan) + 2
    assert c == dict({n: 0 for n in COUNTER_NAMES}, frames_ok=c["frames_ok"],
                     seq_gaps=c["seq_gaps"], framing_errors=c["framing_errors"],
                     crc_errors=c["crc_errors"], length_errors=c["length_errors"],
                     version_errors=1)
    twin = IzhikevichTwin(lc.core)
    for p in arrived:
        for n, v in p.writes:
            twin.I[n] = v
    expect = [(k, int(n)) for k in range(32) for n in np.flatnonzero(twin.sweep())]
    got = [s for m in msgs if m.type == MSG_SPIKES for s in parse_spikes(m)[2]]
    assert got == expect and len(got) > 0
    model = LinkModel(lc)
    model.feed(stream + b"".join(tail))
    assert model.counters == c
    print(f"\n{simulator}: {n_bad} damaged frames sent, {damaged_runs} damaged runs, counted "
          f"{refused} ({', '.join(f'{k}={c[k]}' for k in COUNTER_NAMES if c[k])}), "
          f"0 accepted, {len(rep['writes'])} currents written (all intact)")


def lockstep_chunks(lc, writes: dict, n_sweeps: int, margin: int = 800) -> list:
    """A schedule (``{sweep: [(first, raw values), ...]}``) as the host sends it in lockstep:
    at each sweep with writes, its WRITE frames and a STEP to the next such sweep (the device
    stopped between), each chunk followed by the cycles its sweeps take."""
    W, cpt = lc.current_width, lc.info.cycles_per_tick
    at = sorted(writes) + [n_sweeps]
    chunks, seq = [], 0
    for k, nxt in zip(at[:-1], at[1:]):
        for first, raw in writes[k]:
            chunks.append((encode_frame(write_message(seq, k, first, raw, W)), 0))
            seq += 1
        chunks.append((encode_frame(control_message(seq, OP_STEP, nxt - k)),
                       (nxt - k) * cpt + margin))
        seq += 1
    return chunks


@pytest.mark.cocotb
@pytest.mark.long
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_the_learning_layer_learns_behind_the_link(simulator, build_root):
    """The learning layer behind the UART link: a presentation's afferent spikes, its window's
    end and the readout requests sent as WRITE frames; the CN spikes and the weights read back
    in the readout sweeps' SPIKES frames equal the fixed engine's (its twin) after learning."""
    cfg, pres = small_layer()
    pres = pres.select([0])
    lc = LinkConfig(cfg, clocks_per_bit=CPB, batch_sweeps=16, batch_capacity=40)
    plan = face_schedule(cfg, pres, [True])
    writes, n_sweeps = plan.writes, plan.n_sweeps
    msgs, _ = play(simulator, lc, lockstep_chunks(lc, writes, n_sweeps), 6000,
                   build_root / f"link_learning_{simulator}")
    got = [s for m in msgs if m.type == MSG_SPIKES for s in parse_spikes(m)[2]]
    assert all(parse_spikes(m)[0] == 0 for m in msgs if m.type == MSG_SPIKES)
    fixed = run_learning("fixed", cfg, pres, [True])
    n_total, M = pres.n_ticks, cfg.n_targets
    assert fixed.spike_cn.size > 0 and not np.array_equal(fixed.weights_raw, cfg.weights_raw)
    assert [(k, j) for k, j in got if k < n_total] == list(zip(fixed.spike_tick, fixed.spike_cn))
    weights = [weights_from_ids(cfg, [j for k, j in got if k == n_total + c]) for c in range(M)]
    assert np.array_equal(np.stack(weights), fixed.weights_raw)
