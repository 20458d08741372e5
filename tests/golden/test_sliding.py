"""A texture slid under the fingertip: the protocol's phases, normal load, friction with
stick-slip, slopes."""

import numpy as np
import pytest

from cuneate.golden.sliding import Protocol, prepare, slide_loads, smoothstep, surface_extent
from cuneate.golden.textures import TEXTURES, surface, texture

FS = 2000.0
STILL = Protocol(slide_mm=4.0, spread_force=0, spread_velocity=0, spread_friction=0,
                 jitter_mm=0)


def _prep(name, prot=STILL):
    return prepare(surface(texture(name), 1, *surface_extent(prot)))


def test_the_protocols_phases():
    ph = STILL.phases_ms()
    assert list(ph) == ["rest", "indentation", "hold", "slide", "hold_after", "retraction"]
    assert ph["slide"] == (350.0, 350.0 + 4.0 / 15.0 * 1000.0)
    assert STILL.duration_ms == ph["retraction"][1]
    assert smoothstep(np.array([-1.0, 0.0, 0.5, 1.0, 2.0])).tolist() == [0, 0, 0.5, 1, 1]


def test_flat_sliding_is_kinetic_friction_on_each_sensors_share():
    n, tx, ty, info = slide_loads(_prep("controller"), STILL, np.random.default_rng(0), FS)
    t = np.arange(n.shape[0]) / FS * 1000.0
    t0, t1 = info["phases_ms"]["slide"]
    assert n[0].max() == 0.0 and n[-1].max() < 1e-4 * 0.4       # no contact at rest and after
    hold = (t > 300) & (t < 340)
    assert n[hold].sum(axis=1) == pytest.approx(0.4, rel=1e-3)  # the force, shared by four
    assert np.abs(tx[hold]).max() < 1e-3                         # no friction before the slide
    mid = (t > t0 + 50) & (t < t1)
    mu = tx[mid] / n[mid]
    assert mu.mean() == pytest.approx(TEXTURES["controller"].mu_kinetic, abs=0.01)
    assert info["slips"] == 0 and np.abs(ty).max() < 1e-3


def test_latex_sticks_and_slips_between_its_static_and_kinetic_levels():
    n, tx, _, info = slide_loads(_prep("latex"), STILL, np.random.default_rng(0), FS)
    t = np.arange(n.shape[0]) / FS * 1000.0
    t0, t1 = info["phases_ms"]["slide"]
    mid = (t > t0 + 20) & (t < t1)
    r = np.where(mid, tx.sum(axis=1), 0.0) / np.where(mid, n.sum(axis=1), 1.0)
    lat = TEXTURES["latex"]
    assert info["slips"] > 20
    assert r[mid].max() < lat.mu_static * 1.6 and r[mid].min() > 2 * lat.mu_kinetic - \
        1.6 * lat.mu_static
    assert np.ptp(r[mid]) > 0.2                                  # a sawtooth, not a level


def test_a_weave_modulates_the_load_and_shear_where_it_passes():
    n, tx, _, info = slide_loads(_prep("corduroy"), STILL, np.random.default_rng(0), FS)
    t = np.arange(n.shape[0]) / FS * 1000.0
    t0, t1 = info["phases_ms"]["slide"]
    mid = (t > t0) & (t < t1)
    assert np.ptp(n[mid, 0]) > 0.02 and np.ptp(tx[mid, 0]) > 0.02
    # sensors 0 and 1 sit a pitch apart along the slide: sensor 1 meets what sensor 0 met a
    # pitch's travel earlier
    lag = int(round(2.2 / 15.0 * FS))
    a, b = tx[mid, 1][lag:], tx[mid, 0][:-lag]
    assert np.corrcoef(a, b)[0, 1] > 0.9


def test_trials_are_the_seeded_generators_and_vary_by_the_spreads():
    prot = Protocol(slide_mm=4.0)
    prep = _prep("twill", prot)
    a = slide_loads(prep, prot, np.random.default_rng(5), FS)
    b = slide_loads(prep, prot, np.random.default_rng(5), FS)
    c = slide_loads(prep, prot, np.random.default_rng(6), FS)
    np.testing.assert_array_equal(a[1], b[1])
    assert a[3]["force_N"] != c[3]["force_N"] and not np.array_equal(a[1], c[1])
    # without spreads (and without stick-slip, whose events are drawn) two trials are one
    smooth = prepare(surface(texture({"name": "t", "like": "twill", "mu_static": 0.58}), 1,
                             *surface_extent(STILL)))
    d = slide_loads(smooth, STILL, np.random.default_rng(1), FS)
    e = slide_loads(smooth, STILL, np.random.default_rng(2), FS)
    np.testing.assert_array_equal(d[1], e[1])
