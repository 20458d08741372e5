"""Host driver: front end, quantization with counted saturation, tick alignment and latency,
loss detection, and every engine fed with time-varying currents equal to the twin."""

import numpy as np
import pytest

from cuneate.golden.fbg import DEFAULT_BANDPASS, FbgFrontEnd
from cuneate.hdl.izhikevich import IzhikevichTwin
from cuneate.sim.host.driver import AfferentEncoding, FbgDriver, GapError
from cuneate.sim.izhikevich.engines import engine_core
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.host.transport import COUNTERS, SpikeBatch, Transport, TransportError
from cuneate.sim.izhikevich.engines import (AmaranthTransport, CocotbTransport, TwinTransport,
                                    make_transport)

FA = AfferentEncoding("FA", 180.0, 10.0, DEFAULT_BANDPASS)
SA = AfferentEncoding("SA", 2.0, 1.0, None, "none", 0.5)


class Recorder(Transport):
    """Records what the driver does (test double of a core link)."""

    name = "recorder"

    def __init__(self):
        self.calls = []
        self.n_writes = 0

    def open(self, config):
        pass

    def write_currents(self, tick, first, raw):
        self.calls.append(("write", tick, first, np.asarray(raw).tolist()))
        self.n_writes += 1

    def run(self, n):
        self.calls.append(("run", n))

    def collect(self):
        return SpikeBatch()

    def counters(self):
        return dict.fromkeys(COUNTERS, 0) | {"writes": self.n_writes}


def _cfg(n=4):
    return engine_core({"param_sets": ("RS",)}, n)


def test_fa_and_sa_currents_follow_the_front_end():
    dl = np.linspace(0, 0.01, 200)[:, None] * np.ones((1, 2))
    drv = FbgDriver(_cfg(), [FA, SA])
    cur = drv.currents(dl)
    ref = FbgFrontEnd(DEFAULT_BANDPASS, 180.0).currents(dl[:, 0] * 100.0)
    assert np.allclose(cur[:, 0], np.maximum(ref, 0))
    pm = dl[:, 1] * 1e3
    assert np.allclose(cur[:, 1], np.where(pm >= 0.5, 2.0 * pm, 0.0))


def test_writes_are_aligned_to_ticks_with_latency():
    cfg = _cfg(2)
    raw_currents = np.array([[1.0, 0], [1.0, 0], [2.0, 3.0], [2.0, 3.0], [0.0, 3.0]])
    for L in (0, 5):
        rec = Recorder()
        drv = FbgDriver(cfg, [SA, SA], latency_ticks=L)
        raw, _ = drv.quantize(raw_currents)
        drv.stream(rec, None, raw=raw)
        writes = [c for c in rec.calls if c[0] == "write"]
        # only changed spans are written: samples 0, 2 and 4
        assert [w[1] for w in writes] == [0 + L, 32 + L, 64 + L]
        assert writes[0][2:] == (0, [256])               # 1.0 in sQ10.8, neuron 0 only
        assert writes[1][2:] == (0, [512, 768])
        assert writes[2][2:] == (0, [0])
        runs = sum(c[1] for c in rec.calls if c[0] == "run")
        assert runs == 5 * 16                            # the run covers the trace exactly
        held = drv.held(raw_currents)
        assert held.shape == (80, 2)
        assert np.all(held[:L] == 0) and np.all(held[L:L + 16, 0] == 1.0)
        assert np.all(held[L + 32:L + 48, 1] == 3.0)


def test_latency_past_the_end_is_counted():
    drv = FbgDriver(_cfg(1), [SA], latency_ticks=20)
    raw, _ = drv.quantize(np.arange(1.0, 6.0)[:, None])
    r = drv.stream(Recorder(), None, raw=raw)
    # samples start at ticks 20, 36, 52, 68, 84: the last is past the 80-tick run
    assert r.samples_past_end == 1 and r.writes_sent == 4


