"""Golden Izhikevich model: published behaviours, schemes, convergence, divergence detection."""

import numpy as np
import pytest

from cuneate.golden.izhikevich import (PRESETS, SCHEMES, DivergenceError, IzhikevichParams,
                                       simulate, step)


def pulse(t0, amp, t1=None):
    """Current ``amp`` for t0 <= t < t1 (t1=None: to the end), else 0."""
    return lambda t: amp if (t >= t0 and (t1 is None or t < t1)) else 0.0


# Parameter sets and inputs of Izhikevich (2004), "Which model to use for cortical spiking
# neurons?", Fig. 1 (MATLAB code of the figure): (a, b, c, d), input, v0, duration.
FIG1 = {
    "tonic_spiking": ((0.02, 0.2, -65, 6), pulse(10, 14), -70, 200),
    "phasic_spiking": ((0.02, 0.25, -65, 6), pulse(20, 0.5), -64, 200),
    "tonic_bursting": ((0.02, 0.2, -50, 2), pulse(22, 15), -70, 500),
    "adaptation": ((0.01, 0.2, -65, 8), pulse(10, 30), -70, 200),
    "spike_latency": ((0.02, 0.2, -65, 6), pulse(10, 7.04, 13), -70, 100),
    "rebound_spike": ((0.03, 0.25, -60, 4), pulse(20, -15, 25), -64, 200),
}


def run(name, scheme):
    p, current, v0, T = FIG1[name]
    return simulate(p, current, duration_ms=T, v0=v0, scheme=scheme).spikes_ms[0]


@pytest.mark.parametrize("scheme", SCHEMES)
class TestFigure1Behaviours:
    def test_tonic_spiking_settles_to_regular_isi(self, scheme):
        s = run("tonic_spiking", scheme)
        assert len(s) >= 5
        isi = np.diff(s)[-3:]
        assert np.ptp(isi) / isi.mean() < 0.02

    def test_phasic_spiking_is_exactly_one_spike_after_onset(self, scheme):
        s = run("phasic_spiking", scheme)
        assert len(s) == 1 and s[0] > 20

    def test_tonic_bursting_has_bimodal_isis(self, scheme):
        isi = np.sort(np.diff(run("tonic_bursting", scheme)))
        ratios = isi[1:] / isi[:-1]
        gap = int(np.argmax(ratios))
        short, long_ = isi[:gap + 1], isi[gap + 1:]
        assert ratios[gap] > 5, "no gap between intra- and inter-burst intervals"
        assert len(short) >= 4 and len(long_) >= 2
        assert long_.min() > 10 * short.max() / 2

    def test_spike_frequency_adaptation_isis_non_decreasing(self, scheme):
        isi = np.diff(run("adaptation", scheme))
        assert len(isi) >= 4
        assert np.all(np.diff(isi) >= -1e-9)
        assert isi[-1] > 5 * isi[0]

    def test_spike_latency_fires_after_the_pulse_ends(self, scheme):
        s = run("spike_latency", scheme)
        assert len(s) == 1 and s[0] > 13.0

    def test_rebound_spike_after_hyperpolarization(self, scheme):
        s = run("rebound_spike", scheme)
        assert len(s) == 1 and s[0] > 25.0
        p, _, v0, T = FIG1["rebound_spike"]
        assert len(simulate(p, 0.0, duration_ms=T, v0=v0, scheme=scheme).spikes_ms[0]) == 0


def test_rs_f_i_curve_is_monotone():
    currents = np.arange(0, 101, 2.5)
    res = simulate("RS", lambda t: currents, n_neurons=len(currents), duration_ms=1000)
    rates = res.spike_counts
    assert np.all(np.diff(rates) >= 0)
    assert rates[0] == 0 and rates[-1] > 100


def test_conventions_initial_state_and_spike_time():
    res = simulate("RS", 10.0, n_steps=1, record=True)
    assert res.v_trace[0, 0] == -65.0 and res.u_trace[0, 0] == pytest.approx(0.2 * -65.0)
    # Euler: spike at update k reported at (k+1) dt, v reset to c, u incremented by d
    v = np.array([29.9]); u = np.array([-13.0])
    a, b, c, d = (np.array([x]) for x in PRESETS["RS"].as_tuple())
    v1, u1, spk, v_pre = step(v, u, np.array([10.0]), a, b, c, d, 1 / 16)
    dv = 0.04 * 29.9**2 + 5 * 29.9 + 140 + 13.0 + 10.0
    assert v_pre[0] == pytest.approx(29.9 + dv / 16) and spk[0]
    assert v1[0] == -65.0
    assert u1[0] == pytest.approx(-13.0 + (0.02 * (0.2 * 29.9 + 13.0)) / 16 + 8.0)
    r = simulate("RS", 10.0, duration_ms=100)
    assert np.allclose(r.spikes_ms[0], (r.spike_steps[0] + 1) / 16)


