"""The compiled golden loop gives the same state, spikes and divergence reports as the
vectorized reference loop (``kernel="numpy"``), to the bit."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cuneate.golden import izhikevich as golden
from cuneate.golden.behaviours import BEHAVIOURS

MIX = ["RS", "IB", "CH", "FS", "LTS", "RZ", BEHAVIOURS["G"].params, BEHAVIOURS["R"].params]


def both(**kw):
    ref = golden.simulate(kernel="numpy", **kw)
    fast = golden.simulate(kernel="numba", **kw)
    return ref, fast


def assert_same(ref, fast):
    assert np.array_equal(ref.v, fast.v, equal_nan=True)
    assert np.array_equal(ref.u, fast.u, equal_nan=True)
    assert ref.v.dtype == fast.v.dtype
    assert len(ref.spikes_ms) == len(fast.spikes_ms)
    assert all(np.array_equal(a, b) for a, b in zip(ref.spikes_ms, fast.spikes_ms))
    assert all(np.array_equal(a, b) for a, b in zip(ref.spike_steps, fast.spike_steps))


# float64 with the Izhikevich scheme in the default lane; Euler and float32 (its own compiled
# loops) in the long lane
@pytest.mark.parametrize("scheme", [pytest.param("euler", marks=pytest.mark.long), "izhikevich"])
@pytest.mark.parametrize("dtype", [np.float64, pytest.param(np.float32, marks=pytest.mark.long)])
def test_same_spikes_and_state_mixed_sets_all_current_forms(scheme, dtype):
    n, steps = 40, 3000
    params = [MIX[i % len(MIX)] for i in range(n)]
    rng = np.random.default_rng(1)
    per_neuron = rng.uniform(-5, 40, n)
    forms = {
        "scalar": 12.0,
        "per-step": 10 + 10 * np.sin(np.arange(steps) / 300.0),
        "2-D": rng.uniform(-5, 40, (steps, n)),
        "broadcast": np.broadcast_to(per_neuron, (steps, n)),
        "callable": lambda t: per_neuron * (1 + 0.5 * np.sin(t / 20.0)),
    }
    for name, cur in forms.items():
        ref, fast = both(params=params, current=cur, n_steps=steps, n_neurons=n,
                         scheme=scheme, dtype=dtype)
        assert sum(map(len, ref.spikes_ms)) > 0, name
        assert_same(ref, fast)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(a=st.floats(-0.05, 1.0), b=st.floats(-1.0, 1.0), c=st.floats(-80.0, -40.0),
       d=st.floats(-20.0, 10.0), I=st.floats(-20.0, 60.0), v0=st.floats(-90.0, 29.0),
       u0=st.floats(-30.0, 30.0), dt=st.sampled_from([1 / 16, 1 / 20, 0.25]),
       scheme=st.sampled_from(["euler", "izhikevich"]))
def test_same_bits_random_parameters_and_states(a, b, c, d, I, v0, u0, dt, scheme):
    kw = dict(params=[(a, b, c, d), "RS"], current=lambda t: np.array([I, I * 0.5]),
              n_neurons=2, n_steps=800, dt_ms=dt, scheme=scheme, v0=[v0, -65.0],
              u0=[u0, -13.0])
    try:
        ref = golden.simulate(kernel="numpy", **kw)
    except golden.DivergenceError as e:
        with pytest.raises(golden.DivergenceError) as f:
            golden.simulate(kernel="numba", **kw)
        assert (e.neuron, e.step, e.v, e.u) == (f.value.neuron, f.value.step, f.value.v,
                                                f.value.u) or np.isnan(e.v) or np.isnan(e.u)
        assert str(e) == str(f.value)
        return
    assert_same(ref, golden.simulate(kernel="numba", **kw))


# two threads in the default lane, one in the long lane
@pytest.mark.parametrize("threads", [pytest.param(1, marks=pytest.mark.long), 2])
def test_divergence_detected_and_named_identically(threads):
    """Neurons diverge at different updates (a large step and currents): the first update
    with a diverged state and the lowest neuron in it are named, with the same values."""
    n, steps = 12, 400
    cur = np.full((steps, n), 10.0)
    onset = [300, 250, 120, 390, 120, 200, 350, 120, 260, 330, 310, 280]   # first: 2, 4, 7
    for i, k in enumerate(onset):
        cur[k:, i] = 400000.0
    kw = dict(params="RS", current=cur, n_neurons=n, n_steps=steps)
    with pytest.raises(golden.DivergenceError) as e:
        golden.simulate(kernel="numpy", **kw)
    with pytest.raises(golden.DivergenceError) as f:
        golden.simulate(kernel="numba", threads=threads, **kw)
    assert (e.value.neuron, e.value.step) == (f.value.neuron, f.value.step) == (2, 120)
    assert str(e.value) == str(f.value)
    # another order and a tighter bound: the lowest diverged neuron of that update
    kw["state_bound"] = 120.0
    kw["current"] = cur[:, ::-1].copy()
    with pytest.raises(golden.DivergenceError) as e:
        golden.simulate(kernel="numpy", **kw)
    with pytest.raises(golden.DivergenceError) as f:
        golden.simulate(kernel="numba", threads=threads, **kw)
    assert str(e.value) == str(f.value) and (e.value.neuron, e.value.step) == (4, 120)


def test_threads_progress_and_kernel_choice():
    n = 300
    cur = np.linspace(0.0, 30.0, n)
    one = golden.simulate("RS", np.broadcast_to(cur, (2500, n)), n_neurons=n, n_steps=2500,
                          threads=1)
    seen = []
    two = golden.simulate("RS", np.broadcast_to(cur, (2500, n)), n_neurons=n, n_steps=2500,
                          threads=2, progress=seen.append)
    assert_same(one, two)
    assert seen == [1000, 2000]
    ref = golden.simulate("RS", np.broadcast_to(cur, (2500, n)), n_neurons=n, n_steps=2500,
                          kernel="numpy")
    assert_same(ref, one)
    # record and rk4 take the reference loop; asking the kernel for them is refused
    r = golden.simulate("RS", 10.0, n_steps=100, record=True)
    assert r.v_trace.shape == (101, 1)
    with pytest.raises(ValueError, match="numba golden kernel"):
        golden.simulate("RS", 10.0, n_steps=10, scheme="rk4", kernel="numba")
    with pytest.raises(ValueError, match="unknown golden kernel"):
        golden.simulate("RS", 10.0, n_steps=10, kernel="cuda")


# the long lane (CI): blocks of every partial size
@pytest.mark.long
def test_blocks_partial_block_buffer_growth_and_divergence_order():
    """Several blocks of neurons (the last partial), mixed sets, a 2-D current with many
    spikes (the spike buffer grows mid-run): same bits as the reference loop on one and two
    threads; a later block that diverges at an earlier update is the one named."""
    from cuneate.golden.izhikevich_kernel import BLOCK
    n, steps = 2 * BLOCK + 77, 600
    params = [MIX[(i // 5) % len(MIX)] for i in range(n)]
    rng = np.random.default_rng(7)
    cur = rng.uniform(0.0, 60.0, (steps, n))
    ref = golden.simulate(kernel="numpy", params=params, current=cur, n_steps=steps,
                          n_neurons=n)
    assert sum(map(len, ref.spikes_ms)) > 8 * n
    for threads in (1, 2):
        assert_same(ref, golden.simulate(kernel="numba", threads=threads, params=params,
                                         current=cur, n_steps=steps, n_neurons=n))
    cur = np.full((steps, n), 10.0)
    cur[300:, 3] = cur[90:, BLOCK + 9] = cur[90:, 2 * BLOCK + 5] = 400000.0
    kw = dict(params="RS", current=cur, n_neurons=n, n_steps=steps)
    with pytest.raises(golden.DivergenceError) as e:
        golden.simulate(kernel="numpy", **kw)
    for threads in (1, 2):
        with pytest.raises(golden.DivergenceError) as f:
            golden.simulate(kernel="numba", threads=threads, **kw)
        assert str(e.value) == str(f.value) and e.value.neuron == BLOCK + 9
