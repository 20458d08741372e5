"""The compiled coincidence-detector twin kernel equals the stage-function twin bit for bit.

Property tests draw target states over the whole Izhikevich state formats, PSP traces over their
proven ranges, input sums over the accumulator and set indices, for both roundings and a
parameter-set mix. Long runs with random afferent spikes (merged duplicates, delays up to the
history length) compare output spikes, final state, traces, history and clamp accounting.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cuneate.hdl.coincidence import kernel as kernel
from cuneate.hdl.coincidence import CLAMP_KINDS, CoincidenceConfig, CoincidenceTwin

pytestmark = pytest.mark.skipif(not kernel.available(), reason="numba not installed")

DELAYS = [[0, 3, 1, 0, 7], [2, 0, 0, 5, 1], [7, 7, 0, 0, 4], [1, 2, 3, 4, 5]]
W = [[8, 2, 4, 1, 8], [1, 1, 1, 1, 1], [16, 0.5, 3, 2, 6], [2, 2, 2, 2, 2]]
CONFIGS = {
    "nearest": dict(),
    "truncate": dict(rounding="truncate"),
    "mix": dict(param_sets=("RS", "FS", "CH", "LTS"), target_sets=[0, 1, 2, 3]),
    "mix-truncate-fast-psp": dict(param_sets=("RS", "IB"), target_sets=[1, 0, 1, 0],
                                  rounding="truncate", tau_rise_ms=0.25, tau_decay_ms=2.0),
}
_built: dict = {}


def config(name) -> CoincidenceConfig:
    if name not in _built:
        _built[name] = CoincidenceConfig(n_sources=5, n_targets=4, delays_ticks=DELAYS,
                                         weights=W, max_delay_ticks=8, **CONFIGS[name])
    return _built[name]


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(sorted(CONFIGS)), seed=st.integers(0, 2**32 - 1),
       edge=st.sampled_from(["uniform", "near-threshold"]))
def test_kernel_update_equals_stages_on_random_states(name, seed, edge):
    cfg = config(name)
    iz = cfg.iz
    ref = CoincidenceTwin(cfg, kernel="stages")
    consts = kernel.gather_constants(cfg)
    rng = np.random.default_rng(seed)
    n = 256
    if edge == "uniform":
        v = rng.integers(iz.V.min_raw, iz.V.max_raw, n, endpoint=True)
    else:
        v = iz.VTH.raw - rng.integers(-4, 1 << (iz.V.frac_bits + 2), n)
    u = rng.integers(iz.u_lo_raw, iz.u_hi_raw, n, endpoint=True)
    xd, xr = (rng.integers(t.t_bounds[0], t.t_bounds[1], n, endpoint=True) for t in cfg.traces)
    a = rng.integers(0, cfg.acc_max_raw, n, endpoint=True)
    sel = rng.integers(0, len(cfg.param_sets), n)
    # keep the PSP current inside its proven range, as every reachable state does
    ok = (xd - xr >= cfg.isyn_bounds[0]) & (xd - xr <= cfg.isyn_bounds[1])
    v, u, xd, xr, a, sel = (np.ascontiguousarray(z[ok], dtype=np.int64)
                            for z in (v, u, xd, xr, a, sel))
    want = ref.update(v, u, xd, xr, a, sel)
    got = kernel.update_arrays(consts, v, u, xd, xr, a, sel)
    for key in ("v", "u", "xd", "xr", "spike", "i"):
        assert np.array_equal(np.asarray(want[key]).astype(np.int64),
                              got[key].astype(np.int64)), f"{name}/{edge}: {key}"
    bits = sum(np.asarray(want[k], dtype=np.int64) << b for b, k in enumerate(CLAMP_KINDS))
    assert np.array_equal(bits, got["clamp"])


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_long_run_equal_spikes_state_and_history(name):
    """4000 ticks of random afferent spikes (some sources twice in a tick), then tick by tick:
    identical output spikes, state, traces, history, merged count and clamp accounting."""
    cfg = config(name)
    ref, fast = CoincidenceTwin(cfg, kernel="stages"), CoincidenceTwin(cfg, kernel="numba")
    rng = np.random.default_rng(9)
    n_ticks = 4000
    ins = [np.sort(rng.integers(-5, n_ticks + 5, 700)) for _ in range(cfg.n_sources)]
    ra, rb = ref.run(ins, n_ticks), fast.run(ins, n_ticks)
    assert sum(map(len, ra)) > 0
    assert all(np.array_equal(p, q) for p, q in zip(ra, rb))

    def same():
        for k in ("v", "u", "xd", "xr", "history", "pending"):
            assert np.array_equal(getattr(ref, k), getattr(fast, k)), k
        assert (ref.ticks, ref.events, ref.merged) == (fast.ticks, fast.events, fast.merged)
        assert ref.clamp_counts == fast.clamp_counts and ref.clamp_sticky == fast.clamp_sticky
    same()
    assert ref.merged > 0
    for k in range(300):
        srcs = rng.integers(0, cfg.n_sources, rng.integers(0, 4))
        ref.spike_in(srcs)
        fast.spike_in(srcs)
        assert np.array_equal(ref.tick(), fast.tick())
    same()


def test_kernel_selection():
    cfg = config("nearest")
    assert CoincidenceTwin(cfg).kernel == "numba"
    assert CoincidenceTwin(cfg, kernel="stages").iz.kernel == "stages"
    with pytest.raises(ValueError, match="unknown twin kernel"):
        CoincidenceTwin(cfg, kernel="cuda")
    with pytest.raises(ValueError, match=r"pending spikes must have shape \(n_ticks, 5\)"):
        CoincidenceTwin(cfg).run_pending(np.zeros((3, 2), bool))