def test_schemes_differ_as_documented():
    """euler takes u from the old v, izhikevich from the new v (after two half steps)."""
    v = np.array([-60.0]); u = np.array([-12.0]); I = np.array([5.0])
    a, b, c, d = (np.array([x]) for x in (0.02, 0.2, -65.0, 8.0))
    ve, ue, *_ = step(v, u, I, a, b, c, d, 0.5, "euler")
    vi, ui, *_ = step(v, u, I, a, b, c, d, 0.5, "izhikevich")
    assert ue[0] == pytest.approx(-12.0 + 0.5 * 0.02 * (0.2 * -60 + 12.0))
    f = lambda x: 0.04 * x * x + 5 * x + 140 + 12.0 + 5.0
    vh = -60.0 + 0.25 * f(-60.0)
    assert vi[0] == pytest.approx(vh + 0.25 * f(vh))
    assert ui[0] == pytest.approx(-12.0 + 0.5 * 0.02 * (0.2 * vi[0] + 12.0))


def test_presets_and_overrides():
    assert set(PRESETS) == {"RS", "IB", "CH", "FS", "LTS", "RZ"}
    assert PRESETS["CH"] == IzhikevichParams(0.02, 0.2, -50.0, 2.0)
    r = simulate(["RS", "FS", (0.02, 0.2, -65.0, 8.0)], 10.0, duration_ms=300)
    assert r.spike_counts[0] == r.spike_counts[2] and r.spike_counts[1] > r.spike_counts[0]
    with pytest.raises(ValueError, match="unknown Izhikevich preset"):
        simulate("XX", 10.0, duration_ms=10)


def test_current_forms_agree():
    n_steps = 1600
    const = simulate("RS", 10.0, n_steps=n_steps).spikes_ms[0]
    per_step = simulate("RS", np.full(n_steps, 10.0), n_steps=n_steps).spikes_ms[0]
    per_neuron = simulate("RS", np.full((n_steps, 2), 10.0), n_steps=n_steps, n_neurons=2)
    call = simulate("RS", lambda t: 10.0, n_steps=n_steps).spikes_ms[0]
    for other in (per_step, per_neuron.spikes_ms[0], per_neuron.spikes_ms[1], call):
        np.testing.assert_array_equal(const, other)
    with pytest.raises(ValueError, match="per-step"):
        simulate("RS", np.ones(5), n_steps=n_steps)
    with pytest.raises(ValueError, match="non-finite"):
        simulate("RS", np.full(n_steps, np.nan), n_steps=n_steps)


def test_euler_converges_to_rk4_at_first_order():
    """Subthreshold trajectory (no reset discontinuity) at t = 50 ms against RK4 at dt = 1/1024."""
    T = 50.0
    ref = simulate("RS", 2.0, duration_ms=T, dt_ms=1 / 1024, scheme="rk4")
    dts = np.array([0.5, 0.25, 0.125, 1 / 16, 1 / 32])
    err = []
    for dt in dts:
        r = simulate("RS", 2.0, duration_ms=T, dt_ms=dt, scheme="euler")
        err.append(abs(r.v[0] - ref.v[0]) + abs(r.u[0] - ref.u[0]))
    err = np.array(err)
    orders = np.log2(err[:-1] / err[1:])
    print(f"\nEuler vs RK4 state error at t={T} ms:",
          ", ".join(f"dt={dt:g}: {e:.3e}" for dt, e in zip(dts, err)))
    print("observed orders:", np.round(orders, 3))
    assert np.all(np.diff(err) < 0)
    assert np.all(np.abs(orders - 1.0) < 0.15)
    # spike timing converges too: first-spike time at I = 10
    first = [simulate("RS", 10.0, duration_ms=20, dt_ms=dt).spikes_ms[0][0] for dt in dts]
    rk = simulate("RS", 10.0, duration_ms=20, dt_ms=1 / 1024, scheme="rk4").spikes_ms[0][0]
    terr = np.abs(np.array(first) - rk)
    print("first-spike time error:", np.round(terr, 5))
    assert terr[-1] < terr[0] / 4


def test_divergence_is_detected_and_named():
    with pytest.raises(DivergenceError) as info:
        simulate("RS", -2000.0, duration_ms=100, dt_ms=1.0)
    err = info.value
    assert err.neuron == 0 and err.dt_ms == 1.0 and err.step >= 0
    assert "neuron 0" in str(err) and "dt = 1 ms" in str(err)
    # the second neuron is the one that blows up
    with pytest.raises(DivergenceError, match="neuron 1"):
        simulate("RS", lambda t: np.array([5.0, -5000.0]), n_neurons=2, duration_ms=50,
                 dt_ms=0.5)


# the long lane (CI): float32 compiles loops of its own
@pytest.mark.long
def test_float32_runs_in_float32():
    r = simulate("RS", 10.0, duration_ms=50, dtype=np.float32)
    assert r.v.dtype == np.float32
