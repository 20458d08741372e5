"""The compiled twin kernel equals the stage-function twin bit for bit.

Property tests draw states over the whole state formats, currents over the whole current format
(so out-of-range currents saturate and every clamp kind acts where the formats allow it) and set
indices, for every rounding and a range of parameter-set mixes (shared and per-set constants,
mixed ``shift_a``, ``u_leak = 0`` with ``v_u``, non-standard ``A, B, C``, ``a = 0``, a
non-power-of-two dt with its fifth multiplier, and formats narrowed below the proven range).
Long runs compare spikes, final state, clamp counts, sticky flags and the last sweep's counts.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cuneate.golden.behaviours import BEHAVIOURS
from cuneate.hdl.izhikevich import kernel as kernel
from cuneate.hdl.izhikevich import CLAMP_KINDS, IzhikevichConfig, IzhikevichTwin

pytestmark = pytest.mark.skipif(not kernel.available(), reason="numba not installed")

N = 24
FLAG = dict(v_int_bits=8, u_int_bits=5, y_int_bits=5, current_range=(-400.0, 400.0),
            saturation="flag")
MIX = ("RS", "FS", BEHAVIOURS["G"].params, BEHAVIOURS["R"].params, BEHAVIOURS["Q"].params,
       (0.0, 0.2, -60.0, 2.0))


def _cfg(sets=("RS",), update_hz=16e3, **kw):
    return IzhikevichConfig(n_neurons=N, clock_hz=update_hz * N, update_hz=update_hz,
                            param_sets=sets, neuron_sets=[i % len(sets) for i in range(N)],
                            tick_source="external", **kw)


CONFIGS = {
    "rs-nearest": lambda: _cfg(),
    "rs-truncate": lambda: _cfg(rounding="truncate"),
    "mix-nearest": lambda: _cfg(MIX, current_range=(-20.0, 40.0)),
    "mix-truncate": lambda: _cfg(MIX, current_range=(-20.0, 40.0), rounding="truncate"),
    "dt20k-nearest": lambda: _cfg(("RS", "FS", "LTS"), update_hz=20e3),
    "dt20k-truncate": lambda: _cfg(("RS", "CH"), update_hz=20e3, rounding="truncate"),
    "flag-nearest": lambda: _cfg(("RS", "FS"), **FLAG),
    "flag-truncate": lambda: _cfg(("RS", "FS"), rounding="truncate", **FLAG),
    "flag-dt20k": lambda: _cfg(("RS", "FS"), update_hz=20e3, **FLAG),
}
_built: dict = {}


def config(name) -> IzhikevichConfig:
    if name not in _built:
        _built[name] = CONFIGS[name]()
    return _built[name]


def twins(cfg, **kw):
    return IzhikevichTwin(cfg, kernel="stages", **kw), IzhikevichTwin(cfg, kernel="numba", **kw)


def test_the_mixes_cover_what_they_claim():
    """The configurations really differ where the kernel has branches."""
    mix, dt20 = config("mix-nearest"), config("dt20k-nearest")
    assert len(set(mix.shift_a)) > 1 and len({w.raw for w in mix.woff}) > 1
    assert 0 in mix.u_leak and any(e.raw for e in mix.E) and any(a.raw == 0 for a in mix.alpha)
    assert dt20.dt_shift is None and mix.dt_shift is not None
    flag = config("flag-nearest")
    assert flag.current_clamp and all(flag.clamp_can_act[k] for k in ("v_low", "u_high", "y"))


def _assert_same(ref, out, ctx=""):
    for k in ("v", "u", "spike", "v_pre", "clamp", *CLAMP_KINDS):
        a, b = np.asarray(ref[k]), np.asarray(out[k])
        assert np.array_equal(a.astype(np.int64), b.astype(np.int64)), \
            f"{ctx}{k}: first difference at {np.flatnonzero(a != b)[:3]}"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(sorted(CONFIGS)), seed=st.integers(0, 2**32 - 1),
       edge=st.sampled_from(["uniform", "extremes", "near-threshold"]))
def test_kernel_update_equals_stages_on_random_states(name, seed, edge):
    cfg = config(name)
    ref, fast = twins(cfg)
    rng = np.random.default_rng(seed)
    n = 512
    V, U, I = cfg.V, cfg.U, cfg.I
    if edge == "uniform":       # the whole state and current formats
        v = rng.integers(V.min_raw, V.max_raw, n, endpoint=True)
        u = rng.integers(U.min_raw, U.max_raw, n, endpoint=True)
        i = rng.integers(I.min_raw, I.max_raw, n, endpoint=True)
    elif edge == "extremes":    # format limits, clamp levels and their neighbours
        vs = [V.min_raw, V.max_raw, cfg.v_floor_raw, cfg.v_floor_raw + 1, cfg.VTH.raw,
              cfg.VTH.raw - 1, 0, -1]
        us = [U.min_raw, U.max_raw, cfg.u_lo_raw, cfg.u_hi_raw, cfg.u_lo_raw - 1,
              cfg.u_hi_raw + 1, 0, -1]
        is_ = [I.min_raw, I.max_raw, cfg.i_lo_raw, cfg.i_hi_raw, cfg.i_lo_raw - 1,
               cfg.i_hi_raw + 1, 0, 1]
        v, u, i = (rng.choice(np.clip(x, f.min_raw, f.max_raw), n)
                   for x, f in ((vs, V), (us, U), (is_, I)))
    else:                       # just below threshold: spike decisions and resets
        v = cfg.VTH.raw - rng.integers(0, 1 << (V.frac_bits + 2), n)
        u = rng.integers(cfg.u_lo_raw, cfg.u_hi_raw, n, endpoint=True)
        i = rng.integers(cfg.i_lo_raw, cfg.i_hi_raw, n, endpoint=True)
    sel = rng.integers(0, len(cfg.params), n)
    _assert_same(ref.update(v, u, i, sel), fast.update(v, u, i, sel), f"{name}/{edge}: ")


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_every_reachable_clamp_kind_is_exercised_and_equal(name):
    """Over the extremes every clamp kind the configuration can build acts, in both twins."""
    cfg = config(name)
    ref, fast = twins(cfg)
    V, U, I = cfg.V, cfg.U, cfg.I
    grid = np.array(np.meshgrid(
        [V.min_raw, cfg.v_floor_raw, V.to_raw(-65.0), cfg.VTH.raw - 1, V.max_raw],
        [U.min_raw, cfg.u_lo_raw, U.to_raw(0.0), cfg.u_hi_raw, U.max_raw],
        [I.min_raw, cfg.i_lo_raw, 0, cfg.i_hi_raw, I.max_raw],
        range(len(cfg.params)))).reshape(4, -1)
    a, b = ref.update(*grid), fast.update(*grid)
    _assert_same(a, b, f"{name}: ")
    acted = {k: bool(np.any(b[k])) for k in CLAMP_KINDS}
    if name.startswith("flag"):
        assert all(acted.values()), acted
    assert acted["current"] == cfg.current_clamp


# the configurations at the default rate in the default lane, at 20 kHz in the long lane
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.long) if "dt20k" in n else n
                                  for n in sorted(CONFIGS)])
def test_long_run_equal_spikes_state_and_clamp_accounting(name):
    """2000 sweeps with currents over (and beyond) the accepted range: identical spike trains,
    final state and clamp bookkeeping; then per-sweep stepping with changing currents."""
    cfg = config(name)
    ref, fast = twins(cfg)
    rng = np.random.default_rng(3)
    lo, hi = cfg.i_lo, cfg.i_hi
    cur = rng.uniform(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), N)
    cur = np.clip(cur, cfg.I.min_value, cfg.I.max_value)
    a, b = ref.run(cur, 2000), fast.run(cur, 2000)
    assert sum(map(len, a)) > 0
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert np.array_equal(ref.v, fast.v) and np.array_equal(ref.u, fast.u)
    assert ref.clamp_counts == fast.clamp_counts and ref.clamp_sticky == fast.clamp_sticky
    assert ref.last_sweep_clamps == fast.last_sweep_clamps and ref.sweeps == fast.sweeps
    if name.startswith("flag"):
        assert fast.clamp_sticky, fast.clamp_report()
    for k in range(300):
        c = rng.uniform(cfg.I.min_value, cfg.I.max_value, N) if k % 50 == 0 else cur
        ref.set_currents(c)
        fast.set_currents(c)
        assert np.array_equal(ref.sweep(), fast.sweep())
        assert ref.last_sweep_clamps == fast.last_sweep_clamps
    assert np.array_equal(ref.v, fast.v) and np.array_equal(ref.u, fast.u)
    assert ref.clamp_counts == fast.clamp_counts and ref.clamp_sticky == fast.clamp_sticky


def test_callable_currents_threads_and_progress_equal():
    """A time-varying current (callable), a threaded split of the population and progress
    reporting change nothing."""
    cfg = config("mix-nearest")
    ref, fast = twins(cfg)
    f = (lambda t: 10.0 + 25.0 * np.sin(t / 7.0) * np.linspace(-1, 1, N))
    assert all(np.array_equal(x, y) for x, y in zip(ref.run(f, 1500), fast.run(f, 1500)))
    assert np.array_equal(ref.v, fast.v) and ref.clamp_counts == fast.clamp_counts
    one, two = IzhikevichTwin(cfg, threads=1), IzhikevichTwin(cfg, threads=2)
    seen = []
    cur = np.linspace(-20.0, 40.0, N)
    s1, s2 = one.run(cur, 2500), two.run(cur, 2500, progress=seen.append)
    assert seen == [1000, 2000]
    assert all(np.array_equal(x, y) for x, y in zip(s1, s2)) and sum(map(len, s1)) > 0
    assert np.array_equal(one.v, two.v) and np.array_equal(one.u, two.u)
    assert one.last_sweep_clamps == two.last_sweep_clamps


def test_checked_mode_uses_the_stage_functions_and_refuses_bad_input():
    cfg = config("rs-nearest")
    assert IzhikevichTwin(cfg, check=True).kernel == "stages"
    assert IzhikevichTwin(cfg).kernel == "numba"
    with pytest.raises(ValueError, match="unknown twin kernel"):
        IzhikevichTwin(cfg, kernel="cuda")
    with pytest.raises(ValueError, match="parameter-set index"):
        IzhikevichTwin(cfg).update([0], [0], [0], [3])


def _several_blocks():
    n = 2 * kernel.BLOCK + 77                      # the last block partial
    return IzhikevichConfig(n_neurons=n, clock_hz=16e3 * n, param_sets=("RS", "FS"),
                            neuron_sets=[(i // 3) % 2 for i in range(n)],
                            tick_source="external", **FLAG)


def test_blocked_run_over_several_blocks_equals_the_stages():
    """A run of several blocks of neurons (the last partial), two parameter sets, every clamp
    kind acting and far more spikes than the spike buffer first holds (the run resumes where
    it stopped): the generic and the specialized loop, on one and on two threads, equal the
    stage functions (spikes, state, clamp counts, the last sweep's counts)."""
    cfg = _several_blocks()
    cur = np.random.default_rng(5).uniform(cfg.I.min_value, cfg.I.max_value, cfg.n_neurons)
    ref = IzhikevichTwin(cfg, kernel="stages")
    a = ref.run(cur, 400)
    assert sum(map(len, a)) > 8 * cfg.n_neurons and ref.clamp_sticky
    for special, threads in ((False, 1), (True, 2)):
        fast = IzhikevichTwin(cfg, specialize=special, threads=threads)
        b = fast.run(cur, 400)
        assert all(np.array_equal(x, y) for x, y in zip(a, b)), (special, threads)
        assert np.array_equal(ref.v, fast.v) and np.array_equal(ref.u, fast.u)
        assert ref.clamp_counts == fast.clamp_counts
        assert ref.last_sweep_clamps == fast.last_sweep_clamps


def test_specialized_loop_equals_the_stages():
    """The loop compiled with a configuration's constants folded in (per-set constants, mixed
    shifts, truncation) equals the stage functions (every configuration: the long lane)."""
    cfg = config("mix-truncate")
    ref = IzhikevichTwin(cfg, kernel="stages")
    fast = IzhikevichTwin(cfg, specialize=True)
    cur = np.linspace(cfg.i_lo, cfg.i_hi, N)
    a, b = ref.run(cur, 1500), fast.run(cur, 1500)
    assert sum(map(len, a)) > 0 and all(np.array_equal(x, y) for x, y in zip(a, b))
    assert np.array_equal(ref.v, fast.v) and np.array_equal(ref.u, fast.u)
    assert ref.clamp_counts == fast.clamp_counts


@pytest.mark.long
@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_long_specialized_loop_equals_the_stages_every_config(name):
    """Every configuration of the property tests, 5000 sweeps over and beyond the accepted
    currents: the specialized loop equals the stage functions."""
    cfg = config(name)
    rng = np.random.default_rng(11)
    lo, hi = cfg.i_lo, cfg.i_hi
    cur = np.clip(rng.uniform(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), N),
                  cfg.I.min_value, cfg.I.max_value)
    ref = IzhikevichTwin(cfg, kernel="stages")
    fast = IzhikevichTwin(cfg, specialize=True)
    a, b = ref.run(cur, 5000), fast.run(cur, 5000)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert np.array_equal(ref.v, fast.v) and np.array_equal(ref.u, fast.u)
    assert ref.clamp_counts == fast.clamp_counts and ref.clamp_sticky == fast.clamp_sticky
