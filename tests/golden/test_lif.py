"""Tests of the LIF reference models (cuneate.golden.lif)."""

import math

import numpy as np
import pytest

from cuneate.golden import lif


# ----------------------------------------------------------------------------- continuous LIF

@pytest.mark.parametrize("I, dt", [(30.0, 0.1), (25.0, 0.05), (60.0, 0.1)])
def test_constant_current_isi_matches_analytic_exact_scheme(I, dt):
    tau, v_th, v_reset, t_ref = 20.0, 18.0, 11.0, 2.0
    res = lif.simulate_lif(I, dt, duration_ms=300.0, tau_m_ms=tau, v_th=v_th, v_reset=v_reset,
                           t_ref_ms=t_ref, scheme="exact")
    spikes = res.spikes_ms[0]
    assert spikes.size >= 5
    # first spike from v0 = v_rest = 0: T0 = tau ln(I / (I - v_th)), rounded up to the grid
    T0 = tau * math.log(I / (I - v_th))
    assert T0 <= spikes[0] + 1e-9 and spikes[0] < T0 + dt + 1e-9
    # subsequent ISIs: t_ref + tau ln((I - v_reset)/(I - v_th)), at most one dt late
    isi_analytic = t_ref + tau * math.log((I - v_reset) / (I - v_th))
    isis = np.diff(spikes)
    assert np.all(isis >= isi_analytic - 1e-9)
    assert np.all(isis < isi_analytic + dt + 1e-9)


def test_euler_scheme_converges_to_analytic_isi():
    I, tau, v_th, v_reset, t_ref = 30.0, 20.0, 18.0, 11.0, 2.0
    isi_analytic = t_ref + tau * math.log((I - v_reset) / (I - v_th))
    res = lif.simulate_lif(I, 0.01, duration_ms=100.0, scheme="euler", tau_m_ms=tau,
                           v_reset=v_reset, t_ref_ms=t_ref)
    isis = np.diff(res.spikes_ms[0])
    assert isis.size >= 3
    assert np.all(np.abs(isis - isi_analytic) < 0.05)


def test_exact_scheme_single_step_formula():
    # one update from v = 5 with I = 10, tau = 20, dt = 1: v' = 10 + (5 - 10) e^(-1/20)
    res = lif.simulate_lif(np.array([10.0]), 1.0, v0=5.0, tau_m_ms=20.0)
    assert res.v_trace[1, 0] == pytest.approx(10.0 - 5.0 * math.exp(-0.05), rel=1e-14)
    res_e = lif.simulate_lif(np.array([10.0]), 1.0, v0=5.0, tau_m_ms=20.0, scheme="euler")
    assert res_e.v_trace[1, 0] == pytest.approx(5.0 + (1.0 / 20.0) * (10.0 - 5.0), rel=1e-14)


def test_subthreshold_current_never_spikes():
    res = lif.simulate_lif(17.9, 0.1, duration_ms=1000.0, v_th=18.0)
    assert res.spike_counts[0] == 0
    assert res.v_trace.max() < 18.0
    assert res.v[0] == pytest.approx(17.9, abs=1e-6)   # relaxed to v_inf after 50 tau


def test_refractory_period_clamps_and_is_respected():
    dt, t_ref, v_reset = 0.1, 2.0, 11.0
    # a huge current crosses threshold in a single integration step, so each ISI is exactly
    # the refractory time plus one update
    res = lif.simulate_lif(5000.0, dt, duration_ms=30.0, t_ref_ms=t_ref, v_reset=v_reset)
    isis = np.diff(res.spikes_ms[0])
    assert np.allclose(isis, t_ref + dt)
    n_ref = round(t_ref / dt)
    for k in res.spike_steps[0]:
        # trace row k+1 is the state after the spiking update; the next n_ref rows are clamped
        clamped = res.v_trace[k + 1:k + 2 + n_ref, 0]
        if clamped.size == n_ref + 1:
            assert np.all(clamped == v_reset)


def test_per_neuron_parameters_vectorized():
    tau = np.array([20.0, 10.0])
    res = lif.simulate_lif(30.0, 0.1, duration_ms=200.0, tau_m_ms=tau, t_ref_ms=[2.0, 1.0])
    assert res.v_trace.shape == (2001, 2)
    for i in range(2):
        single = lif.simulate_lif(30.0, 0.1, duration_ms=200.0, tau_m_ms=tau[i],
                                  t_ref_ms=[2.0, 1.0][i])
        assert np.array_equal(res.spikes_ms[i], single.spikes_ms[0])
    # the faster inhibitory-type membrane fires more
    assert res.spike_counts[1] > res.spike_counts[0]


