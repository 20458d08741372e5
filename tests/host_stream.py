"""Shared by the host-link tests: a trace of held levels, the host driver of three SA gratings,
the bit-exact twin's stream of it (the reference), the transport contract a stream over a
link must meet against that reference, and a run of raw samples through a transport."""

import numpy as np

from cuneate.sim.host.driver import AfferentEncoding, FbgDriver
from cuneate.sim.host.transport import COUNTERS
from cuneate.sim.izhikevich.engines import TwinTransport

SA = AfferentEncoding("SA", gain=40.0, unit_pm=1000.0)


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
