"""Tests of the cuneate coincidence-detector reference (cuneate.golden.coincidence)."""

import math

import numpy as np
import pytest

from cuneate.golden import coincidence as cn
from cuneate.golden import izhikevich

DT = izhikevich.DEFAULT_DT_MS


# ----------------------------------------------------------------------------- PSP kernel

def test_psp_kernel_peak_time_matches_analytic():
    tr, td = 0.5, 2.0
    t_peak = tr * td / (td - tr) * math.log(td / tr)          # 0.924 ms
    assert cn.psp_peak_time() == pytest.approx(t_peak, rel=1e-14)
    t = np.linspace(0.0, 10.0, 100001)
    k = cn.psp_kernel(t)
    assert t[np.argmax(k)] == pytest.approx(t_peak, abs=1e-4)
    # default normalization "none": the raw difference of exponentials
    assert k.max() == pytest.approx(math.exp(-t_peak / td) - math.exp(-t_peak / tr), rel=1e-8)
    kp = cn.psp_kernel(t, normalize="peak")
    assert kp.max() == pytest.approx(1.0, abs=1e-9)
    assert t[np.argmax(kp)] == pytest.approx(t_peak, abs=1e-4)


def test_psp_kernel_causal():
    assert np.all(cn.psp_kernel(np.array([-3.0, -0.1, 0.0])) == 0.0)
    assert cn.psp_kernel(np.array([0.5]))[0] > 0.0


# ----------------------------------------------------------------------------- drive

def test_psp_drive_matches_hand_sum():
    t = np.arange(400) * DT
    s0, s1 = np.array([2.0, 10.0]), np.array([5.0])
    delays = np.array([[1.0, 3.0], [0.0, 7.5]])
    weights = np.array([[1.0, 0.5], [2.0, 1.0]])
    J = 8.0
    drive = cn.psp_drive([s0, s1], delays, t, J=J, weights=weights)
    assert drive.shape == (t.size, 2)

    def psp(s):
        return np.where(s >= 0, np.exp(-np.maximum(s, 0) / 2.0) - np.exp(-np.maximum(s, 0) / 0.5),
                        0.0)

    for c in range(2):
        exp = np.zeros_like(t)
        for i, s in enumerate((s0, s1)):
            for tj in s:
                exp += J * weights[c, i] * psp(t - tj - delays[c, i])
        assert np.allclose(drive[:, c], exp, rtol=1e-12, atol=1e-12)


def test_delays_shift_the_drive():
    t = np.arange(1000) * DT
    spikes = [np.array([5.0, 9.0])]
    base = cn.psp_drive(spikes, [[0.0]], t)[:, 0]
    for n_shift in (16, 50, 160):                     # 1 ms, 3.125 ms, 10 ms
        shifted = cn.psp_drive(spikes, [[n_shift * DT]], t)[:, 0]
        assert np.all(shifted[:n_shift] == 0.0)
        assert np.allclose(shifted[n_shift:], base[:-n_shift], rtol=1e-12, atol=1e-12)
        peak_shift = np.argmax(shifted) - np.argmax(base)
        assert peak_shift == n_shift


def test_drive_evaluated_at_update_start():
    # with a spike at t = 0 and no delay, the drive at update 0 (t = 0) is PSP(0) = 0, and the
    # drive at update k is PSP(k dt)
    t = np.arange(50) * DT
    d = cn.psp_drive([np.array([0.0])], [[0.0]], t, J=1.0)[:, 0]
    assert d[0] == 0.0
    assert d[10] == pytest.approx(math.exp(-10 * DT / 2.0) - math.exp(-10 * DT / 0.5), rel=1e-12)


# ----------------------------------------------------------------------------- coincidence

# Afferent A fires a doublet (two spikes 3 ms apart) starting at 50 ms; afferent B fires the same
# doublet L = 15 ms later. With J = 8 and the raw bi-exponential PSP (default normalization), one
# afferent spike peaks at ~3.8 mV/ms and is far below the RS firing threshold; a single afferent's
# doublet alone does not fire the neuron either, but the two doublets superimposed do. (Single-
# spike pairs are not used: two coincident raw PSPs with J = 8 sit right at threshold.)
L_MS = 15.0
A_SPIKES = np.array([50.0, 53.0])
B_SPIKES = A_SPIKES + L_MS
DURATION = 150.0


def _run(delays, J=8.0, inputs=None):
    inputs = [A_SPIKES, B_SPIKES] if inputs is None else inputs
    return cn.simulate_cuneate(inputs, np.asarray(delays, dtype=float), DURATION, dt_ms=DT, J=J)