def test_twin_transport_sees_sample_j_from_tick_16j_plus_latency():
    # one neuron, a single strong sample at j = 3; reference: the twin run directly with a
    # callable current under the documented alignment
    cfg = _cfg(1)
    cur = np.zeros((8, 1))
    cur[3] = 60.0
    for L in (0, 7):
        drv = FbgDriver(cfg, [SA], latency_ticks=L)
        raw, _ = drv.quantize(cur)
        tr = TwinTransport()
        tr.open(cfg)
        spikes = drv.stream(tr, None, raw=raw).spikes
        twin = IzhikevichTwin(cfg)
        ref = twin.run(lambda t_ms: 60.0 if 48 + L <= round(t_ms * 16) < 64 + L else 0.0,
                       8 * 16)[0]
        got = (spikes.tick[spikes.neuron == 0] + 1) * cfg.dt_ms
        assert np.array_equal(got, ref) and got.size > 0
        assert spikes.tick.min() >= 48 + L


def test_saturations_are_counted_and_clamped():
    cfg = _cfg(2)
    drv = FbgDriver(cfg, [SA, SA])
    raw, sat = drv.quantize(np.array([[600.0, -700.0], [10.0, 1000.0]]))
    assert sat["format_high"] == 2 and sat["format_low"] == 1
    assert raw[0, 0] == cfg.I.max_raw and raw[0, 1] == cfg.I.min_raw
    assert sat["max_mV_per_ms"] == 1000.0


def test_gaps_are_refused_or_held_and_counted():
    drv = FbgDriver(_cfg(2), [SA, SA])
    dl = np.ones((10, 2)) * 1e-3
    dl[4, 1] = np.nan
    with pytest.raises(GapError, match="sample 4 of channel 1 is missing"):
        drv.currents(dl)
    held, n = FbgDriver(_cfg(2), [SA, SA], on_gap="hold").fill_gaps(dl)
    assert n == 1 and held[4, 1] == held[3, 1]


class DropWrite(TwinTransport):
    def write_currents(self, tick, first, raw):
        if tick == 32:
            return                      # silently lost on the way
        super().write_currents(tick, first, raw)


class DropSpike(TwinTransport):
    def collect(self):
        b = super().collect()
        self.cnt["spikes"] -= 1         # the link itself did not notice
        return SpikeBatch(b.tick[1:], b.neuron[1:])


class Overflow(TwinTransport):
    def counters(self):
        return super().counters() | {"overflow": 1}


class Silent(TwinTransport):
    def counters(self):
        c = super().counters()
        del c["writes"]                 # a transport that does not report writes
        return c


@pytest.mark.parametrize("cls,msg", [(DropWrite, r"8 of 9 current writes were applied by the "
                                                r"core \(1 lost\)"),
                                     (Silent, "does not report writes"),
                                     (DropSpike, "spikes lost on the way"),
                                     (Overflow, "overflow: 1")])
def test_loss_is_detected(cls, msg):
    cfg = _cfg(2)
    drv = FbgDriver(cfg, [SA, SA])
    raw, _ = drv.quantize(np.linspace(0, 40, 10)[:, None] * np.ones((1, 2)))
    tr = cls()
    tr.open(cfg)
    with pytest.raises(TransportError, match=msg):
        drv.stream(tr, None, raw=raw)


def test_late_writes_and_buffer_overruns_are_errors():
    cfg = _cfg(2)
    tr = TwinTransport()
    tr.open(cfg)
    tr.run(5)
    with pytest.raises(TransportError, match="late write refused"):
        tr.write_currents(3, 0, [1])
    b = CocotbTransport("verilator", buffer_writes=2)
    b.open(cfg)
    b.write_currents(0, 0, [1])
    b.write_currents(1, 0, [1])
    with pytest.raises(TransportError, match="write buffer overrun"):
        b.write_currents(2, 0, [1])
    c = CocotbTransport("icarus")
    c.open(cfg)
    with pytest.raises(TransportError, match="outside the core"):
        c.write_currents(3, cfg.n_neurons - 1, [1, 2])


def _schedule():
    """Time-varying FA currents for 6 neurons over 40 samples (640 ticks)."""
    rng = np.random.default_rng(3)
    dl = np.cumsum(rng.uniform(0, 4e-4, (40, 6)), axis=0)
    cfg = _cfg(6)
    drv = FbgDriver(cfg, [FA] * 6)
    raw, _ = drv.quantize(drv.currents(dl))
    return cfg, drv, raw


