"""The compiled LIF twin kernel equals the stage-function twin bit for bit.

Property tests draw states over the whole state format, refractory counters, currents over the
whole current format (so the current clamp acts where one is built), input-spike vectors,
synaptic traces over their proven ranges and set indices, for every form (continuous, discrete),
decay (multiply, mixed per-set shifts), rounding, clamp option (current, input, state floor) and
with AMPA/GABA traces. Long runs compare spikes, final state, traces, clamp counts and sticky flags
over programs with per-sweep currents and input spikes.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cuneate.hdl.lif import kernel as kernel
from cuneate.hdl.lif import CLAMP_KINDS, LifConfig, LifTwin

pytestmark = pytest.mark.skipif(not kernel.available(), reason="numba not installed")

N = 16
_rng = np.random.default_rng(11)
_W_DISCRETE = _rng.integers(-8, 8, (N, 6)) / 8.0
_W_SYN = _rng.uniform(0, 20, (N, 4))
_W_CLAMP = np.vstack([np.zeros((N // 2, 3)), np.full((N - N // 2, 3), 100.0)])
_TWO = {"neuron_sets": [i % 2 for i in range(N)]}


def _cfg(**kw):
    return LifConfig(n_neurons=N, tick_source="external", **kw)


CONFIGS = {
    "continuous-multiply": lambda: _cfg(
        param_sets=[{"tau_m_ms": 2.0, "t_ref_ms": 0.25}, {"tau_m_ms": 1.0, "v_rest": -1.0}],
        **_TWO),
    "continuous-multiply-truncate": lambda: _cfg(
        param_sets=[{"tau_m_ms": 2.0, "t_ref_ms": 0.5}, {"tau_m_ms": 10.0}], rounding="truncate",
        update_hz=20e3, **_TWO),
    "continuous-shift": lambda: _cfg(
        decay="shift", param_sets=[{"tau_m_ms": 8.0, "t_ref_ms": 0.125}, {"tau_m_ms": 16.0}],
        **_TWO),
    "discrete-weights": lambda: _cfg(
        form="discrete", weights=_W_DISCRETE, weight_bits=4, current_format=(4, 12),
        param_sets=[{"alpha": 0.389, "u_th": 0.65, "refractory_steps": 1},
                    {"alpha": 0.9, "u_th": 0.3, "refractory_steps": 3}], **_TWO),
    "discrete-truncate": lambda: _cfg(
        form="discrete", weights=_W_DISCRETE, weight_bits=8, current_format=(4, 12),
        rounding="truncate", param_sets=[{"alpha": 0.5, "u_th": 0.5}]),
    "synapses": lambda: _cfg(
        synapses=True, weights=_W_SYN, input_types=["exc", "exc", "inh", "exc"],
        update_hz=2000.0, param_sets=[{"tau_m_ms": 5.0, "t_ref_ms": 1.0}]),
    "synapses-truncate": lambda: _cfg(
        synapses=True, weights=_W_SYN, input_types=["inh", "exc", "inh", "exc"],
        update_hz=4000.0, rounding="truncate",
        param_sets=[{"tau_m_ms": 5.0, "t_ref_ms": 1.0}, {"tau_m_ms": 3.0}], **_TWO),
    "clamps": lambda: _cfg(
        weights=_W_CLAMP, input_limit=(-50.0, 150.0), saturation="flag",
        current_range=(-60.0, 100.0), v_int_bits=6,
        param_sets=[{"tau_m_ms": 0.5, "v_reset": -20.0}]),
}
_built: dict = {}


def config(name) -> LifConfig:
    if name not in _built:
        _built[name] = CONFIGS[name]()
    return _built[name]


def test_the_configurations_cover_what_they_claim():
    c = {k: config(k) for k in CONFIGS}
    assert len(set(c["continuous-shift"].k_shift)) == 2
    assert c["discrete-weights"].n_inputs and c["discrete-weights"].form == "discrete"
    assert c["synapses"].synapses and not c["synapses"].input_exc.all()
    assert all(c["clamps"].clamp_can_act[k] for k in CLAMP_KINDS)
    assert c["clamps"].v_clamp and c["clamps"].input_clamp and c["clamps"].current_clamp
    assert all(LifTwin(cfg).kernel == "numba" for cfg in c.values())


def _random_state(cfg, rng, n, edge):
    V, I = cfg.V, cfg.I
    if edge == "uniform":
        v = rng.integers(V.min_raw, V.max_raw, n, endpoint=True)
        i = rng.integers(I.min_raw, I.max_raw, n, endpoint=True)
    elif edge == "extremes":
        vs = [V.min_raw, V.max_raw, cfg.v_floor_raw, 0, -1, *cfg.th_cmp_raw,
              *(t - 1 for t in cfg.th_cmp_raw), *(c.raw for c in cfg.RESET)]
        is_ = [I.min_raw, I.max_raw, cfg.i_lo_raw, cfg.i_hi_raw, cfg.i_lo_raw - 1,
               cfg.i_hi_raw + 1, 0, 1]
        v = rng.choice(np.clip(vs, V.min_raw, V.max_raw), n)
        i = rng.choice(np.clip(is_, I.min_raw, I.max_raw), n)
    else:                        # just below and at the thresholds
        th = np.asarray(cfg.th_cmp_raw)[rng.integers(0, len(cfg.sets), n)]
        v = th - rng.integers(-4, 1 << (V.frac_bits - 2), n)
        i = rng.integers(cfg.i_lo_raw, cfg.i_hi_raw, n, endpoint=True)
    ref = rng.integers(0, max(1, (1 << cfg.ref_bits) - 1), n, endpoint=True) \
        if cfg.ref_bits else np.zeros(n, np.int64)
    sel = rng.integers(0, len(cfg.sets), n)
    x = rng.random(cfg.n_inputs) < rng.random()
    tr = None
    if cfg.synapses:
        tr = np.array([rng.integers(t.t_bounds[0], t.t_bounds[1], n, endpoint=True)
                       for t in cfg.traces])
    return v, ref, i, sel, x, tr


def _assert_same(ref_out, k_out, ctx):
    for key in ("v", "ref", "spike", "v_pre", "d", "acc", "clamp"):
        a = np.asarray(ref_out[key]).astype(np.int64)
        b = np.asarray(k_out[key]).astype(np.int64)
        assert np.array_equal(np.broadcast_to(a, b.shape), b), \
            f"{ctx}{key}: first difference at {np.flatnonzero(np.broadcast_to(a, b.shape) != b)[:3]}"
    if "traces" in ref_out:
        assert np.array_equal(ref_out["traces"], k_out["traces"]), f"{ctx}traces"


@pytest.mark.long
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(sorted(CONFIGS)), seed=st.integers(0, 2**32 - 1),
       edge=st.sampled_from(["uniform", "extremes", "near-threshold"]))
def test_kernel_update_equals_stages_on_random_states(name, seed, edge):
    cfg = config(name)
    twin = LifTwin(cfg, kernel="stages")
    consts = kernel.gather_constants(cfg)
    rng = np.random.default_rng(seed)
    n = 256
    v, ref, i, sel, x, tr = _random_state(cfg, rng, n, edge)
    W = np.ascontiguousarray(np.resize(cfg.weights_raw, (n, cfg.n_inputs)), dtype=np.int64)
    twin.W = W
    a = twin.update(v, ref, i, x, sel, tr)
    b = kernel.update_arrays(consts, *(np.ascontiguousarray(z, dtype=np.int64)
                                       for z in (v, ref, i, sel)), x, W, tr)
    _assert_same(a, b, f"{name}/{edge}: ")


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_every_buildable_clamp_acts_equally_at_the_extremes(name):
    cfg = config(name)
    consts = kernel.gather_constants(cfg)
    twin = LifTwin(cfg, kernel="stages")
    V, I = cfg.V, cfg.I
    grid = np.array(np.meshgrid([V.min_raw, cfg.v_floor_raw, 0, max(cfg.th_cmp_raw), V.max_raw],
                                [I.min_raw, cfg.i_lo_raw, 0, cfg.i_hi_raw, I.max_raw],
                                range(len(cfg.sets)))).reshape(3, -1)
    n = grid.shape[1]
    W = np.ascontiguousarray(np.resize(cfg.weights_raw, (n, cfg.n_inputs)), dtype=np.int64)
    twin.W = W
    ref = np.zeros(n, np.int64)
    tr = np.zeros((4, n), np.int64) if cfg.synapses else None
    for x in (np.zeros(cfg.n_inputs, bool), np.ones(cfg.n_inputs, bool)):
        a = twin.update(grid[0], ref, grid[1], x, grid[2], tr)
        b = kernel.update_arrays(consts, grid[0].copy(), ref, grid[1].copy(), grid[2].copy(), x,
                                 W, tr)
        _assert_same(a, b, f"{name}: ")
        if name == "clamps" and x.all():
            assert all(((b["clamp"] >> j) & 1).any() for j in range(len(CLAMP_KINDS)))


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_long_run_equal_spikes_state_traces_and_clamps(name):
    """3000 sweeps of a program with per-sweep currents over the whole current format and random
    input spikes, then constant currents by run(), then single sweeps: identical spikes, state,
    traces and clamp bookkeeping."""
    cfg = config(name)
    ref, fast = LifTwin(cfg, kernel="stages"), LifTwin(cfg, kernel="numba")
    rng = np.random.default_rng(5)
    n_sweeps = 3000
    lo, hi = max(cfg.I.min_value, cfg.i_lo - 20), min(cfg.I.max_value, cfg.i_hi + 20)
    level = rng.uniform(lo, hi, N)
    cur = np.clip(level + rng.normal(0, 0.2 * (hi - lo), (n_sweeps, N)) *
                  (rng.random((n_sweeps, 1)) < 0.2), cfg.I.min_value, cfg.I.max_value)
    raw = np.asarray(cfg.I.to_raw(cur), dtype=np.int64)
    X = rng.random((n_sweeps, cfg.n_inputs)) < 0.25 if cfg.n_inputs else None
    ka, na = ref.run_raw(raw, n_sweeps, X)
    kb, nb = fast.run_raw(raw, n_sweeps, X)
    assert ka.size > 0
    oa, ob = np.lexsort((na, ka)), np.lexsort((nb, kb))
    assert np.array_equal(ka[oa], kb[ob]) and np.array_equal(na[oa], nb[ob])

    def same_state():
        assert np.array_equal(ref.v, fast.v) and np.array_equal(ref.ref, fast.ref)
        assert np.array_equal(ref.traces, fast.traces) and np.array_equal(ref.I, fast.I)
        assert ref.clamp_counts == fast.clamp_counts and ref.clamp_sticky == fast.clamp_sticky
        assert ref.sweeps == fast.sweeps
    same_state()
    if name == "clamps":
        assert all(fast.clamp_report()["sticky"].values()), fast.clamp_report()
    Xc = rng.random((500, cfg.n_inputs)) < 0.1 if cfg.n_inputs else None
    a, b = ref.run(level, 500, Xc), fast.run(level, 500, Xc)
    assert all(np.array_equal(p, q) for p, q in zip(a, b))
    same_state()
    for k in range(200):
        x = rng.random(cfg.n_inputs) < 0.3
        assert np.array_equal(ref.sweep(x), fast.sweep(x))
    same_state()


@pytest.mark.parametrize("name", ["synapses-truncate", "discrete-weights", "clamps"])
def test_threaded_split_changes_nothing(name):
    """The population split over threads (uneven chunks) gives the same spikes and state."""
    cfg = config(name)
    one, three = LifTwin(cfg, threads=1), LifTwin(cfg, threads=3)
    rng = np.random.default_rng(8)
    raw = np.asarray(cfg.I.to_raw(rng.uniform(cfg.I.min_value, cfg.I.max_value, (800, N))),
                     dtype=np.int64)
    X = rng.random((800, cfg.n_inputs)) < 0.3
    (ka, na), (kb, nb) = one.run_raw(raw, 800, X), three.run_raw(raw, 800, X)
    oa, ob = np.lexsort((na, ka)), np.lexsort((nb, kb))
    assert ka.size and np.array_equal(ka[oa], kb[ob]) and np.array_equal(na[oa], nb[ob])
    assert np.array_equal(one.v, three.v) and np.array_equal(one.ref, three.ref)
    assert np.array_equal(one.traces, three.traces) and one.clamp_counts == three.clamp_counts


def test_kernel_selection_and_refusals():
    cfg = config("continuous-multiply")
    assert LifTwin(cfg, check=True).kernel == "stages"
    assert LifTwin(cfg, check=True, kernel="numba").kernel == "numba"
    with pytest.raises(ValueError, match="unknown twin kernel"):
        LifTwin(cfg, kernel="cuda")
    twin = LifTwin(cfg)
    with pytest.raises(ValueError, match=r"currents must have shape \(16,\) or \(5, 16\)"):
        twin.run_raw(np.zeros((4, N), np.int64), 5)
    d = config("discrete-weights")
    with pytest.raises(ValueError, match=r"input spikes must have shape \(5, 6\)"):
        LifTwin(d).run_raw(np.zeros(N, np.int64), 5, np.zeros((5, 2), bool))
    with pytest.raises(ValueError, match="input spike vector must have 6 entries"):
        LifTwin(d).sweep(np.zeros(2, bool))
