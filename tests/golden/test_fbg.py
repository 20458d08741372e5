"""Tests of the FBG front-end reference (cuneate.golden.fbg)."""

import cmath
import dataclasses
import json
import math

import numpy as np
import pytest
import scipy.signal

from cuneate.golden import fbg


# ----------------------------------------------------------------------------- Bragg physics

def test_bragg_strain_and_temperature_sensitivity():
    # 1 microstrain at 1550 nm, p_e = 0.22: 1550 nm * 0.78 * 1e-6 = 1.209e-3 nm = 1.209 pm
    assert fbg.bragg_shift_nm(1e-6) == pytest.approx(1550.0 * 0.78 * 1e-6, rel=1e-12)
    assert fbg.strain_sensitivity_pm_per_microstrain() == pytest.approx(1.209, rel=1e-9)
    # brief: about 1.2 pm/ue and about 10 pm/K
    assert fbg.strain_sensitivity_pm_per_microstrain() == pytest.approx(1.2, rel=0.02)
    assert fbg.temperature_sensitivity_pm_per_K() == pytest.approx(10.0, rel=0.05)
    # superposition of strain and temperature, vectorized
    eps = np.array([0.0, 1e-4, 2e-4])
    d = fbg.bragg_shift_nm(eps, delta_T_K=2.0)
    assert np.allclose(d, 1550.0 * (0.78 * eps + fbg.THERMO_PER_K * 2.0), rtol=1e-12)


