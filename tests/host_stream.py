"""Shared by the host-link tests: a trace of held levels, the host driver of three SA gratings,
the bit-exact twin's stream of it (the reference), the transport contract a stream over a
link must meet against that reference, a run of raw samples through a transport, the spike
frames a board link sends for a run of current writes, and a channel fan-out in front of a
core (one design, so the Verilator builds of the tests that run it are shared)."""

import numpy as np

from cuneate.hdl.fanout import FanoutConfig
from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.hdl.link.codec import MSG_SPIKES, FrameDecoder
from cuneate.sim.host.driver import AfferentEncoding, FbgDriver
from cuneate.sim.host.transport import COUNTERS
from cuneate.sim.izhikevich.engines import TwinTransport

SA = AfferentEncoding("SA", gain=40.0, unit_pm=1000.0)

#: a core of 30 neurons fed by a fan-out of 4 channels (gains, rectifications, thresholds of
#: every kind), a sample every ``FANOUT_EVERY`` sweeps
FANOUT_CORE = IzhikevichConfig(n_neurons=30, clock_hz=4e3 * 30, update_hz=4e3,
                               spike_fifo_depth=32)
_rng = np.random.default_rng(11)
FANOUT = FanoutConfig(n_channels=4, channel=[i % 4 for i in range(30)],
                      gain=[float(g) for g in np.round(_rng.uniform(4, 30, 30), 2)],
                      rectify=["positive", "abs", "none"] * 10,
                      threshold=[0.5 if i % 5 == 0 else None for i in range(30)],
                      sample_max=4.0, sample_width=12)
FANOUT_EVERY = 4


def fanout_samples(n: int, seed: int = 2) -> np.ndarray:
    """``n`` raw samples of :data:`FANOUT`'s channels."""
    rng = np.random.default_rng(seed)
    return FANOUT.S.to_raw(rng.uniform(-1.5, 3.0, (n, FANOUT.n_channels)))


def held_levels(n_samples: int, seed: int = 1) -> np.ndarray:
    """Shifts (nm) of three gratings: held levels that change every third sample (the driver
    writes only the changes), strong enough to make the neurons spike."""
    rng = np.random.default_rng(seed)
    levels = rng.uniform(0.0, 1.8, (max(1, n_samples // 3), 3))
    return np.repeat(levels, 3, axis=0)[:n_samples]


def sa_driver(core, first: int) -> FbgDriver:
    """The driver of three SA gratings on neurons ``first .. first + 2`` of ``core``."""
    return FbgDriver(core, [SA] * 3, first=first)


def twin_reference(core, first: int, x):
    """``x`` streamed by :func:`sa_driver` to the bit-exact twin of ``core``."""
    tw = TwinTransport()
    tw.open(core)
    return sa_driver(core, first).stream(tw, x)


def stream_samples(tr, config, raw, every: int):
    """Open ``tr`` on ``config``, write row ``k`` of ``raw`` (from value 0) before sweep
    ``k every``, run every row's sweeps and close; ``(spikes, checked counters, figures)``."""
    tr.open(config)
    try:
        for k, row in enumerate(raw):
            tr.write_currents(k * every, 0, row)
        tr.run(len(raw) * every)
        got = tr.collect()
        counters = tr.check()
    finally:
        tr.close()
    return got, counters, tr.figures()


def assert_contract(got, ref) -> dict:
    """``got`` (a stream over a link) equals ``ref`` (:func:`twin_reference`) spike for spike,
    with every counter of the transport contract and every frame sent after the device cleared
    its counters accepted; returns the counters."""
    assert len(ref.spikes) > 30 and ref.writes_sent > 10
    assert np.array_equal(got.spikes.tick, ref.spikes.tick)
    assert np.array_equal(got.spikes.neuron, ref.spikes.neuron)
    c = got.counters
    assert {k: c[k] for k in COUNTERS} == {
        "writes": ref.writes_sent, "spikes": len(ref.spikes), "spikes_counted": len(ref.spikes),
        "frames_lost": 0, "overflow": 0, "overrun": 0, "late_writes": 0}
    assert c["device_frames_ok"] == c["frames_sent"] - 2 and c["device_seq_gaps"] == 0
    return c


def board_spike_frames(cfg, runs: dict, n: int, **board) -> list:
    """The spike frames a :class:`~cuneate.sim.link.engines.BoardTransport` (``board`` its
    options) sends for the current writes ``runs`` (sweep -> ``[(first, raw)]``) and ``n``
    sweeps of ``cfg``, its counters checked."""
    from cuneate.sim.link.engines import BoardTransport
    from cuneate.sim.link.faults import Recorder
    rec = Recorder()
    tr = BoardTransport(corrupt=rec, **board)
    tr.open(cfg)
    try:
        for k, rs in runs.items():
            for first, raw in rs:
                tr.write_currents(k, first, raw)
        tr.run(n)
        tr.collect()
        tr.check()
    finally:
        tr.close()
    return [m for m in FrameDecoder().feed(bytes(rec.data)) if m.type == MSG_SPIKES]
