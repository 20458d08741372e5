"""Tests of cuneate.golden.metrics (spike-train metrics).

Every distance is checked against an independent plain-Python or numerical reference written
here; the Elephant cross-checks are an extra (optional ``crosscheck`` extra) on top of those.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from cuneate.golden.metrics import (
    compare_populations,
    compare_trains,
    first_spike_latency_difference,
    fraction_within,
    isi_stats,
    matched_spike_errors,
    spike_count_difference,
    van_rossum,
    victor_purpura,
    victor_purpura_matrix,
)


def random_train(rng: np.random.Generator, max_n: int = 12, t_max: float = 100.0) -> np.ndarray:
    """Sorted uniform spike times in [0, t_max) ms (continuous, so no two trains coincide)."""
    return np.sort(rng.uniform(0.0, t_max, rng.integers(0, max_n + 1)))


def vp_reference(a, b, q) -> float:
    """Textbook Victor-Purpura double loop (Victor & Purpura 1996)."""
    n, m = len(a), len(b)
    d = [[0.0] * (m + 1) for _ in range(n + 1)]
    for i in range(n + 1):
        d[i][0] = float(i)
    for j in range(m + 1):
        d[0][j] = float(j)
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            dt = abs(a[i - 1] - b[j - 1])
            shift = 0.0 if dt == 0 else q * dt
            d[i][j] = min(d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + shift)
    return d[n][m]


# ------------------------------------------------------------------------- Victor-Purpura


def test_vp_q_zero_is_count_difference():
    rng = np.random.default_rng(1)
    for _ in range(30):
        a, b = random_train(rng), random_train(rng)
        assert victor_purpura(a, b, 0.0) == abs(len(a) - len(b))


@pytest.mark.parametrize("q", [1e9, np.inf])
def test_vp_q_infinite_is_total_count(q):
    rng = np.random.default_rng(2)
    for _ in range(30):
        a, b = random_train(rng), random_train(rng)
        assert victor_purpura(a, b, q) == pytest.approx(len(a) + len(b))


def test_vp_q_inf_keeps_coincident_spikes_free():
    # 2.0 coincides exactly: 5 spikes, one free pair -> 3 (no inf * 0 = NaN)
    assert victor_purpura([1.0, 2.0, 3.0], [2.0, 5.0], np.inf) == 3.0
    assert victor_purpura([1.0, 2.0], [1.0, 2.0], np.inf) == 0.0


def test_vp_identical_trains_zero_and_symmetric():
    rng = np.random.default_rng(3)
    for _ in range(20):
        a, b, q = random_train(rng), random_train(rng), rng.uniform(0, 2)
        assert victor_purpura(a, a, q) == 0.0
        assert victor_purpura(a, b, q) == pytest.approx(victor_purpura(b, a, q), abs=1e-12)


def test_vp_triangle_inequality():
    rng = np.random.default_rng(4)
    for _ in range(50):
        a, b, c = (random_train(rng) for _ in range(3))
        q = rng.uniform(0.0, 1.0)
        assert victor_purpura(a, c, q) <= victor_purpura(a, b, q) + victor_purpura(b, c, q) + 1e-9


@pytest.mark.parametrize("q", [0.0, 0.05, 0.5, 1.0, 2.0, 10.0, np.inf])
@pytest.mark.parametrize("dt", [0.1, 1.0, 3.0])
def test_vp_single_spike_shift(q, dt):
    assert victor_purpura([10.0], [10.0 + dt], q) == pytest.approx(min(q * dt, 2.0))


def test_vp_matches_double_loop_reference():
    rng = np.random.default_rng(5)
    for _ in range(60):
        a, b = random_train(rng, 15), random_train(rng, 15)
        q = float(rng.choice([0.0, rng.uniform(0.001, 0.1), rng.uniform(0.1, 5.0), np.inf]))
        assert np.isclose(victor_purpura(a, b, q), vp_reference(a, b, q), rtol=1e-12, atol=1e-12)
    # grid-aligned trains (many exact coincidences, like engine output) too
    for _ in range(30):
        a = np.flatnonzero(rng.random(60) < 0.2) * 0.5
        b = np.flatnonzero(rng.random(60) < 0.2) * 0.5
        q = rng.uniform(0.0, 3.0)
        assert np.isclose(victor_purpura(a, b, q), vp_reference(a, b, q), rtol=1e-12, atol=1e-12)


def test_vp_matrix():
    rng = np.random.default_rng(6)
    trains = [random_train(rng) for _ in range(5)]
    mat = victor_purpura_matrix(trains, 0.3)
    assert mat.shape == (5, 5)
    np.testing.assert_array_equal(np.diag(mat), 0.0)
    np.testing.assert_array_equal(mat, mat.T)
    assert mat[1, 3] == victor_purpura(trains[1], trains[3], 0.3)


def test_elephant_crosscheck():
    """Extra check against Elephant (verified with elephant 1.2.1).

    Conversions: Elephant's ``cost_factor`` is our q as a rate, q_per_ms = cost_factor[Hz] / 1000;
    its van Rossum distance is normalized to 1 for one spike vs an empty train, i.e. it equals
    sqrt(2) x ours (we use the paper's normalization, sqrt(1/2) for that case).
    """
    pq = pytest.importorskip("quantities")
    neo = pytest.importorskip("neo")
    sd = pytest.importorskip("elephant.spike_train_dissimilarity")
    rng = np.random.default_rng(7)
    for _ in range(10):
        a, b = random_train(rng, 20, 200.0), random_train(rng, 20, 200.0)
        sa, sb = (neo.SpikeTrain(x * pq.ms, t_stop=200.0 * pq.ms) for x in (a, b))
        q_per_ms = rng.uniform(0.005, 2.0)
        tau_ms = rng.uniform(0.5, 50.0)
        vp_e = sd.victor_purpura_distance([sa, sb], cost_factor=q_per_ms * 1000.0 * pq.Hz)[0, 1]
        vr_e = sd.van_rossum_distance([sa, sb], time_constant=tau_ms * pq.ms)[0, 1]
        assert victor_purpura(a, b, q_per_ms) == pytest.approx(vp_e, rel=1e-9, abs=1e-12)
        assert math.sqrt(2.0) * van_rossum(a, b, tau_ms) == pytest.approx(vr_e, rel=1e-9, abs=1e-9)


# ------------------------------------------------------------------------- van Rossum


def vr_numerical(a, b, tau) -> float:
    """D^2 = (1/tau) * integral (f_a - f_b)^2 dt by adaptive quadrature between spike times."""
    from scipy.integrate import quad

    def diff(t):
        fa = sum(math.exp(-(t - s) / tau) for s in a if s <= t)
        return fa - sum(math.exp(-(t - s) / tau) for s in b if s <= t)

    edges = sorted({*a, *b})
    pieces = [quad(lambda t: diff(t) ** 2, lo, hi)[0] for lo, hi in zip(edges, edges[1:])]
    tail = diff(edges[-1]) ** 2 * tau / 2  # after the last spike the difference just decays
    return math.sqrt((sum(pieces) + tail) / tau)


def test_van_rossum_basic_values():
    assert van_rossum([3.0, 7.0], [3.0, 7.0], 5.0) == 0.0
    assert van_rossum([12.0], [], 5.0) == pytest.approx(math.sqrt(0.5))
    assert van_rossum([], [12.0], 5.0) == pytest.approx(math.sqrt(0.5))
    assert van_rossum([], [], 5.0) == 0.0
    assert van_rossum([0.0], [1e4], 5.0) == pytest.approx(1.0)
    # tau -> inf: only counts matter, (n - m)^2 / 2
    assert van_rossum([1.0, 2.0, 3.0], [50.0], np.inf) == pytest.approx(math.sqrt(2.0))


def test_van_rossum_symmetric_and_matches_integral():
    rng = np.random.default_rng(8)
    for _ in range(15):
        a, b = random_train(rng, 8, 40.0), random_train(rng, 8, 40.0)
        tau = rng.uniform(1.0, 10.0)
        d = van_rossum(a, b, tau)
        assert d == pytest.approx(van_rossum(b, a, tau), abs=1e-12)
    a, b = [2.0, 9.5, 10.0, 30.0], [2.5, 11.0, 25.0]
    assert van_rossum(a, b, 4.0) == pytest.approx(vr_numerical(a, b, 4.0), rel=1e-9)


def test_van_rossum_discrete_grid():
    rng = np.random.default_rng(9)
    dt = 0.25
    for _ in range(10):  # spikes on the grid: discrete version is exact
        a = np.flatnonzero(rng.random(200) < 0.1) * dt + 3.0
        b = np.flatnonzero(rng.random(200) < 0.1) * dt + 3.0
        exact = van_rossum(a, b, 2.0)
        assert van_rossum(a, b, 2.0, dt_ms=dt) == pytest.approx(exact, rel=1e-9, abs=1e-12)
    # off-grid spikes: converges to the closed form as dt -> 0
    a, b = random_train(rng, 10, 50.0), random_train(rng, 10, 50.0)
    exact = van_rossum(a, b, 5.0)
    errs = [abs(van_rossum(a, b, 5.0, dt_ms=h) - exact) for h in (1.0, 0.1, 0.01)]
    assert errs[2] < 0.02 * exact and errs[2] < errs[0]
    assert van_rossum([12.0], [], 5.0, dt_ms=0.1) == pytest.approx(math.sqrt(0.5))


# ------------------------------------------------------------------------- ISI statistics


def test_isi_regular_train():
    st = isi_stats(np.arange(10) * 12.5, duration_ms=250.0)
    assert st["n_spikes"] == 10
    assert st["mean_isi_ms"] == pytest.approx(12.5)
    assert st["cv_isi"] == pytest.approx(0.0, abs=1e-12)
    assert st["rate_hz"] == pytest.approx(40.0)


def test_isi_poisson_cv_near_one():
    rng = np.random.default_rng(10)
    spikes = np.cumsum(rng.exponential(20.0, 5000))
    st = isi_stats(spikes)
    assert st["cv_isi"] == pytest.approx(1.0, abs=0.05)
    assert st["mean_isi_ms"] == pytest.approx(20.0, rel=0.05)
    assert st["rate_hz"] is None


@pytest.mark.parametrize("spikes", [[], [5.0]])
def test_isi_too_few_spikes(spikes):
    st = isi_stats(spikes, duration_ms=100.0)
    assert st["n_spikes"] == len(spikes)
    assert st["mean_isi_ms"] is None and st["cv_isi"] is None and st["std_isi_ms"] is None
    assert st["rate_hz"] == pytest.approx(10.0 * len(spikes))


# ---------------------------------------------------------------- counts, latency, matching


def test_count_and_latency():
    assert spike_count_difference([1.0, 2.0], [1.0, 2.0, 3.0]) == 1
    assert spike_count_difference([1.0, 2.0, 3.0], []) == -3
    assert first_spike_latency_difference([4.0, 9.0], [5.5]) == pytest.approx(1.5)
    assert first_spike_latency_difference([], [5.5]) is None
    assert first_spike_latency_difference([1.0], []) is None


def test_matched_shifted_train():
    a = np.array([10.0, 20.0, 30.0, 40.0])
    np.testing.assert_allclose(matched_spike_errors(a, a + 0.5), 0.5)
    np.testing.assert_allclose(matched_spike_errors(a, a - 0.5, max_shift_ms=1.0), -0.5)
    assert matched_spike_errors(a, a + 2.0, max_shift_ms=1.0).size == 0
    assert fraction_within(a, a + 0.5, 0.5) == 1.0
    assert fraction_within(a, a + 0.5, 0.4) == 0.0


def test_matched_missing_and_extra_spike():
    a = np.array([10.0, 20.0, 30.0, 40.0])
    missing = np.array([10.1, 30.1, 40.1])  # 20 dropped
    np.testing.assert_allclose(matched_spike_errors(a, missing), [0.1, 0.1, 0.1])
    assert fraction_within(a, missing, 0.2) == pytest.approx(0.75)
    extra = np.array([9.9, 20.0, 24.0, 30.2, 40.0])  # 24 inserted
    np.testing.assert_allclose(matched_spike_errors(a, extra), [-0.1, 0.0, 0.2, 0.0], atol=1e-12)
    assert fraction_within(a, extra, 0.15) == pytest.approx(0.75)  # 30 -> 30.2 is out of window
    assert fraction_within([], extra, 1.0) is None
    assert fraction_within(a, [], 1.0) == 0.0


def test_matching_prefers_more_pairs_then_smaller_error():
    # one pair (2 -> 1.9, error 0.1) vs two pairs (errors 1.9, 1.9): more pairs wins
    err = matched_spike_errors([0.0, 2.0], [1.9, 3.9], max_shift_ms=2.0)
    np.testing.assert_allclose(err, [1.9, 1.9])
    # equal pair counts: smaller total error wins
    np.testing.assert_allclose(matched_spike_errors([5.0], [4.0, 5.5, 7.0]), [0.5])


def test_matching_against_brute_force():
    """Exhaustive search over in-order matchings: most pairs, then least total |error|."""
    rng = np.random.default_rng(11)
    for _ in range(60):
        a, b = random_train(rng, 5, 10.0), random_train(rng, 5, 10.0)
        w = float(rng.choice([0.5, 1.5, 3.0, np.inf]))
        best = (0, 0.0)
        for k in range(1, min(len(a), len(b)) + 1):
            for ia in itertools.combinations(range(len(a)), k):
                for ib in itertools.combinations(range(len(b)), k):
                    d = np.abs(b[list(ib)] - a[list(ia)])
                    if np.all(d <= w) and (k > best[0] or (k == best[0] and d.sum() < best[1])):
                        best = (k, d.sum())
        err = matched_spike_errors(a, b, None if np.isinf(w) else w)
        assert err.size == best[0]
        assert np.abs(err).sum() == pytest.approx(best[1], abs=1e-9)
        assert np.all(np.abs(err) <= w)


# ------------------------------------------------------------------------- reports


def test_compare_trains_and_populations():
    dt = 0.1
    a = [1.0, 2.0, 3.0, 4.0]
    b = [1.1, 2.0, 3.3, 4.0, 6.0]  # +1 tick, exact, +3 ticks, exact, extra spike
    r = compare_trains(a, b, dt)
    assert (r["n_a"], r["n_b"], r["count_difference"]) == (4, 5, 1)
    assert r["first_spike_latency_diff_ms"] == pytest.approx(0.1)
    assert r["n_matched"] == 4
    assert r["max_abs_error_ms"] == pytest.approx(0.3)
    assert r["mean_abs_error_ms"] == pytest.approx(0.1)
    assert r["n_within_tick"] == 3 and r["fraction_within_tick"] == pytest.approx(0.75)
    assert r["vp_distance"] == pytest.approx(victor_purpura(a, b, 0.005))

    pop = compare_populations([a, [5.0], []], [b, [5.0], []], dt)
    assert pop["n_trains"] == 3 and len(pop["per_train"]) == 3
    assert (pop["total_a"], pop["total_b"], pop["counts_equal"]) == (5, 6, False)
    assert pop["fraction_within_tick"] == pytest.approx(4 / 5)
    assert pop["max_abs_error_ms"] == pytest.approx(0.3)
    assert pop["mean_vp_distance"] == pytest.approx(r["vp_distance"] / 3)
    assert pop["per_train"][2]["fraction_within_tick"] is None
    assert compare_populations([[1.0]], [[1.0]], dt)["counts_equal"] is True
    with pytest.raises(ValueError, match="differ in size"):
        compare_populations([a], [a, a], dt)


# ------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("train", "match"),
    [
        ([3.0, 1.0, 2.0], "sorted"),
        ([1.0, np.nan], "finite"),
        ([1.0, np.inf], "finite"),
        ([[1.0, 2.0]], "1-D"),
        (["x"], "numbers"),
    ],
)
def test_invalid_trains_raise(train, match):
    for call in (
        lambda t: victor_purpura(t, [1.0], 0.1),
        lambda t: van_rossum([1.0], t, 5.0),
        lambda t: matched_spike_errors(t, [1.0]),
        lambda t: isi_stats(t),
        lambda t: spike_count_difference([1.0], t),
    ):
        with pytest.raises(ValueError, match=match):
            call(train)


def test_invalid_parameters_raise():
    with pytest.raises(ValueError, match="q_per_ms"):
        victor_purpura([1.0], [2.0], -1.0)
    with pytest.raises(ValueError, match="q_per_ms"):
        victor_purpura([1.0], [2.0], np.nan)
    with pytest.raises(ValueError, match="tau_ms"):
        van_rossum([1.0], [2.0], 0.0)
    with pytest.raises(ValueError, match="dt_ms"):
        compare_trains([1.0], [2.0], 0.0)
    with pytest.raises(ValueError, match="duration_ms"):
        isi_stats([1.0, 2.0], duration_ms=-5.0)


def test_compiled_vp_matrix_equals_the_pairwise_programme():
    """The compiled matrix (golden/metrics_kernel.py) against :func:`victor_purpura` pair by
    pair: random and grid-aligned trains, empty ones, q = 0, q = inf; and against Elephant."""
    from cuneate.golden.kernel import available
    assert available()
    rng = np.random.default_rng(11)
    trains = [random_train(rng, 40, 500.0) for _ in range(12)] + [np.zeros(0), np.zeros(0)]
    trains += [np.flatnonzero(rng.random(80) < 0.2) * 0.5 for _ in range(6)]
    for q in (0.0, 0.005, 0.7, np.inf):
        mat = victor_purpura_matrix(trains, q)
        ref = np.array([[victor_purpura(a, b, q) for b in trains] for a in trains])
        np.testing.assert_allclose(mat, ref, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(mat, mat.T)
    pq = pytest.importorskip("quantities")
    neo = pytest.importorskip("neo")
    sd = pytest.importorskip("elephant.spike_train_dissimilarity")
    st = [neo.SpikeTrain(t * pq.ms, t_stop=500.0 * pq.ms) for t in trains[:8]]
    np.testing.assert_allclose(victor_purpura_matrix(trains[:8], 0.005),
                               sd.victor_purpura_distance(st, cost_factor=5.0 * pq.Hz),
                               rtol=1e-9, atol=1e-12)