@pytest.mark.parametrize("kwargs, pattern", [
    ({"strain": np.nan}, "strain"),
    ({"strain": 1e-6, "p_e": 1.0}, "p_e"),
    ({"strain": 1e-6, "lambda_B_nm": 0.0}, "lambda_B_nm"),
    ({"strain": 1e-6, "delta_T_K": np.inf}, "delta_T_K"),
])
def test_bragg_validation(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        fbg.bragg_shift_nm(**kwargs)


# ----------------------------------------------------------------------------- stability

def test_published_filter_poles_from_quadratic_formula():
    a1, a2 = -1.919, 0.91
    # poles are the roots of z^2 + a1 z + a2 = z^2 - 1.919 z + 0.91
    disc = a1 * a1 - 4 * a2                      # 3.682561 - 3.64 = 0.042561
    z1 = (-a1 + cmath.sqrt(disc)) / 2
    z2 = (-a1 - cmath.sqrt(disc)) / 2
    rep = fbg.PUBLISHED_BANDPASS.check()
    got = sorted(rep.poles, key=abs)
    exp = sorted([z1, z2], key=abs)
    for g, e in zip(got, exp):
        assert abs(g - e) < 1e-12
    # the radii multiply to a2 (Vieta); they would both equal sqrt(0.91) only if the poles were
    # complex conjugates, but the discriminant is positive: the poles are real, 1.0627 and 0.8563
    assert disc > 0
    assert rep.radii[0] * rep.radii[1] == pytest.approx(0.91, rel=1e-12)
    assert rep.max_radius == pytest.approx(abs(z1), rel=1e-12)
    assert rep.max_radius > 1.0
    # independent criterion: a second-order filter is stable iff |a2| < 1 and |a1| < 1 + a2
    assert not (abs(a2) < 1 and abs(a1) < 1 + a2)
    assert rep.stable is False and rep.verdict == "UNSTABLE"
    assert not fbg.PUBLISHED_BANDPASS.is_stable()


def test_published_filter_is_refused_with_pole_and_radius_in_message():
    r = (1.919 + math.sqrt(1.919 ** 2 - 4 * 0.91)) / 2
    with pytest.raises(fbg.UnstableFilterError) as ei:
        fbg.PUBLISHED_BANDPASS.apply(np.zeros(10))
    msg = str(ei.value)
    assert f"{r:.10g}" in msg and "pole" in msg
    assert isinstance(ei.value, ValueError)
    with pytest.raises(fbg.UnstableFilterError):
        fbg.FbgFrontEnd(filter=fbg.PUBLISHED_BANDPASS)


def test_default_bandpass_is_stable_and_close_to_published_numbers():
    f = fbg.DEFAULT_BANDPASS
    assert f.is_stable()
    # published b = [0.045, 0, -0.045], a[2] = 0.91, quoted to 3 decimals
    assert np.allclose(f.b, [0.045, 0.0, -0.045], atol=5e-4)
    assert f.a[2] == pytest.approx(0.91, abs=5e-4)
    # independent second-order stability triangle
    assert abs(f.a[2]) < 1 and abs(f.a[1]) < 1 + f.a[2]


def test_stable_complex_pair_radius():
    # z^2 - 1.8 z + 0.9: discriminant 3.24 - 3.6 < 0 -> complex pair with radius sqrt(0.9)
    rep = fbg.filter_check_report([1.0], [1.0, -1.8, 0.9])
    assert rep.stable
    assert np.allclose(rep.radii, math.sqrt(0.9), rtol=1e-12)
    assert rep.max_radius == pytest.approx(math.sqrt(0.9), rel=1e-12)


@pytest.mark.parametrize("a, radius", [
    ([1.0, -2.1, 1.2], math.sqrt(1.2)),          # complex pair outside: |z|^2 = 1.2
    ([1.0, -1.05], 1.05),                        # real pole at 1.05
])
def test_unstable_examples_refused(a, radius):
    filt = fbg.IIRFilter(b=[1.0], a=a)
    assert not filt.is_stable()
    assert filt.check().max_radius == pytest.approx(radius, rel=1e-12)
    with pytest.raises(fbg.UnstableFilterError, match=f"{radius:.10g}".replace(".", r"\.")):
        filt.require_stable()
    with pytest.raises(fbg.UnstableFilterError):
        filt.apply(np.ones(5))


@pytest.mark.parametrize("a", [[1.0, -1.0], [1.0, 0.0, 1.0], [1.0, 1.0], [1.0, -2.0, 1.0]])
def test_marginal_poles_on_unit_circle_refused(a):
    rep = fbg.filter_check_report([1.0], a)
    assert not rep.stable
    assert rep.max_radius == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(fbg.UnstableFilterError):
        fbg.IIRFilter(b=[1.0], a=a).apply(np.ones(4))


def test_fir_filter_has_no_poles_and_is_stable():
    rep = fbg.filter_check_report([0.5, 0.5], [1.0])
    assert rep.stable and rep.poles == () and rep.max_radius == 0.0


def test_report_text_and_dict():
    rep = fbg.PUBLISHED_BANDPASS.check()
    text = rep.to_text()
    for z, r in zip(rep.poles, rep.radii):
        assert f"{r:.10g}" in text
        assert f"{z.real:.10g}" in text
    assert "UNSTABLE" in text
    d = json.loads(json.dumps(rep.to_dict()))
    assert d["stable"] is False and d["verdict"] == "UNSTABLE"
    assert len(d["poles"]) == 2
    assert max(p["radius"] for p in d["poles"]) == pytest.approx(rep.max_radius)
    good = fbg.DEFAULT_BANDPASS.check()
    assert "verdict: stable" in good.to_text()
    assert good.to_dict()["verdict"] == "stable"


def test_filter_check_report_accepts_strings():
    rep = fbg.filter_check_report("0.045, 0, -0.045", "[1 -1.919 0.91]")
    assert rep.a == (1.0, -1.919, 0.91)
    assert not rep.stable


@pytest.mark.parametrize("b, a, pattern", [
    ([], [1.0], "b coefficients are empty"),
    ([1.0], [], "a coefficients are empty"),
    ([1.0, np.nan], [1.0], r"b\[1\] is not finite"),
    ([1.0], [1.0, np.inf], r"a\[1\] is not finite"),
    ([1.0], [0.0, 1.0], r"a\[0\] must be non-zero"),
    ([[1.0, 2.0]], [1.0], "1-D"),
    ("1, x", [1.0], "cannot parse"),
])
def test_bad_coefficients(b, a, pattern):
    with pytest.raises(ValueError, match=pattern):
        fbg.IIRFilter(b=b, a=a)


def test_filter_normalized_frozen_and_read_only():
    f = fbg.IIRFilter(b=[2.0, 4.0], a=[2.0, -1.0])
    assert f.a[0] == 1.0
    assert np.array_equal(f.b, [1.0, 2.0]) and np.array_equal(f.a, [1.0, -0.5])
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.b = np.array([1.0])
    with pytest.raises(ValueError):
        f.b[0] = 3.0
    assert f == fbg.IIRFilter(b=[1.0, 2.0], a=[1.0, -0.5])


# ----------------------------------------------------------------------------- design

@pytest.mark.parametrize("low, high, order, kind", [
    (1.0, 16.0, 1, "butter"), (5.0, 50.0, 2, "butter"), (20.0, 100.0, 2, "bessel"),
    (10.0, 40.0, 2, "cheby1"),
])
def test_designed_bandpass_stable_with_peak_near_centre(low, high, order, kind):
    fs = 1000.0
    f = fbg.design_bandpass(low, high, fs, order=order, kind=kind)
    assert f.is_stable()
    assert len(f.a) == 2 * order + 1
    freqs, h = scipy.signal.freqz(f.b, f.a, worN=2 ** 16, fs=fs)
    f_peak = freqs[np.argmax(np.abs(h))]
    # digital centre of a bilinear band-pass: tan^2(pi f0/fs) = tan(pi f1/fs) tan(pi f2/fs)
    f0 = fs / math.pi * math.atan(math.sqrt(math.tan(math.pi * low / fs)
                                            * math.tan(math.pi * high / fs)))
    assert low < f_peak < high
    if kind == "butter":
        assert f_peak == pytest.approx(f0, rel=0.02)
        assert np.abs(h).max() == pytest.approx(1.0, abs=1e-3)
        # -3 dB at the band edges
        for edge in (low, high):
            g = np.abs(scipy.signal.freqz(f.b, f.a, worN=[edge], fs=fs)[1][0])
            assert g == pytest.approx(1 / math.sqrt(2), rel=1e-6)
    # far outside the band the gain is small
    g_dc = np.abs(h[0])
    assert g_dc < 1e-6


@pytest.mark.parametrize("low, high, fs, kwargs, pattern", [
    (10.0, 5.0, 1000.0, {}, "0 < low_hz < high_hz"),
    (0.0, 5.0, 1000.0, {}, "0 < low_hz < high_hz"),
    (10.0, 500.0, 1000.0, {}, "0 < low_hz < high_hz"),
    (10.0, 50.0, -1.0, {}, "fs_hz"),
    (10.0, 50.0, 1000.0, {"order": 0}, "order"),
    (10.0, 50.0, 1000.0, {"kind": "fir"}, "kind"),
    (np.nan, 50.0, 1000.0, {}, "low_hz"),
])
def test_design_validation(low, high, fs, kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        fbg.design_bandpass(low, high, fs, **kwargs)


# ----------------------------------------------------------------------------- apply

def _difference_equation(b, a, x):
    """Direct-form I: a0 y[n] = sum_k b[k] x[n-k] - sum_{k>=1} a[k] y[n-k]."""
    y = np.zeros(len(x))
    for n in range(len(x)):
        acc = 0.0
        for k in range(len(b)):
            if n - k >= 0:
                acc += b[k] * x[n - k]
        for k in range(1, len(a)):
            if n - k >= 0:
                acc -= a[k] * y[n - k]
        y[n] = acc / a[0]
    return y


@pytest.mark.parametrize("b, a", [
    ([0.04503500591, 0.0, -0.04503500591], [1.0, -1.909326365, 0.9099299882]),
    ([0.2, 0.4, 0.2], [2.0, -1.0, 0.5]),                      # a[0] != 1 gets normalized
    ([1.0, -0.5], [1.0, -0.3, 0.1, -0.05]),
])
def test_apply_matches_hand_rolled_difference_equation(b, a):
    rng = np.random.default_rng(1234)
    x = rng.normal(size=300)
    f = fbg.IIRFilter(b=b, a=a)
    assert np.allclose(f.apply(x), _difference_equation(b, a, x), rtol=1e-10, atol=1e-12)
    # vectorized over gratings: each column filtered independently along axis 0
    X = np.column_stack([x, 2.0 * x[::-1], np.zeros_like(x)])
    Y = f.apply(X)
    for j in range(3):
        assert np.allclose(Y[:, j], _difference_equation(b, a, X[:, j]), rtol=1e-10, atol=1e-12)


def test_apply_refuses_non_finite_with_index():
    x = np.zeros(200)
    x[123] = np.nan
    with pytest.raises(ValueError, match="sample index 123"):
        fbg.DEFAULT_BANDPASS.apply(x)


# ----------------------------------------------------------------------------- front end

def _ramp_hold(slope_nm_per_ms, n=2000, target=0.01, start=100):
    t = np.arange(n, dtype=float)       # ms at 1 kHz
    return np.clip((t - start) * slope_nm_per_ms, 0.0, target)


def test_steeper_ramp_gives_larger_current_peak():
    fe = fbg.FbgFrontEnd()
    slopes = [0.01 / 800, 0.01 / 300, 0.01 / 100, 0.01 / 40]       # plateau 0.01 nm
    peaks = [fe.currents(_ramp_hold(s)).max() for s in slopes]
    assert all(p > 0 for p in peaks)
    assert all(p2 > p1 for p1, p2 in zip(peaks, peaks[1:]))


def test_front_end_is_filter_times_gain_and_vectorized():
    fe = fbg.FbgFrontEnd(gain=180.0)
    x = np.column_stack([_ramp_hold(0.01 / 100), _ramp_hold(0.01 / 300)])
    out = fe.currents(x)
    assert out.shape == x.shape
    for j in range(2):
        ref = 180.0 * _difference_equation(fe.filter.b, fe.filter.a, x[:, j])
        assert np.allclose(out[:, j], ref, rtol=1e-10, atol=1e-12)
    assert fe.dt_ms == 1.0
    assert fbg.DEFAULT_GAIN_S == 180.0


def test_front_end_refuses_bad_traces_and_parameters():
    fe = fbg.FbgFrontEnd()
    x = np.zeros((50, 2))
    x[17, 1] = np.inf
    with pytest.raises(ValueError, match=r"sample index 17 \(grating 1\)"):
        fe.currents(x)
    with pytest.raises(ValueError, match="shape"):
        fe.currents(np.zeros((3, 3, 3)))
    with pytest.raises(ValueError, match="empty"):
        fe.currents(np.zeros(0))
    with pytest.raises(ValueError, match="gain"):
        fbg.FbgFrontEnd(gain=np.nan)
    with pytest.raises(ValueError, match="fs_hz"):
        fbg.FbgFrontEnd(fs_hz=0.0)
    with pytest.raises(ValueError, match="IIRFilter"):
        fbg.FbgFrontEnd(filter=([1.0], [1.0]))
