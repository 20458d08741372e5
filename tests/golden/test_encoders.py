"""Tests of the SA/FA mechanoreceptor encoders (cuneate.golden.encoders)."""

import numpy as np
import pytest

from cuneate.golden import encoders as enc


def test_opponent_difference_is_channel_difference():
    a = np.array([1.0, 2.0, 5.0])
    b = np.array([0.5, 3.0, 1.0])
    assert np.array_equal(enc.opponent_difference(a, b), [0.5, -1.0, 4.0])


def test_opponent_difference_shape_mismatch():
    with pytest.raises(ValueError, match="same shape"):
        enc.opponent_difference(np.zeros(3), np.zeros(4))


def test_sa_zero_below_threshold_linear_above():
    s = np.linspace(-1.0, 1.0, 41)
    K, R, th = 12000.0, 2.0, 0.25
    i = enc.sa_current(s, gain_K=K, R_ohm=R, threshold=th)
    below = s < th
    assert np.all(i[below] == 0.0)
    # linear above threshold with slope K/R = 6000 and no offset
    assert np.allclose(i[~below], 6000.0 * s[~below], rtol=0, atol=1e-9)
    # the comparison is >=: a sample exactly at the threshold is encoded
    assert enc.sa_current([0.25], gain_K=K, R_ohm=R, threshold=0.25)[0] == 1500.0


def test_sa_per_channel_shape_preserved():
    s = np.array([[0.0, 1.0], [2.0, -1.0]])
    i = enc.sa_current(s, gain_K=10.0)
    assert i.shape == (2, 2)
    assert np.array_equal(i, [[0.0, 10.0], [20.0, 0.0]])


def test_fa_ramp_gives_constant_plateau():
    dt = 0.05
    slope = 0.2                     # signal units per ms
    t = np.arange(200) * dt
    ramp = slope * t
    i = enc.fa_current(ramp, dt, gain=1000.0, tau_ms=2.0, Cm=1.0)
    assert i[0] == 0.0              # stated convention: first sample 0
    # (tau/Cm) * G * slope = 2 * 1000 * 0.2 = 400
    assert np.allclose(i[1:], 400.0, rtol=1e-9)


def test_fa_constant_signal_is_zero():
    i = enc.fa_current(np.full((50, 3), 7.5), 0.05, gain=1e4)
    assert i.shape == (50, 3)
    assert np.all(i == 0.0)


def test_fa_step_onset_and_offset_with_abs_rectification():
    dt = 0.05
    s = np.zeros(100)
    s[30:60] = 1.0                  # step up at sample 30, down at sample 60
    raw = enc.fa_current(s, dt, gain=10.0, tau_ms=1.0)
    nz = np.flatnonzero(raw)
    assert list(nz) == [30, 60]
    assert raw[30] == pytest.approx(10.0 / dt)
    assert raw[60] == pytest.approx(-10.0 / dt)
    ab = enc.fa_current(s, dt, gain=10.0, tau_ms=1.0, rectify="abs")
    assert list(np.flatnonzero(ab)) == [30, 60]
    assert ab[30] == ab[60] == pytest.approx(10.0 / dt)
    pos = enc.fa_current(s, dt, gain=10.0, tau_ms=1.0, rectify="positive")
    assert list(np.flatnonzero(pos)) == [30]


def test_fa_backward_difference_is_causal():
    s = np.zeros(20)
    s[10] = 1.0
    i = enc.fa_current(s, 1.0, gain=1.0)
    assert np.all(i[:10] == 0.0)    # nothing before the change


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_signal_refused_with_index(bad):
    s = np.zeros(10)
    s[7] = bad
    with pytest.raises(ValueError, match="sample 7"):
        enc.sa_current(s)
    with pytest.raises(ValueError, match="sample 7"):
        enc.fa_current(s, 0.05)


@pytest.mark.parametrize("kwargs, pattern", [
    ({"dt_ms": 0.0}, "dt_ms"),
    ({"dt_ms": -1.0}, "dt_ms"),
    ({"dt_ms": 0.05, "tau_ms": -2.0}, "tau_ms"),
    ({"dt_ms": 0.05, "Cm": 0.0}, "Cm"),
    ({"dt_ms": 0.05, "gain": np.nan}, "gain"),
    ({"dt_ms": 0.05, "rectify": "half"}, "rectify"),
])
def test_fa_bad_parameters(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        enc.fa_current(np.zeros(5), **kwargs)


def test_bad_shapes_and_parameters():
    with pytest.raises(ValueError, match="shape"):
        enc.sa_current(np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match="empty"):
        enc.sa_current(np.zeros(0))
    with pytest.raises(ValueError, match="R_ohm"):
        enc.sa_current(np.zeros(3), R_ohm=0.0)
    with pytest.raises(ValueError, match="threshold"):
        enc.sa_current(np.zeros(3), threshold=np.nan)


def test_overflow_is_not_silent():
    with pytest.raises(ValueError, match="overflow"):
        enc.sa_current([1e305], gain_K=1e10)
    with pytest.raises(ValueError, match="overflow"):
        enc.fa_current([0.0, 1e300], 1e-10, gain=1e10)