def test_time_varying_current_and_spike_convention():
    # current switched on at update 100; spike times are multiples of dt reported at (k+1) dt
    dt = 0.1
    I = np.zeros(1000)
    I[100:] = 40.0
    res = lif.simulate_lif(I, dt)
    k0 = res.spike_steps[0][0]
    assert res.spikes_ms[0][0] == pytest.approx((k0 + 1) * dt)
    T0 = 20.0 * math.log(40.0 / (40.0 - 18.0))
    assert 100 * dt + T0 <= res.spikes_ms[0][0] + 1e-9 < 100 * dt + T0 + dt + 1e-9


@pytest.mark.parametrize("kwargs, pattern", [
    ({"tau_m_ms": -20.0}, "tau_m_ms"),
    ({"tau_m_ms": 0.0}, "tau_m_ms"),
    ({"t_ref_ms": -1.0}, "t_ref_ms"),
    ({"v_reset": 18.0}, "v_reset"),
    ({"scheme": "rk2"}, "scheme"),
    ({"scheme": "euler", "tau_m_ms": 0.04}, "unstable"),
    ({"v_th": np.nan}, "v_th"),
])
def test_simulate_lif_validation(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        lif.simulate_lif(20.0, 0.1, duration_ms=10.0, **kwargs)


def test_non_finite_current_refused():
    I = np.full(10, 20.0)
    I[3] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        lif.simulate_lif(I, 0.1)
    with pytest.raises(ValueError, match="dt_ms"):
        lif.simulate_lif(20.0, 0.0, duration_ms=1.0)
    with pytest.raises(ValueError, match="duration_ms or n_steps"):
        lif.simulate_lif(20.0, 0.1)


def test_huge_current_raises_divergence_not_nan():
    with pytest.raises(lif.LIFDivergenceError):
        lif.simulate_lif(1e300, 0.1, duration_ms=1.0)


# ----------------------------------------------------------------------------- synapses

@pytest.mark.parametrize("tr, td", [(0.4, 2.0), (0.25, 5.0), (0.5, 2.0)])
def test_kernel_peak_time_and_value(tr, td):
    t_peak = tr * td / (td - tr) * math.log(td / tr)
    assert lif.diff_exp_peak_time(tr, td) == pytest.approx(t_peak, rel=1e-14)
    t = np.linspace(0.0, 10.0, 200001)
    k = lif.diff_exp_kernel(t, tr, td, normalize="peak")
    assert t[np.argmax(k)] == pytest.approx(t_peak, abs=1e-4)
    assert k.max() == pytest.approx(1.0, abs=1e-9)
    raw = lif.diff_exp_kernel(t, tr, td, normalize="none")
    assert raw.max() == pytest.approx(math.exp(-t_peak / td) - math.exp(-t_peak / tr), rel=1e-8)
    t_long = np.linspace(0.0, 40.0 * td, 400001)
    area = np.trapezoid(lif.diff_exp_kernel(t_long, tr, td, normalize="area"), t_long)
    assert area == pytest.approx(1.0, rel=1e-6)


def test_kernel_is_causal_and_zero_at_onset():
    k = lif.diff_exp_kernel([-5.0, -1e-9, 0.0], 0.4, 2.0)
    assert np.array_equal(k, [0.0, 0.0, 0.0])


def test_synaptic_current_matches_hand_sum():
    spikes = np.array([1.0, 2.5, 7.0])
    t = np.arange(0.0, 20.0, 0.1)
    tr, td, L, w = 0.4, 2.0, 1.0, 3.0
    tp = tr * td / (td - tr) * math.log(td / tr)
    norm = math.exp(-tp / td) - math.exp(-tp / tr)
    expected = np.zeros_like(t)
    for ts in spikes:
        for j, tj in enumerate(t):
            s = tj - ts - L
            if s >= 0:
                expected[j] += w * (math.exp(-s / td) - math.exp(-s / tr)) / norm
    got = lif.synaptic_current(spikes, t, tr, td, latency_ms=L, weight=w)
    assert np.allclose(got, expected, rtol=1e-12, atol=1e-14)
    # the same through the DiffExpSynapse object
    syn = lif.DiffExpSynapse(tr, td, weight=w, latency_ms=L)
    assert np.allclose(syn.current(spikes, t), expected, rtol=1e-12, atol=1e-14)


def test_synaptic_peak_time_after_a_single_spike():
    dt = 0.001
    t = np.arange(0.0, 15.0, dt)
    syn = lif.AMPA
    I = syn.current(np.array([3.0]), t)
    t_expected = 3.0 + syn.latency_ms + syn.peak_time_ms
    assert t[np.argmax(I)] == pytest.approx(t_expected, abs=dt)
    assert I.max() == pytest.approx(syn.weight, rel=1e-6)


def test_latency_shifts_response_by_exactly_latency():
    dt = 0.05
    t = np.arange(0, 2000) * dt
    spikes = np.array([2.0, 4.3, 10.0])
    base = lif.synaptic_current(spikes, t, 0.25, 5.0, latency_ms=0.0)
    for n_shift in (1, 20, 37):
        L = n_shift * dt
        shifted = lif.synaptic_current(spikes, t, 0.25, 5.0, latency_ms=L)
        assert np.all(shifted[:n_shift] == 0.0)
        # equal up to float rounding of the grid times (k dt is not exact in binary)
        assert np.allclose(shifted[n_shift:], base[:-n_shift], rtol=1e-12, atol=1e-12)
        # nothing before the first arrival
        assert np.all(shifted[t < spikes[0] + L] == 0.0)


def test_synaptic_current_vectorized_over_sources_and_targets():
    t = np.arange(0.0, 30.0, 0.1)
    s0, s1 = np.array([1.0, 5.0]), np.array([3.0])
    W = np.array([[1.0, 0.5, 0.0], [2.0, 0.0, 1.0]])       # (n_pre, n_post)
    lat = np.array([[1.0, 2.0, 1.0], [0.5, 1.0, 3.0]])
    out = lif.synaptic_current([s0, s1], t, 0.4, 2.0, latency_ms=lat, weight=W)
    assert out.shape == (t.size, 3)
    for post in range(3):
        ref = sum(W[pre, post] * lif.synaptic_current(s, t, 0.4, 2.0, latency_ms=lat[pre, post])
                  for pre, s in enumerate((s0, s1)))
        assert np.allclose(out[:, post], ref, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("tr, td", [(2.0, 0.4), (0.0, 2.0), (-1.0, 2.0), (1.0, 1.0)])
def test_bad_time_constants(tr, td):
    with pytest.raises(ValueError, match="tau"):
        lif.DiffExpSynapse(tr, td)


def test_negative_latency_and_bad_normalization_refused():
    with pytest.raises(ValueError, match="latency"):
        lif.synaptic_current([1.0], np.arange(10.0), 0.4, 2.0, latency_ms=-1.0)
    with pytest.raises(ValueError, match="normalize"):
        lif.diff_exp_kernel([0.0], 0.4, 2.0, normalize="max")
    with pytest.raises(ValueError, match="non-finite"):
        lif.synaptic_current([1.0, np.nan], np.arange(10.0), 0.4, 2.0)


# ----------------------------------------------------------------------------- network

@pytest.mark.parametrize("latency", [1.0, 1.03])
def test_network_synaptic_current_matches_direct_sum(latency):
    dt, n_steps = 0.1, 1500
    ampa = lif.DiffExpSynapse(0.4, 2.0, weight=1.0, latency_ms=latency)
    W = np.array([[0.0, 4.0], [0.0, 0.0]])                 # neuron 0 excites neuron 1
    ext = np.zeros((n_steps, 2))
    ext[:, 0] = 30.0                                       # only neuron 0 is driven
    res = lif.simulate_lif_network(2, W, 0.0, ext, dt, ampa=ampa)
    pre = res.spikes_ms[0]
    assert pre.size >= 5
    t_grid = np.arange(n_steps) * dt
    expected = 4.0 * ampa.current(pre, t_grid)
    assert np.allclose(res.i_exc_trace[:, 1], expected, rtol=1e-9, atol=1e-12)
    assert np.all(res.i_exc_trace[:, 0] == 0.0)
    assert np.all(res.i_inh_trace == 0.0)


def test_network_inhibition_silences_target():
    dt, n_steps = 0.1, 3000
    ext = np.full((n_steps, 2), 30.0)
    free = lif.simulate_lif_network(2, 0.0, 0.0, ext, dt)
    Wi = np.array([[0.0, 20.0], [0.0, 0.0]])
    inhibited = lif.simulate_lif_network(2, 0.0, Wi, ext, dt)
    assert np.array_equal(free.spikes_ms[0], inhibited.spikes_ms[0])
    assert inhibited.spike_counts[1] < free.spike_counts[1]
    # uncoupled network equals independent neurons
    single = lif.simulate_lif(30.0, dt, n_steps=n_steps)
    assert np.array_equal(free.spikes_ms[1], single.spikes_ms[0])


def test_network_validation():
    with pytest.raises(ValueError, match=">= 0"):
        lif.simulate_lif_network(2, -np.ones((2, 2)), 0.0, 20.0, 0.1, duration_ms=5.0)
    with pytest.raises(ValueError, match="shape"):
        lif.simulate_lif_network(2, np.ones((3, 3)), 0.0, 20.0, 0.1, duration_ms=5.0)


def test_force_to_current():
    f = np.array([0.0, 0.5, 2.0])
    assert np.allclose(lif.force_to_current(f, 5.0, 10.0), [5.0, 10.0, 25.0])
    per_taxel = lif.force_to_current(np.ones((4, 3)), np.array([1.0, 2.0, 3.0]), 2.0)
    assert np.allclose(per_taxel[0], [3.0, 4.0, 5.0])
    with pytest.raises(ValueError, match="non-finite"):
        lif.force_to_current([1.0, np.inf], 0.0, 1.0)


# ----------------------------------------------------------------------------- discrete LIF

def test_discrete_lif_hand_checked_sequence():
    # alpha = 0.5, w = 0.4, u_th = 0.65, u0 = 0, inputs 1 1 1 0 1 1 1:
    # t0: 0.4; t1: 0.2 + 0.4 = 0.6; t2: 0.3 + 0.4 = 0.7 > 0.65 -> spike, reset 0;
    # t3: 0 + 0 = 0; t4: 0.4; t5: 0.6; t6: 0.7 -> spike.
    # second neuron, w = 0.8: 0.8 > 0.65 spikes whenever the input is 1 (reset each time).
    x = np.array([1, 1, 1, 0, 1, 1, 1], dtype=float)[:, None]
    res = lif.simulate_discrete_lif(x, np.array([[0.4, 0.8]]), alpha=0.5, u_th=0.65)
    assert res.spikes.dtype == bool and res.spikes.shape == (7, 2)
    assert res.spikes[:, 0].tolist() == [False, False, True, False, False, False, True]
    assert res.spikes[:, 1].tolist() == [True, True, True, False, True, True, True]
    assert np.allclose(res.u_pre[:, 0], [0.4, 0.6, 0.7, 0.0, 0.4, 0.6, 0.7])
    assert np.allclose(res.u[:, 0], [0.4, 0.6, 0.0, 0.0, 0.4, 0.6, 0.0])


def test_discrete_lif_strict_threshold():
    # alpha = 0.5, w = 0.5, u_th = 0.75: t0 0.5; t1 0.25 + 0.5 = 0.75 == u_th (exact in binary),
    # no spike because the test is strict; t2 0.375 + 0.5 = 0.875 -> spike.
    x = np.ones((3, 1))
    res = lif.simulate_discrete_lif(x, [0.5], alpha=0.5, u_th=0.75)
    assert res.u_pre[1, 0] == 0.75
    assert res.spikes[:, 0].tolist() == [False, False, True]


def test_discrete_lif_multiple_inputs_sum():
    # two inputs, weights 0.3 and 0.2, alpha 0 (no memory), u_th 0.4:
    # both on -> 0.5 spike; only first -> 0.3; only second -> 0.2; none -> 0
    x = np.array([[1, 1], [1, 0], [0, 1], [0, 0]], dtype=float)
    res = lif.simulate_discrete_lif(x, [[0.3], [0.2]], alpha=0.0, u_th=0.4)
    assert res.spikes[:, 0].tolist() == [True, False, False, False]
    assert np.allclose(res.u_pre[:, 0], [0.5, 0.3, 0.2, 0.0])


def test_discrete_lif_refractory_and_reset_value():
    # w = 0.8 > u_th every step; refractory 2 -> spikes at t = 0, 3, 6, 9; held at u_rest = -0.1
    x = np.ones((10, 1))
    res = lif.simulate_discrete_lif(x, [0.8], alpha=0.5, u_th=0.65, u_rest=-0.1,
                                    refractory_steps=2)
    assert np.flatnonzero(res.spikes[:, 0]).tolist() == [0, 3, 6, 9]
    assert np.all(res.u[[1, 2, 4, 5], 0] == -0.1)


def test_discrete_alpha_from_tau():
    res = lif.simulate_discrete_lif(np.zeros((2, 1)), [1.0], tau=2.0, dt=1.0)
    assert res.alpha == pytest.approx(math.exp(-0.5))
    assert lif.simulate_discrete_lif(np.zeros((1, 1)), [1.0]).alpha == 0.389
    with pytest.raises(ValueError, match="either alpha"):
        lif.simulate_discrete_lif(np.zeros((1, 1)), [1.0], alpha=0.5, tau=2.0, dt=1.0)
    with pytest.raises(ValueError, match="tau"):
        lif.simulate_discrete_lif(np.zeros((1, 1)), [1.0], tau=-2.0, dt=1.0)


@pytest.mark.parametrize("inputs, weights, kwargs, pattern", [
    (np.zeros(5), [1.0], {}, "2-D"),
    (np.zeros((5, 2)), [[1.0]], {}, "shape"),
    (np.array([[np.nan]]), [1.0], {}, "non-finite"),
    (np.zeros((5, 1)), [1.0], {"alpha": 1.5}, "alpha"),
    (np.zeros((5, 1)), [1.0], {"refractory_steps": -1}, "refractory"),
    (np.zeros((5, 1)), [np.inf], {}, "non-finite"),
])
def test_discrete_lif_validation(inputs, weights, kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        lif.simulate_discrete_lif(inputs, weights, **kwargs)