def test_compensating_delay_fires_mismatched_does_not():
    # CN0: delay(A) - delay(B) = L  -> PSPs coincide
    # CN1: delay difference L + 10 -> PSPs 10 ms apart
    # CN2: no delay difference      -> PSPs L = 15 ms apart
    # CN3: delay difference L - 30  -> PSPs 30 ms apart (A at 52 ms, B at 82 ms)
    delays = [[L_MS + 2.0, 2.0], [L_MS + 10.0 + 2.0, 2.0], [2.0, 2.0], [2.0, 17.0]]
    res = _run(delays)
    counts = res.spike_counts
    assert counts[0] >= 1
    assert counts[1] == 0 and counts[2] == 0 and counts[3] == 0
    # the matched neuron fires after the coincident arrival (B's doublet arrives at 67 ms)
    assert res.spikes_ms[0][0] > B_SPIKES[0] + 2.0


@pytest.mark.parametrize("J", [6.0, 7.0, 8.0])
def test_selectivity_is_not_a_knife_edge(J):
    res = _run([[L_MS, 0.0], [L_MS + 10.0, 0.0]], J=J)
    assert res.spike_counts[0] >= 1 and res.spike_counts[1] == 0


def test_single_afferent_alone_does_not_fire():
    res = _run([[L_MS, 0.0]], inputs=[A_SPIKES, np.array([])])
    assert res.spike_counts[0] == 0
    res = _run([[L_MS, 0.0]], inputs=[np.array([]), B_SPIKES])
    assert res.spike_counts[0] == 0


def test_result_is_izhikevich_simulate_with_the_drive():
    delays = np.array([[L_MS, 0.0], [0.0, 0.0]])
    res = _run(delays)
    n_steps = round(DURATION / DT)
    drive = cn.psp_drive([A_SPIKES, B_SPIKES], delays, np.arange(n_steps) * DT)
    ref = izhikevich.simulate("RS", drive, n_steps=n_steps, n_neurons=2, dt_ms=DT)
    for a, b in zip(res.spikes_ms, ref.spikes_ms):
        assert np.array_equal(a, b)
    assert np.array_equal(res.v, ref.v)


def test_peak_normalized_j8_single_psp_fires_from_rest():
    # documented caveat: with PSP peak-normalized to 1, J = 8 fires an RS neuron at rest on a
    # single PSP, so there is no coincidence selectivity at that normalization
    rest_v = -70.0    # resting point of RS: 0.04 v^2 + 4.8 v + 140 = 0 -> v = -70, u = b v
    res = cn.simulate_cuneate([np.array([10.0])], [[0.0]], 60.0, J=8.0, normalize="peak",
                              v0=rest_v, u0=0.2 * rest_v)
    assert res.spike_counts[0] == 1


# ----------------------------------------------------------------------------- validation

@pytest.mark.parametrize("inputs, delays, pattern", [
    ([np.array([1.0])], [[-1.0]], "delays_ms must be >= 0"),
    ([np.array([1.0])], [[np.nan]], "non-finite"),
    ([np.array([np.nan])], [[0.0]], "non-finite"),
    ([np.array([1.0]), np.array([2.0])], [[0.0]], "shape"),
    (np.array([1.0, 2.0]), [[0.0]], "one 1-D array"),
    ([], [[0.0]], "empty"),
])
def test_validation(inputs, delays, pattern):
    with pytest.raises(ValueError, match=pattern):
        cn.psp_drive(inputs, delays, np.arange(10) * DT)


def test_bad_j_and_duration():
    with pytest.raises(ValueError, match="J"):
        cn.psp_drive([np.array([1.0])], [[0.0]], np.arange(10) * DT, J=np.inf)
    with pytest.raises(ValueError, match="duration_ms"):
        cn.simulate_cuneate([np.array([1.0])], [[0.0]], -5.0)
    with pytest.raises(ValueError, match="weights"):
        cn.psp_drive([np.array([1.0])], [[0.0]], np.arange(10) * DT, weights=[[1.0], [1.0]])


def test_peak_normalization_is_a_rescaling_of_the_default():
    tr, td = 0.5, 2.0
    tp = tr * td / (td - tr) * math.log(td / tr)
    raw_peak = math.exp(-tp / td) - math.exp(-tp / tr)
    t = np.arange(300) * DT
    spikes = [np.array([1.0, 4.0]), np.array([2.0])]
    d_raw = cn.psp_drive(spikes, [[0.0, 1.0]], t, J=8.0)
    d_peak = cn.psp_drive(spikes, [[0.0, 1.0]], t, J=8.0 * raw_peak, normalize="peak")
    assert np.allclose(d_raw, d_peak, rtol=1e-12, atol=1e-14)
