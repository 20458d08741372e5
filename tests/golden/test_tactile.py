"""Physics synthesis of FBG traces: stiffness chain, Bragg scaling, stop shift, spreads,
effects computed only when listed, and the current range of the published gain."""

import numpy as np
import pytest

from cuneate.golden import tactile
from cuneate.golden.fbg import DEFAULT_BANDPASS, FbgFrontEnd
from cuneate.golden.izhikevich import simulate
from cuneate.golden.tactile import (MATERIALS, GraspSpec, Pad, apply_effects, contact_stiffness,
                                    series_stiffness, synthesize_grasp)

NO_SPREAD = GraspSpec(spread_velocity=0, spread_pad=0, spread_young=0, spread_coupling=0)


def test_contact_and_series_stiffness_by_hand():
    m = MATERIALS["dragon_skin"]
    # (pi/4) * 0.34e6 / (1 - 0.49^2) * 0.015
    assert contact_stiffness(m, 0.015) == pytest.approx(0.7853981634 * 0.34e6 / 0.7599 * 0.015)
    assert series_stiffness(2.0, 2.0) == pytest.approx(1.0)
    assert Pad().stiffness_N_per_m == pytest.approx(1e6 * 225e-6 / 3e-3)


def test_grasp_stops_at_threshold_and_scales_with_bragg_relation():
    rng = np.random.default_rng(0)
    strain, info = synthesize_grasp(MATERIALS["vytaflex"], NO_SPREAD, rng)
    tr = apply_effects(strain, ["strain"], {}, rng, 1000.0)
    # 1550 nm * (1 - 0.22) = 1209 nm per unit strain
    assert np.allclose(tr.d_lambda_nm, strain * 1209.0)
    # the first (most coupled) grating stops at 0.01 nm; the other holds in proportion
    assert tr.d_lambda_nm[:, 0].max() == pytest.approx(0.01, rel=1e-9)
    assert tr.d_lambda_nm[:, 1].max() == pytest.approx(0.01 * 1.6 / 2.0, rel=1e-9)
    # before contact nothing, after the stop the shift holds
    assert np.all(tr.d_lambda_nm[:50] == 0)
    stop = int(np.ceil(info["stop_ms"]))
    assert np.all(tr.d_lambda_nm[stop + 1:, 0] == tr.d_lambda_nm[-1, 0])
    # loading time = stop force / (k_eff v)
    k = series_stiffness(Pad().stiffness_N_per_m, contact_stiffness(MATERIALS["vytaflex"], 0.015))
    f_stop = 0.01 / (2.0e-6 * 1209.0)
    assert info["loading_ms"] == pytest.approx(1000 * f_stop / k / 1.5e-3)


def test_stiffer_objects_load_faster_and_abs_aluminium_are_close():
    rng = np.random.default_rng(0)
    load = {n: synthesize_grasp(m, NO_SPREAD, rng)[1]["loading_ms"] for n, m in MATERIALS.items()}
    assert load["dragon_skin"] > load["vytaflex"] > load["abs"] > load["aluminium"]
    assert load["dragon_skin"] > 3 * load["vytaflex"]
    assert load["abs"] / load["aluminium"] < 1.05      # both far stiffer than the pad


def test_trials_vary_within_spreads_and_seed_repeats():
    a = [synthesize_grasp(MATERIALS["abs"], GraspSpec(), np.random.default_rng(5))[1]
         for _ in range(2)]
    assert a[0] == a[1]
    rng = np.random.default_rng(1)
    v = [synthesize_grasp(MATERIALS["abs"], GraspSpec(), rng)[1]["velocity_m_per_s"]
         for _ in range(200)]
    assert np.std(v) / np.mean(v) == pytest.approx(0.05, rel=0.25)


def test_unlisted_effects_are_never_called(monkeypatch):
    calls = []

    def spy(name):
        def f(x, p, rng, fs, ctx):
            calls.append(name)
            return x, {}
        return f
    for name in tactile.EFFECTS:
        monkeypatch.setitem(tactile.EFFECTS, name, spy(name))
    rng = np.random.default_rng(0)
    tr = apply_effects(np.zeros((10, 2)), ["strain", "noise"], {}, rng, 1000.0)
    assert calls == ["noise"]
    assert list(tr.effect_counts) == ["strain", "noise"]
    calls.clear()
    apply_effects(np.zeros((10, 2)), ["strain"], {}, rng, 1000.0)
    assert calls == []


