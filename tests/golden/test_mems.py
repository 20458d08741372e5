"""The MEMS fingertip: the seeds' opponent pairs, tethers, the cover in space and in time, the
effects it has."""

import numpy as np
import pytest

from cuneate.golden import mems, tactile
from cuneate.golden.mems import (FINGERTIP, cover_filter, cover_transfer, opponent_pairs,
                                 opponent_signals, pair_names, tether_outputs, viscoelastic)


def test_the_sliding_pairs_are_the_seeds_channels():
    assert pair_names()[:4] == ["x s0: 2-4", "x s1: 5-7", "x s2: 12-10", "x s3: 15-13"]
    ang = FINGERTIP.tether_angles_deg
    for s, (p, m) in enumerate(opponent_pairs()):
        if s < 4:       # the plus tether faces +x, the minus one -x
            assert (ang.flat[p], ang.flat[m]) == (0.0, 180.0)
        else:
            assert (ang.flat[p], ang.flat[m]) == (90.0, 270.0)
    assert sorted(c for pair in opponent_pairs() for c in pair) == list(range(16))


def test_shear_drives_its_pair_and_the_normal_load_cancels_but_for_the_mismatch():
    n = np.full((5, 4), 0.1)
    tx = np.zeros((5, 4))
    tx[:, 2] = 0.05
    ty = np.zeros((5, 4))
    ty[:, 3] = -0.02
    v = tether_outputs(n, tx, ty)
    assert v.shape == (5, 16)
    S = opponent_signals(v)
    g = FINGERTIP.gains()
    (p, m) = opponent_pairs()[2]
    expect = FINGERTIP.G_t_V_per_N * 0.05 * (g.flat[p] + g.flat[m]) \
        + FINGERTIP.G_n_V_per_N * 0.1 * (g.flat[p] - g.flat[m])
    assert S[0, 2] == pytest.approx(expect)
    (p, m) = opponent_pairs()[7]                  # sensor 3 across: +y minus -y
    assert S[0, 7] == pytest.approx(FINGERTIP.G_t_V_per_N * -0.02 * (g.flat[p] + g.flat[m])
                                     + FINGERTIP.G_n_V_per_N * 0.1 * (g.flat[p] - g.flat[m]))
    # without shear only the mismatch leaks the normal load (3 % gains: a few % of G_n n)
    leak = opponent_signals(tether_outputs(n, 0 * n, 0 * n))
    assert np.abs(leak).max() < 0.15 * FINGERTIP.G_n_V_per_N * 0.1


def test_the_cover_transfer_and_filter():
    assert cover_transfer(0.0, 0.45) == 1.0
    f = np.linspace(0, 5, 50)
    assert np.all(np.diff(cover_transfer(f, 0.45)) < 0)
    assert cover_transfer(1 / (2 * np.pi * 0.5), 0.5) == pytest.approx(2 / np.e)
    x = np.arange(400) * 0.025
    h = 10.0 + 5.0 * np.cos(2 * np.pi * x / 2.5)[None, :] * np.ones((20, 1))
    hf = cover_filter(h, 0.025, 0.45)
    assert hf.mean() == pytest.approx(10.0)
    assert np.ptp(hf[5]) / 2 == pytest.approx(5.0 * cover_transfer(1 / 2.5, 0.45), rel=1e-6)


def test_the_cover_relaxes_from_its_instantaneous_to_its_relaxed_stiffness():
    fs = 2000.0
    h = np.r_[np.zeros(10), np.ones(2000)]
    load = viscoelastic(h, fs)
    a = FINGERTIP.relax_ms / (FINGERTIP.relax_ms + 1000.0 / fs)     # the high-pass's pole
    assert load[10] == pytest.approx(FINGERTIP.k_relaxed_N_per_um + a * FINGERTIP.k_extra_N_per_um)
    assert load[-1] == pytest.approx(FINGERTIP.k_relaxed_N_per_um, rel=1e-6)
    tau = 10 + int(FINGERTIP.relax_ms * fs / 1000)              # one time constant later
    extra = (load[tau] - FINGERTIP.k_relaxed_N_per_um) / FINGERTIP.k_extra_N_per_um
    assert extra == pytest.approx(np.exp(-1), abs=0.02)


def test_only_the_listed_effects_run_in_millivolts(monkeypatch):
    calls = []
    for name in tactile.EFFECTS:
        def spy(x, p, rng, fs, ctx, name=name):
            calls.append((name, dict(p)))
            return x, {}
        monkeypatch.setitem(tactile.EFFECTS, name, spy)
    rng = np.random.default_rng(0)
    v, counts = mems.sensor_effects(np.zeros((4, 16)), ["noise"], {"noise": {"sigma_mV": 2.0}},
                                    rng, 2000.0)
    assert calls == [("noise", {"sigma": 2e-3})] and counts == {"noise": {"sigma_mV": 2.0}}
    with pytest.raises(ValueError, match="'temperature' is not a MEMS fingertip's"):
        mems.sensor_effects(np.zeros((4, 16)), ["temperature"], {}, rng, 2000.0)


def test_effects_act_in_volts():
    rng = np.random.default_rng(1)
    v = np.full((2000, 16), 1e-3)
    out, c = mems.sensor_effects(v, ["noise", "saturation", "resolution"],
                                 {"noise": {"sigma_mV": 0.1}, "saturation": {"max_mV": 1.1},
                                  "resolution": {"step_mV": 0.05}}, rng, 2000.0)
    assert out.max() <= 1.1e-3 + 1e-12 and c["saturation"]["samples_clipped"] > 0
    assert np.allclose(out / 5e-5, np.round(out / 5e-5))
    assert np.std(out - 1e-3) == pytest.approx(1e-4, rel=0.15)
