"""The host driver over the UART link, end to end: ``FbgDriver.stream`` through
``UartTransport`` to the protocol model (``ModelSerial``) and to the link gateware in the
Amaranth simulator (``AmaranthSerial``, bytes on the rx/tx pins), with every counter of the
transport contract checked; spikes equal the bit-exact twin's streamed the same way. With line
faults injected (``cuneate.sim.link.faults``) on a frame of either direction the run fails,
naming the loss and the counters that saw it: nothing lost is silent, nothing hangs."""

import random

import numpy as np
import pytest

from cuneate.sim.link.faults import KINDS, OnFrame, corrupt, flip
from cuneate.sim.host.uart import ModelSerial, UartTransport
from cuneate.hdl.link import link_config
from cuneate.hdl.link.codec import MSG_CONTROL, MSG_SPIKES, MSG_WRITE, OP_STEP, Message, \
    encode_frame
from cuneate.sim.host.transport import TransportError
from cuneate.sim.link.engines import AmaranthSerial
from host_stream import assert_contract, held_levels as trace, sa_driver, twin_reference

# a small, fast core: 8 neurons, 16 cycles per sweep at 4 kHz (samples at 1 kHz held 4 ticks)
CORE = dict(n_neurons=8, clock_hz=4e3 * 16, update_hz=4e3, spike_fifo_depth=16)


def lcfg():
    return link_config(CORE, clocks_per_bit=4, batch_sweeps=16)


def driver(lc):
    return sa_driver(lc.core, 2)


def reference(lc, x):
    return twin_reference(lc.core, 2, x)


def stream(port, lc, x):
    t = UartTransport(port, timeout_s=600.0)
    t.open(lc.core)
    return driver(lc).stream(t, x)


def test_stream_over_the_model_link_equals_the_twin_with_every_counter_checked():
    lc = lcfg()
    x = trace(60)
    ref = reference(lc, x)
    assert_contract(stream(ModelSerial(lc), lc, x), ref)


@pytest.mark.parametrize("kind", KINDS)
def test_a_damaged_write_on_the_line_fails_the_run_naming_the_loss(kind):
    lc = lcfg()
    rng = random.Random(kind)
    fault = OnFrame(MSG_WRITE, lambda w: corrupt(w, kind, rng), nth=2)
    with pytest.raises(TransportError) as err:
        stream(ModelSerial(lc, corrupt_host=fault), lc, trace(30))
    assert fault.hit
    msg = str(err.value)
    # either the lost write is found in the counters at the end of the run, or (the damage
    # ran into the next frame, a STEP) the missing spikes are explained by them at once
    assert ("frame(s) lost or damaged on the link" in msg or "no answer from the device" in msg)
    assert "device" in msg and ("errors=" in msg or "seq_gaps=" in msg), msg


def test_a_lost_step_is_named_at_once_not_a_hang():
    lc = lcfg()
    fault = OnFrame(MSG_CONTROL, lambda w: flip(w, (8 * 3 + 1,)), nth=3)   # STOP, CLEAR, STEP
    with pytest.raises(TransportError, match=r"no answer from the device .* the device counted "
                                             r"crc_errors=1.*seq_gaps=1") as err:
        stream(ModelSerial(lc, corrupt_host=fault), lc, trace(30))
    assert "the spikes of sweeps" in str(err.value)


@pytest.mark.parametrize("damage,msg", [
    (lambda w: flip(w, (13,)), "damaged frames from the device"),
    (lambda w: b"", "sequence gap|spike batches lost"),                # the frame never arrives
])
def test_a_damaged_or_lost_device_frame_fails_the_run(damage, msg):
    lc = lcfg()
    seen = []

    def device(data):
        if data and len(seen) < 3:
            seen.append(1)
            if len(seen) == 3:
                return damage(data)
        return data
    with pytest.raises(TransportError, match=msg):
        stream(ModelSerial(lc, corrupt=device), lc, trace(30))


def test_a_spike_for_a_neuron_the_core_lacks_is_refused():
    lc = lcfg()
    bad = encode_frame(Message(MSG_SPIKES, 0, 0, bytes([0, 0, 4, 1]) + (9).to_bytes(2, "little")))

    sent = []

    def device(data):                       # in place of the device's first batch
        if data and not sent:
            sent.append(data)
            return bad
        return data
    t = UartTransport(ModelSerial(lc, corrupt=device), timeout_s=5.0)
    t.open(lc.core)
    t.run(4)
    with pytest.raises(TransportError,
                       match="spike of neuron 9 .* the device has neuron ids 0..7"):
        t.collect()
    assert t.counters()["rx_length_errors"] == 1


def test_stream_over_the_gateware_equals_the_twin():
    """The link gateware in the Amaranth simulator, bytes on its pins."""
    lc = lcfg()
    x = trace(15)
    ref = reference(lc, x)
    port = AmaranthSerial(lc)
    got = stream(port, lc, x)
    assert len(ref.spikes) > 5 and ref.writes_sent >= 4
    assert np.array_equal(got.spikes.tick, ref.spikes.tick)
    assert np.array_equal(got.spikes.neuron, ref.spikes.neuron)
    c = got.counters
    assert (c["writes"], c["spikes"], c["spikes_counted"], c["frames_lost"]) == \
        (ref.writes_sent, len(ref.spikes), len(ref.spikes), 0)
    assert c["device_frames_ok"] == c["frames_sent"] - 2 and port.cycles > 10_000


def test_a_damaged_write_to_the_gateware_fails_the_run_naming_the_loss():
    lc = lcfg()
    fault = OnFrame(MSG_WRITE, lambda w: flip(w, (8 * 5 + 2,)), nth=1)
    with pytest.raises(TransportError, match=r"uart: 1 frame\(s\) lost or damaged on the link "
                                             r"\(1 of \d+ frames sent not accepted by the "
                                             r"device, device crc_errors=1, device "
                                             r"seq_gaps=1\)"):
        stream(AmaranthSerial(lc, corrupt_host=fault), lc, trace(9))
    assert fault.hit


def test_steps_as_fast_as_the_sweeps_batch_every_sweep_in_its_frame():
    """Ticks as fast as the sweeps (11 cycles a sweep for 8 neurons and a 5-stage pipeline: a
    step's last tick goes before the previous sweep is done): each step's spike batch still
    closes after the step's last sweep (one frame a step, covering all its sweeps, so every
    spike arrives in the frame of its sweep) and the run equals the twin."""
    from cuneate.hdl.link.codec import FrameDecoder, parse_spikes
    lc = link_config(dict(CORE, clock_hz=4e3 * 11), clocks_per_bit=4, batch_sweeps=16)
    host, dev, steps, batches = FrameDecoder(), FrameDecoder(), [], []

    def sent(data):
        steps.extend(int.from_bytes(m.payload[1:5], "little") for m in host.feed(data)
                     if m.type == MSG_CONTROL and m.payload[0] == OP_STEP)
        return data

    def received(data):
        batches.extend(parse_spikes(m)[1] for m in dev.feed(data) if m.type == MSG_SPIKES)
        return data
    x = trace(24)
    ref = reference(lc, x)
    got = stream(AmaranthSerial(lc, corrupt=received, corrupt_host=sent), lc, x)
    assert len(steps) > 4 and batches == steps
    assert np.array_equal(got.spikes.tick, ref.spikes.tick)
    assert np.array_equal(got.spikes.neuron, ref.spikes.neuron)
    assert got.counters["overrun"] == 0 and got.counters["frames_lost"] == 0
