"""The ``board`` engine: the board top (UART link + core) compiled by Verilator behind a
simulated serial line, driven by the real host stack (``FbgDriver`` -> ``UartTransport`` ->
COBS/CRC frames -> 8N1 bits -> the RTL, and back). Its spikes equal the twin's and the fixed
engine's in a scene; every fault injected on the line, in either direction, is detected and
counted, and none silently changes a spike."""

import random

import numpy as np
import pytest

from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.hdl.link.codec import MAX_FRAME, MSG_CONTROL, MSG_SPIKES, MSG_WRITE
from cuneate.sim.host.transport import TransportError
from cuneate.sim.izhikevich.engines import make_transport
from cuneate.sim.link.engines import BoardTransport, board_link
from cuneate.sim.link.faults import KINDS, OnChunk, OnFrame, corrupt
from host_stream import assert_contract, held_levels as trace, sa_driver, twin_reference

# 24 neurons at one update a clock, as the other engines run a core: the board engine adds the
# idle cycles a board keeps between sweeps
CORE = IzhikevichConfig(n_neurons=24, clock_hz=4e3 * 24, update_hz=4e3, spike_fifo_depth=32)


def driver():
    return sa_driver(CORE, 5)


def reference(x):
    return twin_reference(CORE, 5, x)


def test_the_board_link_keeps_a_boards_idle_cycles_and_one_batch_a_millisecond():
    lc = board_link(CORE)
    assert lc.core.tick_source == "external" and lc.core.cycles_per_tick >= 24 + 16
    assert lc.batch_sweeps == 4 and lc.clocks_per_bit == 4
    # the largest frame (and its delimiters) leaves within a batch's sweeps on the line
    assert lc.batch_sweeps * lc.core.cycles_per_tick >= (MAX_FRAME + 2) * 10 * lc.clocks_per_bit
    # the arithmetic is the core's
    assert lc.core.to_kwargs(clock_hz=0, tick_source="") == CORE.to_kwargs(clock_hz=0,
                                                                          tick_source="")


@pytest.mark.parametrize("ahead", [True, False], ids=["writes-ahead", "lockstep"])
def test_board_engine_equals_the_twin_with_every_counter_checked(ahead):
    """Both host modes: writes sent ahead (the decoder holds each until its sweep) and
    lockstep (each sweep's writes sent once the device stands at it)."""
    x = trace(60)
    ref = reference(x)
    tr = make_transport("board", ahead=ahead)
    tr.open(CORE)
    try:
        got = driver().stream(tr, x)
    finally:
        tr.close()
    c = assert_contract(got, ref)
    f = tr.figures()
    # every byte on the line arrived whole
    assert f["frames_to_device"] == c["frames_sent"] and f["framing_errors"] == 0
    assert f["bytes_to_device"] > 0 and f["bytes_from_device"] > 0
    assert f["cycles"] >= 60 * 4 * board_link(CORE).core.cycles_per_tick
    assert f["ahead"] == ahead and f["cycles_per_sweep_rate"] >= 1.0
    if ahead:     # the device hardly waits for the host: its writes are already queued
        assert f["cycles_per_sweep_rate"] < 1.1


def _fails(**faults) -> str:
    tr = BoardTransport(timeout_s=60.0, **faults)
    tr.open(CORE)
    try:
        with pytest.raises(TransportError) as err:
            driver().stream(tr, trace(30))
    finally:
        tr.close()
    return str(err.value)


#: the default lane's corruption classes (a flipped bit, a lost byte, an extra byte); the long
#: lane runs every class
DEFAULT_KINDS = ("bit", "drop", "insert")


@pytest.mark.parametrize("kinds", [
    pytest.param(DEFAULT_KINDS, id="bit-drop-insert", marks=pytest.mark.long),
    pytest.param(tuple(k for k in KINDS if k not in DEFAULT_KINDS), id="the-others",
                 marks=pytest.mark.long)])
def test_every_fault_injected_on_the_line_is_detected_and_counted(kinds):
    """Each corruption class on a host WRITE, a host STEP and a device SPIKES frame: each run
    fails, naming the counters that saw the loss; none completes with different spikes."""
    detected, injected = 0, 0
    for kind in kinds:
        rng = random.Random(kind)
        for typ, nth in ((MSG_WRITE, 2), (MSG_CONTROL, 4)):
            fault = OnFrame(typ, lambda w: corrupt(w, kind, rng), nth=nth)
            msg = _fails(corrupt_host=fault)
            injected += fault.hit
            assert fault.hit, (kind, typ)
            assert ("lost or damaged on the link" in msg or "no answer from the device" in msg
                    or "spike batches lost" in msg), (kind, typ, msg)
            assert "device" in msg, (kind, typ, msg)
            detected += 1
        dev = OnChunk(lambda w: corrupt(w, kind, rng), nth=3)
        msg = _fails(corrupt=dev)
        injected += dev.hit
        assert dev.hit, kind
        assert ("damaged frames from the device" in msg or "sequence gap" in msg
                or "spike batches lost" in msg or "malformed frame" in msg), (kind, msg)
        detected += 1
    assert injected == detected == 3 * len(kinds)


def test_scene_on_the_board_engine_equals_fixed(tmp_path):
    from cuneate.sim.scenes.runner import run_scene
    from cuneate.sim.scenes.scene import default_scene
    run = run_scene(default_scene(), engines=["fixed", "board"], build_dir=tmp_path)
    fixed, board = run.spikes["fixed"], run.spikes["board"]
    assert sum(len(s) for s in fixed) > 1000
    assert all(np.array_equal(a, b) for a, b in zip(fixed, board)) and len(fixed) == len(board)
    c = run.counters["board"]
    assert c["frames_lost"] == 0 and c["line_frames_from_device"] > 0
    assert c["line_cycles_per_s"] > 0 and c["device_frames_ok"] == c["frames_sent"] - 2


def test_spike_frames_carry_exactly_their_sweeps():
    """Every SPIKES frame from the device holds spikes of its own sweeps only, and the frames'
    sweeps follow each other without a gap (the board's idle cycles between sweeps; the case
    of ticks as fast as the sweeps is tests/sim/host/test_uart_driver.py's)."""
    from cuneate.hdl.link.codec import FrameDecoder, parse_spikes
    dec, batches = FrameDecoder(), []

    def watch(data):
        for msg in dec.feed(data):
            if msg.type == MSG_SPIKES:
                batches.append((msg.tick, parse_spikes(msg)))
        return data
    tr = BoardTransport(corrupt=watch)
    tr.open(CORE)
    driver().stream(tr, trace(45))
    tr.close()
    at = 0
    for tick, (dropped, sweeps, spikes) in batches:
        assert tick == at and dropped == 0
        assert all(tick <= t < tick + sweeps for t, _ in spikes)
        at += sweeps
    assert at == 45 * 4 and sum(len(b[1][2]) for b in batches) > 20
