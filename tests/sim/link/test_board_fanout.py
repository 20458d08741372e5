"""Channels in, fanned out on chip: the board top with the channel fan-out
(:class:`~cuneate.hdl.link.LinkedTop` of the fan-out in front of a core) compiled by Verilator behind the simulated serial
line, driven by the host's transport with raw channel samples. Its spikes equal a reference
built from the twins alone (the fan-out twin's currents into the Izhikevich twin, each sample
in effect from its sweep), and the link carried channels, not afferents."""

import numpy as np
import pytest

from cuneate.hdl.fanout import FanoutTwin
from cuneate.hdl.izhikevich import IzhikevichConfig, IzhikevichTwin
from cuneate.hdl.lib.config import ConfigError
from cuneate.hdl.link import LinkConfig, LinkModel
from cuneate.sim.link.engines import BoardTransport, board_link
from host_stream import FANOUT as FAN
from host_stream import FANOUT_CORE as CORE
from host_stream import FANOUT_EVERY as EVERY
from host_stream import fanout_samples as samples
from host_stream import stream_samples

N, C = CORE.n_neurons, FAN.n_channels


def reference(raw: np.ndarray, n_sweeps: int):
    """(sweep, neuron) of every spike: the fan-out twin's currents from each sample's sweep."""
    fan, core = FanoutTwin(FAN), IzhikevichTwin(CORE, kernel="stages")
    out = []
    for t in range(n_sweeps):
        if t % EVERY == 0 and t // EVERY < len(raw):
            fan.samples[:] = raw[t // EVERY]
            core.I[:] = fan.run()[0]
        out += [(t, int(n)) for n in np.flatnonzero(core.sweep())]
    return out, fan.clamp_counts


@pytest.mark.parametrize("ahead", [True, False], ids=["writes-ahead", "lockstep"])
def test_the_board_with_the_fanout_equals_the_twins(ahead):
    raw = samples(40)
    n_sweeps = len(raw) * EVERY
    want, clamps = reference(raw, n_sweeps)
    got, counters, figures = stream_samples(BoardTransport(fanout=FAN, ahead=ahead), CORE, raw,
                                            EVERY)
    assert len(want) > 40
    assert list(zip(got.tick.tolist(), got.neuron.tolist())) == want
    # the link carried the channels: one frame of C samples a sample, nothing lost
    assert counters["currents_sent"] == C * len(raw) and counters["write_frames_sent"] == len(raw)
    assert counters["device_frames_ok"] == counters["frames_sent"] - 2
    assert counters["device_late_writes"] == 0 and figures["framing_errors"] == 0
    assert sum(clamps.values()) == 0


def test_the_link_model_with_the_fanout_equals_the_twins():
    """The link's behavioural model, fed the host's frames, gives the same spikes."""
    from cuneate.hdl.link.codec import (OP_STEP, FrameDecoder, MSG_SPIKES, control_message,
                                        encode_frame, parse_spikes, write_message)
    lcfg = board_link(CORE, fanout=FAN)
    model = LinkModel(lcfg)
    raw = samples(12, seed=3)
    wire, seq = bytearray(), 0
    for k, row in enumerate(raw):
        wire += encode_frame(write_message(seq, k * EVERY, 0, row, FAN.S.width))
        wire += encode_frame(control_message(seq + 1, OP_STEP, EVERY))
        seq += 2
    out = model.feed(bytes(wire))
    model.advance(EVERY)                           # the last STEP's sweeps
    out += model.feed(b"")
    dec, got = FrameDecoder(), []
    for msg in dec.feed(out):
        if msg.type == MSG_SPIKES:
            got += parse_spikes(msg)[2]            # (sweep, neuron)
    assert sorted(got) == reference(raw, len(raw) * EVERY)[0]


def test_a_fanout_link_refuses_a_core_it_does_not_feed():
    with pytest.raises(ConfigError, match="the fan-out feeds 30 afferents"):
        LinkConfig(IzhikevichConfig(n_neurons=20, tick_source="external"), fanout=FAN)
    # a core of more neurons than the fan-out's afferents: the rest listen to nothing
    more = LinkConfig(IzhikevichConfig(n_neurons=40, tick_source="external"), fanout=FAN)
    assert more.fanout.n_neurons == 40 and more.fanout.gain[N:] == [0.0] * 10
    lcfg = board_link(CORE, fanout=FAN)
    assert lcfg.n_written == C and lcfg.current_width == FAN.S.width
    assert lcfg.core.cycles_per_tick >= N + FAN.cycles_per_run
    # a sweep too short for a frame's writes and the fan-out's run
    short = IzhikevichConfig(n_neurons=N, clock_hz=4e3 * (2 * N + C), update_hz=4e3,
                             tick_source="external")
    with pytest.raises(ConfigError, match=f"a sweep of {2 * N + C} cycles cannot hold"):
        LinkConfig(short, fanout=FAN)
    # the link's values are channel samples, its ids the core's neurons
    assert lcfg.info.written == "channel sample" and lcfg.n_spike_ids == N
