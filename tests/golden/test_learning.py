"""The learning layer's golden models: AIDP's window step and pair-based STDP against their
stated equations, the layer's compiled loop against its reference tick loop, the jittered
presentations, the shapes."""

import math

import numpy as np
import pytest

from cuneate.golden.aidp import AidpParams, sigmoid, window_step
from cuneate.golden.cuneate_layer import LayerParams, presentations, simulate_layer
from cuneate.golden.stdp import StdpParams, step
from cuneate.golden.textures import surface, texture


def test_the_window_step_is_the_compensated_sigmoid_scaled_drive():
    p = AidpParams(eta=0.01, w_max=6.0, w_pot=4.5, w_dep=0.5, slope=0.5)
    w = np.array([[1.0, 5.9, 0.2]])
    L = np.array([[30.0, -10.0, 10.0]])
    mean = 10.0
    want = []
    for wi, li in zip(w[0], L[0]):
        d = li - mean
        s = 1 / (1 + math.exp((wi - 4.5) / 0.5)) if d > 0 else 1 / (1 + math.exp(-(wi - 0.5)
                                                                                / 0.5))
        want.append(min(max(wi + 0.01 * d * s, 0.0), 6.0))
    assert np.allclose(window_step(w, L, p), [want], rtol=0, atol=1e-15)
    assert window_step(w, L, p, apply=False) is w
    # the steps of a row sum to zero before the sigmoids: equal drives change nothing
    assert np.array_equal(window_step(w, np.full((1, 3), 7.0), p), w)
    assert sigmoid(4.5, True, p) == pytest.approx(0.5) and sigmoid(0.5, False, p) == \
        pytest.approx(0.5)


def test_a_stdp_pair_n_ticks_apart_counts_exp_of_its_distance():
    """x and y traces after one spike n ticks ago: the pair formula's exp(-n dt / tau)."""
    p = StdpParams(a_plus=0.1, a_minus=0.05, tau_plus_ms=10.0, tau_minus_ms=20.0)
    dt, n = 0.5, 6
    x = np.array([[math.exp(-n * dt / p.tau_plus_ms)]])          # pre n ticks before post
    w = step(np.array([[1.0]]), x, np.zeros(1), np.array([[False]]), np.array([True]), p)
    assert w[0, 0] == pytest.approx(1.0 + 0.1 * math.exp(-3.0 / 10.0))
    y = np.array([math.exp(-n * dt / p.tau_minus_ms)])          # post n ticks before pre
    w = step(np.array([[1.0]]), np.zeros((1, 1)), y, np.array([[True]]), np.array([False]), p)
    assert w[0, 0] == pytest.approx(1.0 - 0.05 * math.exp(-3.0 / 20.0))


@pytest.mark.parametrize("rule", ["aidp", "stdp", "none"])
def test_the_compiled_loop_equals_the_reference_tick_loop(rule):
    rng = np.random.default_rng(1)
    S, M, K = 10, 3, 5
    tpl = [[np.sort(rng.uniform(0, 200, rng.integers(5, 50))) for _ in range(S)]
           for _ in range(2)]
    pres = presentations(tpl, [0, 1, 1, 0], (0, 100), 0.5, 5.0, 10.0, 3)
    lay = LayerParams(np.array([rng.choice(S, K, replace=False) for _ in range(M)]), S,
                      g_inh=0.2)
    w0 = rng.uniform(0, 4, (M, K))
    p = AidpParams(eta=2e-3) if rule != "stdp" else StdpParams(a_plus=0.2, a_minus=0.2)
    a = simulate_layer(pres, w0, lay, rule, p, [True, False, True, True], 2, kernel="numpy")
    b = simulate_layer(pres, w0, lay, rule, p, [True, False, True, True], 2, kernel="numba")
    assert a.counts.sum() > 0
    assert np.array_equal(a.weights, b.weights) and np.array_equal(a.counts, b.counts)
    for k in ("spike_pres", "spike_tick", "spike_cn"):
        assert np.array_equal(getattr(a, k), getattr(b, k))
    assert [i for i, _ in a.snapshots] == [i for i, _ in b.snapshots] == [0, 2, 4]
    assert np.allclose(a.step, b.step, rtol=1e-12, atol=0)
    if rule != "none":
        assert not np.array_equal(a.weights, w0)          # it learnt something


def test_presentations_stamp_jittered_spikes_in_the_window_and_count_merged_ones():
    tpl = [[np.array([10.0, 10.2, 10.6, 55.0, 99.0]), np.array([120.0])]]
    p = presentations(tpl, [0], (10.0, 110.0), 0.5, 0.0, 5.0, 1)
    assert p.n_ticks == 210 and p.window_ticks == 200
    assert p.ticks.tolist() == [0, 1, 90, 178] and p.sources.tolist() == [0, 0, 0, 0]
    assert p.merged == 1                                    # 10.0 and 10.2 share tick 0
    j = presentations(tpl, [0, 0, 0], (10.0, 110.0), 0.5, 5.0, 5.0, 2)
    assert j.n == 3 and np.all(j.ticks < 200) and len(set(j.ticks.tolist())) > 3


@pytest.mark.parametrize("name,height,cover", [("bars", 150.0, 0.25),
                                               ("dots", 200.0, np.pi * 0.7 ** 2 / 9.0)])
def test_shapes_are_raised_features_of_their_height_and_coverage(name, height, cover):
    s = surface(texture(name), 1, (-6.0, 6.0), (-6.0, 6.0))
    assert s.h_um.max() == pytest.approx(height, abs=3.0)
    assert np.mean(s.h_um > height / 2) == pytest.approx(cover, rel=0.12)