def _equal_to_twin(engine_transport):
    cfg, drv, raw = _schedule()
    ref_t = TwinTransport()
    ref_t.open(cfg)
    ref = drv.stream(ref_t, None, raw=raw)
    engine_transport.open(cfg)
    got = drv.stream(engine_transport, None, raw=raw)
    assert len(ref.spikes) > 20
    assert np.array_equal(got.spikes.tick, ref.spikes.tick)
    assert np.array_equal(got.spikes.neuron, ref.spikes.neuron)
    assert got.counters["writes"] == ref.writes_sent == 40
    assert got.counters["spikes_counted"] == len(ref.spikes)


def test_amaranth_transport_equals_twin():
    _equal_to_twin(AmaranthTransport())


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_cocotb_transport_equals_twin(simulator, build_root):
    _equal_to_twin(make_transport(simulator, build_dir=build_root / f"driver_{simulator}"))


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


_CFGS = {}


@settings(max_examples=60, deadline=None)
@given(ratio=st.sampled_from([8, 10, 16, 20, 32]), latency=st.integers(0, 40), n=st.integers(1, 4),
       samples=st.integers(1, 12), seed=st.integers(0, 2**31))
def test_written_currents_equal_the_held_schedule_at_every_tick(ratio, latency, n, samples,
                                                                 seed):
    """Replaying the driver's writes gives, tick by tick, the currents the golden engine
    integrates (``held``): the same alignment on both paths, for any hold ratio and latency."""
    if (ratio, n) not in _CFGS:
        _CFGS[ratio, n] = engine_core({"param_sets": ("RS",), "update_hz": 1000.0 * ratio}, n)
    drv = FbgDriver(_CFGS[ratio, n], [SA] * n, fs_hz=1000.0, latency_ticks=latency)
    rng = np.random.default_rng(seed)
    raw = rng.integers(-3, 4, (samples, n)) * 64
    rec = Recorder()
    drv.stream(rec, None, raw=raw)
    n_ticks = samples * ratio
    replay = np.zeros((n_ticks, n), dtype=np.int64)
    cur = np.zeros(n, dtype=np.int64)
    writes = {c[1]: c for c in rec.calls if c[0] == "write"}
    for k in range(n_ticks):
        if k in writes:
            _, _, first, vals = writes[k]
            cur[first:first + len(vals)] = vals
        replay[k] = cur
    assert np.array_equal(replay, drv.held(raw, n_ticks))


def test_online_chunks_give_exactly_the_whole_stream():
    """A live link feeds chunks: the filter state, held gaps and written currents carry over,
    so any split gives the same writes, spikes and saturation counts as one call."""
    rng = np.random.default_rng(9)
    cfg = _cfg(4)
    dl = np.cumsum(rng.uniform(0, 5e-4, (60, 4)), axis=0)
    dl[[7, 30, 31], 2] = np.nan
    drv = FbgDriver(cfg, [FA, FA, SA, FA], latency_ticks=3, on_gap="hold")
    rec_whole = Recorder()
    whole = drv.stream(rec_whole, dl)
    tr = TwinTransport()
    tr.open(cfg)
    ref = drv.stream(tr, dl)
    for cuts in ([1, 2, 30, 31, 59], [10, 20, 40], [30]):
        rec = Recorder()
        s = drv.online(rec)
        for part in np.split(dl, cuts):
            s.feed(part)
        r = s.finish()
        assert rec.calls == rec_whole.calls
        assert r.gaps_held == whole.gaps_held == 3 and r.saturations == whole.saturations
        tr = TwinTransport()
        tr.open(cfg)
        s = drv.online(tr)
        for part in np.split(dl, cuts):
            s.feed(part)
        got = s.finish().spikes
        assert np.array_equal(got.tick, ref.spikes.tick) and len(got) > 0
    s = FbgDriver(cfg, [FA] * 4).online(Recorder())
    s.feed(dl[:5, [0, 1, 3, 3]])
    with pytest.raises(GapError, match="sample 7 of channel 2 is missing"):
        s.feed(dl[5:10])
