"""UartTransport on the simulated serial path (the protocol model on the twin) and on a
pyserial URL: lockstep spikes equal the twin's, and every loss or refusal raises."""

import random
import struct

import numpy as np
import pytest

from cuneate.sim.host.uart import HOST_ERRORS, ModelSerial, UartTransport
from cuneate.sim.link.faults import KINDS, corrupt
from cuneate.hdl.izhikevich import IzhikevichTwin
from cuneate.hdl.link import link_config
from cuneate.hdl.link.codec import MSG_SPIKES, MSG_WRITE, Message, encode_frame
from cuneate.sim.host.transport import TransportError

CORE = dict(n_neurons=100, clock_hz=16e3 * 128, update_hz=16e3)


def make(corrupt=None, **kw):
    lc = link_config(CORE, batch_sweeps=16, **kw)
    t = UartTransport(ModelSerial(lc, corrupt=corrupt), timeout_s=0.2)
    t.open(lc.core)
    return lc, t


def test_lockstep_spikes_equal_the_twin_with_writes_at_their_sweeps():
    lc, t = make()
    rng = np.random.default_rng(3)
    I = lc.core.I
    w = {0: (0, I.to_raw(rng.uniform(0, 40, 100))),
         37: (10, I.to_raw(rng.uniform(20, 90, 60))),      # 60 currents: several frames
         100: (50, I.to_raw(rng.uniform(0, 10, 50)))}
    for k, (first, raw) in w.items():
        t.write_currents(k, first, raw)
    t.run(50)
    a = t.collect()
    t.run(90)
    b = t.collect()
    twin = IzhikevichTwin(lc.core)
    ticks, neurons = [], []
    for k in range(140):
        if k in w:
            first, raw = w[k]
            twin.I[first:first + raw.size] = raw
        s = np.flatnonzero(twin.sweep())
        ticks += [k] * s.size
        neurons += list(s)
    assert np.all(a.tick < 50) and np.all(b.tick >= 50)
    got = np.concatenate([a.tick, b.tick]), np.concatenate([a.neuron, b.neuron])
    assert got[0].tolist() == ticks and got[1].tolist() == neurons and len(ticks) > 50
    c = t.check()
    assert c["spikes_received"] == len(ticks)
    assert c["writes_sent"] == 3 and c["write_frames_sent"] == 4 and c["currents_sent"] == 210
    assert c["writes"] == 3 and c["frames_lost"] == 0 and c["spikes"] == len(ticks)
    assert c["device_frames_ok"] > 0 and c["device_late_writes"] == 0
    t.close()


def test_late_and_out_of_range_writes_are_refused():
    lc, t = make()
    t.run(10)
    t.collect()
    with pytest.raises(TransportError, match="sweep 5 .* run to sweep 10"):
        t.write_currents(5, 0, [1, 2])
    with pytest.raises(TransportError, match="outside the core's 100"):
        t.write_currents(20, 99, [1, 2])


def test_damaged_device_frame_raises():
    def flip(data):
        b = bytearray(data)
        if len(b) > 6:
            b[4] ^= 0x01 if b[4] != 1 else 0x02
        return bytes(b)
    lc, t = make(corrupt=flip)
    t.run(16)
    with pytest.raises(TransportError, match="damaged frames"):
        t.collect()


def test_truncated_spike_frame_is_a_counted_loss_not_an_exception():
    """A SPIKES frame ending in 0x00 is encoded ending ``0x01 0x00``; one flipped bit turns the
    code byte into a delimiter and drops the frame's last byte. The host refuses it (no
    FrameError escapes), counts it, and ``check`` fails naming the count."""
    payload = bytearray(struct.pack("<HB", 0, 16) + struct.pack("<BH", 3, 0))
    for n in range(1, 1 << 16):                     # the spike's neuron sets the CRC
        payload[4:6] = struct.pack("<H", n)
        wire = encode_frame(Message(MSG_SPIKES, 0, 0, bytes(payload)))
        if wire[-2:] == b"\x01\x00":
            break
    damaged = wire[:-2] + b"\x00\x00"
    sent = []

    def device(data):
        if data and not sent:
            sent.append(data)
            return damaged                           # in place of the device's first batch
        return data
    lc, t = make(corrupt=device)
    t.run(16)
    with pytest.raises(TransportError, match="damaged frames from the device .*crc=1"):
        t.collect()
    c = t.counters()
    assert c["rx_crc_errors"] == 1 and c["spikes_received"] == 0
    assert sum(c[k] for k in HOST_ERRORS) == 1
    with pytest.raises(TransportError, match="host refused damaged frames .*rx_crc_errors=1"):
        t.check()


@pytest.mark.parametrize("kind", KINDS)
def test_any_damaged_device_frame_is_counted_and_check_fails(kind):
    rng = random.Random(kind)
    hit = []

    def damage(data):
        if data and not hit:
            hit.append(1)
            first = data.index(0) + 1               # the first frame only
            return corrupt(data[:first], kind, rng) + data[first:]
        return data
    lc, t = make(corrupt=damage)
    t.run(64)
    with pytest.raises(TransportError, match="damaged frames|sequence gap|batches lost"):
        t.collect()
    with pytest.raises(TransportError, match="host refused damaged frames"):
        t.check()


def test_dropped_spikes_raise():
    lc, t = make(batch_capacity=2)
    t.write_currents(0, 0, lc.core.I.to_raw(np.full(100, 60.0)))
    t.run(64)
    with pytest.raises(TransportError, match="spikes dropped"):
        t.collect()


def test_device_error_counters_raise():
    lc, t = make()
    t.port.write(encode_frame(Message(MSG_WRITE, 2, 0, b"\x00")))     # a runt write
    with pytest.raises(TransportError, match="length_errors=1"):
        t.check()


def test_serial_url_opens_and_garbage_is_refused():
    lc = link_config(CORE)
    t = UartTransport("loop://", timeout_s=0.2)
    t.open(lc.core)          # loop:// echoes the host's own frames back: not a device
    t.run(1)
    with pytest.raises(TransportError, match="unexpected frame type"):
        t.collect()
    t.close()
    with pytest.raises(TransportError, match="cannot open"):
        UartTransport("/dev/does-not-exist-cuneate").open(lc.core)