def test_effects_do_what_they_say():
    rng = np.random.default_rng(0)
    strain = np.full((1000, 2), 5e-6)
    tr = apply_effects(strain, ["strain", "resolution"], {"resolution": {"step_pm": 1.0}}, rng,
                       1000.0)
    assert np.allclose(tr.d_lambda_nm * 1e3, np.round(5e-6 * 1209.0 * 1e3))
    tr = apply_effects(strain, ["strain", "temperature"],
                       {"temperature": {"offset_K": 1.0}}, rng, 1000.0)
    assert np.allclose(tr.d_lambda_nm - 5e-6 * 1209.0, 1550 * 6.5e-6)    # ~10 pm/K
    tr = apply_effects(strain, ["strain", "dropped_samples"],
                       {"dropped_samples": {"probability": 0.1}}, rng, 1000.0)
    n = tr.effect_counts["dropped_samples"]["samples_dropped"]
    assert n == int(np.isnan(tr.d_lambda_nm[:, 0]).sum()) and 50 < n < 150
    with pytest.raises(ValueError, match="must include 'strain'"):
        apply_effects(strain, ["noise"], {}, rng, 1000.0)


def _peak_currents(unit_pm):
    rng = np.random.default_rng(0)
    fe = FbgFrontEnd(DEFAULT_BANDPASS, 180.0)
    out = {}
    for n, m in MATERIALS.items():
        strain, _ = synthesize_grasp(m, NO_SPREAD, rng)
        dl = apply_effects(strain, ["strain"], {}, rng, 1000.0).d_lambda_nm
        out[n] = fe.currents(dl * 1e3 / unit_pm).max()
    return out


def test_published_gain_needs_ten_picometre_units():
    rheobase = 3.8    # RS, forward Euler at 1/16 ms: 3.7 gives one spike, 3.8 tonic firing
    assert len(simulate("RS", 3.7, duration_ms=1000).spikes_ms[0]) <= 1
    assert len(simulate("RS", 3.8, duration_ms=1000).spikes_ms[0]) >= 5
    nm = _peak_currents(1000.0)
    assert max(nm.values()) < rheobase            # Δλ in nm: no FA neuron ever fires
    pm = _peak_currents(1.0)
    assert max(pm.values()) > 512                 # Δλ in pm: beyond the sQ10.8 format
    ten = _peak_currents(10.0)                    # Δλ in units of 10 pm: the spiking range
    assert all(4 * rheobase < v < 200 for v in ten.values()), ten


def test_pulse_force_profile_by_hand():
    spec = tactile.PulseSpec(start_ms=10, width_ms=20, edge_ms=4, coupling_microstrain_per_N=(
        2.0,), duration_ms=40, spread_force=0.0)
    strain, info = tactile.synthesize_pulse(spec, np.random.default_rng(0), 1.5)
    f = strain[:, 0] / 2e-6
    assert info["amplitude_N"] == 1.5
    assert np.allclose(f[:11], 0) and f[12] == pytest.approx(0.75) and f[14] == pytest.approx(1.5)
    assert np.allclose(f[14:27], 1.5) and f[28] == pytest.approx(0.75) and np.allclose(f[30:], 0)


def test_slide_vibrates_at_speed_over_period_and_second_grating_lags():
    spec = tactile.SlideSpec(spread_speed=0, spread_force=0, duration_ms=1000, ramp_ms=1)
    strain, info = tactile.synthesize_slide(spec, np.random.default_rng(0), 2e-3)
    assert info["vibration_hz"] == pytest.approx(10.0)
    x = strain[200:, 0] - strain[200:, 0].mean()
    spec_f = np.abs(np.fft.rfft(x))
    freqs = np.fft.rfftfreq(x.size, 1e-3)
    assert freqs[np.argmax(spec_f)] == pytest.approx(10.0, abs=1.5)
    # grating 1 sits 2 mm behind: it sees the texture 100 ms later (one full period at 2 mm)
    assert np.allclose(strain[300:900, 1], strain[200:800, 0], atol=1e-9)
