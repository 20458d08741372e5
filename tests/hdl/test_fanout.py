"""The channel fan-out's configuration, twin and golden bound: refusals, hand-computed
currents, the threshold gate, and the twin within the derived bound of golden for random
tables and samples (Hypothesis)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cuneate.golden.fanout import fanout_currents
from cuneate.hdl.fanout import ConfigError, FanoutConfig, FanoutTwin
from cuneate.hdl.lib.fixed import QFormat


def _cfg(**kw):
    base = dict(n_channels=2, channel=[0, 1, 0], gain=[2.5, -4.0, 100.0])
    return FanoutConfig(**(base | kw))


def test_hand_computed_currents_and_flagged_clamps():
    cfg = _cfg(rectify=["none", "positive", "abs"])
    twin = FanoutTwin(cfg)
    twin.write_samples([3.0, -1.5])
    cur, below, above = twin.run()
    # 2.5 * 3 = 7.5; -4 * max(-1.5, 0) = 0; 100 * |3| = 300 (inside sQ10.8: max 511.996)
    assert cfg.I.to_float(cur).tolist() == [7.5, 0.0, 300.0]
    assert not below.any() and not above.any()
    twin.write_samples([-6.0, 1.0])
    cur, below, above = twin.run()
    # 2.5 * -6 = -15; -4 * 1 = -4; 100 * 6 = 600 -> clamped to 511.99609375, flagged
    assert cfg.I.to_float(cur).tolist() == [-15.0, -4.0, 511.99609375]
    assert above.tolist() == [False, False, True] and not below.any()
    assert twin.clamp_counts == {"current_low": 0, "current_high": 1}
    assert twin.clamp_sticky == 0b10


def test_the_gate_passes_exactly_at_the_threshold_on_the_sample_grid():
    # threshold 1.01 is between grid points (sQ11.5: 1/32): the first sample that passes is
    # 33/32 = 1.03125, the one below (1.0) is gated, as golden decides on the same samples
    cfg = _cfg(channel=[0], gain=[10.0], threshold=[1.01])
    twin = FanoutTwin(cfg)
    for s, want in ((1.0, 0.0), (1.03125, 10.3125), (-3.0, 0.0), (2.0, 20.0)):
        twin.write_samples([s, 0.0])
        got = cfg.I.to_float(twin.run()[0])[0]
        assert got == want == fanout_currents([s, 0.0], [0], [10.0], "none", [1.01])[0]


@pytest.mark.parametrize("kw,match", [
    ({"channel": [0, 2, 1]}, "afferent 1 listens to channel 2, outside 0 .. 1"),
    ({"gain": [1.0, 2.0]}, "gain has 2 entries for 3 afferents"),
    ({"gain": [1.0, math.inf, 2.0]}, "gain of afferent 1 is not finite"),
    ({"gain": [1.0, 1e307, 2.0]}, r"the gain of afferent 1, 1e\+307, times the largest sample "
                                  "1024 exceeds float64"),
    ({"gain": [1e5, 1.4, 1.0]}, r"gain\[1\] = 1.4 has relative representation error"),
    ({"threshold": [None, 2000.0, None]}, "afferent 1: threshold 2000 is outside"),
    ({"rectify": ["none", "square", "abs"]}, "afferent 1: unknown rectify 'square'"),
    ({"sample_hz": 1e7}, "a fan-out run of 3 afferents takes 8 cycles"),
    ({"gain": [1e-7, 2e-7, 1e-7]}, "every current would round to 0: the product of a sQ11.5"),
    ({"channel": [0] * 200_000, "gain": [1.0] * 200_000, "sample_hz": 100.0},
     "the fan-out table of 200000 afferents needs 7600000 bits"),
])
def test_refusals_name_what_cannot_be_built(kw, match):
    with pytest.raises(ConfigError, match=match):
        _cfg(**kw)


def test_the_clamp_is_built_only_where_it_can_act():
    small = _cfg(gain=[0.5, -0.25, 0.125], sample_max=8.0)      # |I| <= 4: never clamps
    assert not small.can_clamp and small.to_dict()["current_clamp_built"] is False
    assert _cfg().can_clamp


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_the_twin_stays_within_the_derived_bound_of_golden(data):
    n_ch = data.draw(st.integers(1, 5))
    n = data.draw(st.integers(1, 12))
    gains = data.draw(st.lists(st.floats(-300, 300, allow_nan=False).filter(
        lambda g: g == 0 or abs(g) > 1.0), min_size=n, max_size=n))
    cfg = FanoutConfig(
        n_channels=n_ch, channel=data.draw(st.lists(st.integers(0, n_ch - 1), min_size=n,
                                                    max_size=n)),
        gain=gains, rectify=data.draw(st.lists(st.sampled_from(["none", "positive", "abs"]),
                                               min_size=n, max_size=n)),
        threshold=data.draw(st.lists(st.one_of(st.none(), st.floats(-100, 100)), min_size=n,
                                     max_size=n)),
        rounding=data.draw(st.sampled_from(["nearest", "truncate"])),
        current_format=QFormat(12, 6), gain_width=24)   # gains 1 to 300 share an exponent
    twin = FanoutTwin(cfg)
    x = data.draw(st.lists(st.floats(-600, 600), min_size=n_ch, max_size=n_ch))
    raw = twin.write_samples(x)
    cur, below, above = twin.run()
    s = cfg.S.to_float(raw)
    th = [np.nan if t is None else t for t in cfg.thresholds_]
    from cuneate.golden.fanout import RECTIFY
    gold = fanout_currents(s, cfg.channels_, gains, [RECTIFY[m] for m in cfg.modes_], th)
    got = cfg.I.to_float(cur)
    bound = cfg.golden_bound(s)
    free = ~(below | above)
    assert np.all(np.abs(got - gold)[free] <= bound[free])
    # a clamp acts only where golden lies outside the current format
    assert np.all(gold[above] > cfg.I.max_value) and np.all(gold[below] < cfg.I.min_value)
    assert twin.clamp_counts == {"current_low": int(below.sum()),
                                 "current_high": int(above.sum())}
    # against the unquantized samples, away from the gates' thresholds
    xs = np.clip(np.asarray(x), cfg.S.min_value, cfg.S.max_value)
    gold_x = fanout_currents(xs, cfg.channels_, gains, [RECTIFY[m] for m in cfg.modes_], th)
    near = np.array([t is not None and abs(xs[c] - t) <= cfg.S.lsb
                     for t, c in zip(cfg.thresholds_, cfg.channels_)])
    ok = free & ~near
    assert np.all(np.abs(got - gold_x)[ok] <= cfg.sample_bound(xs)[ok])


def test_the_kwargs_rebuild_the_same_table():
    cfg = _cfg(rectify="abs", threshold=[None, 2.0, -1.0], rounding="truncate")
    again = FanoutConfig.from_kwargs(cfg.to_kwargs())
    assert again.table() == cfg.table() and again.to_dict() == cfg.to_dict()


def _exact_current(cfg, s_raw: int, n: int) -> tuple[int, bool, bool]:
    """Afferent ``n``'s raw current for the raw sample ``s_raw`` in Python integers (no width):
    the specification the twin must meet at every gain."""
    mode, g = cfg.modes_[n], cfg.gains_[n].raw
    r = s_raw if mode == 0 else max(s_raw, 0) if mode == 1 else abs(s_raw)
    if cfg.gated_[n] and s_raw < cfg.theta_raw[n]:
        r = 0
    p, sh = r * g, cfg.shift
    x = p << -sh if sh <= 0 else (p + (1 << (sh - 1))) >> sh if cfg.rounding == "nearest" \
        else p >> sh
    lo, hi = cfg.I.min_raw, cfg.I.max_raw
    return min(max(x, lo), hi), x < lo, x > hi


@settings(max_examples=80, deadline=None)
@given(exponent=st.integers(-3, 300), mantissa=st.floats(1.0, 9.99),
       rounding=st.sampled_from(["nearest", "truncate"]),
       samples=st.lists(st.integers(-(1 << 15), (1 << 15) - 1), min_size=2, max_size=2))
def test_the_twin_is_exact_at_every_gain(exponent, mantissa, rounding, samples):
    """Gains from 1e-3 to 1e300 (the shared exponent then adds up to ~1000 bits to the product):
    every current equals the unbounded-integer specification, every clamp counted (a gain of
    1e18 once wrapped in the twin's int64 to the opposite clamp or to 0)."""
    g = mantissa * 10.0 ** exponent
    cfg = FanoutConfig(n_channels=2, channel=[0, 1, 0, 1], gain=[g, -g, g / 2, 0.0],
                       rectify=["none", "abs", "positive", "none"], threshold=[None, None,
                                                                                 -3.0, None],
                       rounding=rounding)
    twin = FanoutTwin(cfg)
    for c, s in enumerate(samples):
        twin.write(c, s)
    cur, below, above = twin.run()
    want = [_exact_current(cfg, samples[cfg.channels_[n]], n) for n in range(cfg.n_neurons)]
    assert cur.tolist() == [w[0] for w in want]
    assert below.tolist() == [w[1] for w in want] and above.tolist() == [w[2] for w in want]
    assert twin.clamp_counts == {"current_low": sum(w[1] for w in want),
                                 "current_high": sum(w[2] for w in want)}


def test_a_gain_of_1e18_clamps_high_and_counts_it():
    """The case that wrapped: +1e18 x 3 gave -512 counted as a low clamp."""
    cfg = FanoutConfig(n_channels=1, channel=[0, 0], gain=[1e18, -1e18])
    twin = FanoutTwin(cfg)
    twin.write_samples([3.0])
    cur, below, above = twin.run()
    assert cur.tolist() == [cfg.I.max_raw, cfg.I.min_raw]
    assert above.tolist() == [True, False] and below.tolist() == [False, True]
