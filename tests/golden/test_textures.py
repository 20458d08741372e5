"""The ten synthetic textures: seeded specimens, the stated spectra and periods, variants."""

import numpy as np
import pytest

from cuneate.golden.textures import TEXTURES, Texture, fractal_field, surface, texture

X, Y = (-8.0, 8.0), (-3.0, 3.0)


def test_a_specimen_is_its_seed_and_name():
    a = surface(TEXTURES["twill"], 1, X, Y)
    b = surface(TEXTURES["twill"], 1, X, Y)
    c = surface(TEXTURES["twill"], 2, X, Y)
    np.testing.assert_array_equal(a.h_um, b.h_um)
    assert np.abs(a.h_um - c.h_um).max() > 10.0          # another specimen of the same weave
    assert a.info["seed"] == 1 and a.h_um.shape == (241, 641)
    assert a.x_mm[0] == X[0] and a.x_mm[1] - a.x_mm[0] == pytest.approx(0.025)


def test_the_ten_are_the_briefs_families_with_distinct_frictions():
    fam = [t.family for t in TEXTURES.values()]
    assert fam.count("textile") == 5 and fam.count("polymer") == 3
    assert "glass" in fam and "paper" in fam
    mu = {n: t.mu_kinetic for n, t in TEXTURES.items()}
    # latex high, bioskin medium, the controller's cover low
    assert mu["latex"] > mu["bioskin"] > mu["controller"]
    assert TEXTURES["latex"].mu_static - TEXTURES["latex"].mu_kinetic > 0.2   # stick-slip


def test_a_weave_has_its_period_along_its_orientation():
    t = texture({"name": "rib", "like": "corduroy", "rough_rms_um": 0.0, "cross": 0.0,
                 "harmonics": [1.0]})
    s = surface(t, 3, (0.0, 26.0 - 0.025), (0.0, 1.0))
    row = s.h_um[0] - s.h_um[0].mean()
    f = np.fft.rfftfreq(row.size, s.dx_mm)
    peak = f[np.argmax(np.abs(np.fft.rfft(row)))]
    assert peak == pytest.approx(1 / t.period_u_mm, rel=0.02)
    assert row.max() == pytest.approx(t.amplitude_um, rel=0.02)
    # turned by 90 degrees the same ribs run along the slide: no change along x
    s90 = surface(texture({"name": "r90", "like": t, "angle_deg": 90}), 3, (0.0, 5.0),
                  (0.0, 5.0))
    assert np.ptp(s90.h_um[10]) < 1e-9 * t.amplitude_um


def test_fractal_fields_have_the_stated_rms_band_and_slope():
    rng = np.random.default_rng(0)
    h = fractal_field(rng, (256, 1024), 0.025, 5.0, 0.7, 0.1, 4.0)
    assert h.std() == pytest.approx(5.0)
    F = np.abs(np.fft.rfft2(h)) ** 2
    k = np.hypot(np.fft.fftfreq(256, 0.025)[:, None], np.fft.rfftfreq(1024, 0.025)[None])
    assert F[k > 1 / 0.1 * 1.05].max() < 1e-20 * F.max()          # nothing above 1/lambda_hi
    band = (k > 0.5) & (k < 8)
    slope = np.polyfit(np.log(k[band]), np.log(F[band]), 1)[0]
    assert slope == pytest.approx(-2 * (1 + 0.7), abs=0.15)        # P(k) ~ k^-(2 + 2H)
    assert not fractal_field(rng, (8, 8), 0.1, 0.0, 0.7, 0.2, 1.0).any()


def test_glass_is_nearly_flat_and_paper_rough():
    g = surface(TEXTURES["glass"], 1, X, Y)
    p = surface(TEXTURES["paper"], 1, X, Y)
    assert g.h_um.std() < 0.05 and 5 < p.h_um.std() < 20


def test_a_variant_is_the_same_specimen_with_its_parameters_changed():
    b = texture({"name": "corduroy_b", "like": "corduroy", "period_u_mm": 2.65})
    assert b.specimen == "corduroy" and b.period_u_mm == 2.65
    a = surface(TEXTURES["corduroy"], 1, X, Y).h_um
    c = surface(b, 1, X, Y).h_um
    # same weave phases and roughness: nearly the same surface near the origin
    assert np.abs(a[:, 300:340] - c[:, 300:340]).max() < 0.1 * np.ptp(a)


@pytest.mark.parametrize("bad,match", [
    (dict(mu_static=0.3, mu_kinetic=0.5), "mu_kinetic .* exceeds mu_static"),
    (dict(family="wood"), "family must be"),
    (dict(hurst=1.5), "hurst must lie"),
    (dict(rough_hi_mm=3.0, rough_lo_mm=2.0), "rough_hi_mm .* must be below"),
])
def test_impossible_textures_are_refused(bad, match):
    base = dict(name="x", family="paper", mu_static=0.5, mu_kinetic=0.4)
    with pytest.raises(ValueError, match=match):
        Texture(**(base | bad))
    with pytest.raises(ValueError, match="unknown texture 'velvet'"):
        texture("velvet")
