"""Hard cases: extreme and adversarial inputs, parameter extremes, long runs, divergence,
accumulator limits, unstable filters and property-based RTL = twin checks. Each case records
what it tried (``cuneate hardcases summary``)."""

import numpy as np
import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

from cuneate.golden import izhikevich as golden
from cuneate.golden.fbg import IIRFilter, design_bandpass
from cuneate.hdl.izhikevich import ConfigError, IzhikevichConfig, IzhikevichTwin
from cuneate.hdl.lif import LifConfig, LifTwin
from cuneate.sim.engines.registry import engine_for
from cuneate.sim.hardcases import record
from cuneate.sim.scenes import DEFAULT_SCENE_TOML, SceneError, parse_scene

SETS = ("RS", "IB", "CH", "FS", "LTS", "RZ")


def _core(n, **kw):
    return IzhikevichConfig(n_neurons=n, clock_hz=16e3 * n, param_sets=SETS,
                            neuron_sets=[i % len(SETS) for i in range(n)], **kw)


def _drive(cfg, schedule, n_sweeps):
    """Run the twin with ``schedule(k) -> currents``; check every sweep's state against the
    proven ranges and count clamps. Returns (updates, out-of-range updates, clamp events)."""
    twin = IzhikevichTwin(cfg)
    lo_v, hi_v = cfg.v_floor_raw, cfg.VTH.raw
    bad = 0
    for k in range(n_sweeps):
        twin.set_currents(schedule(k))
        twin.sweep()
        bad += int(np.count_nonzero((twin.v < lo_v) | (twin.v > hi_v)
                                    | (twin.u < cfg.u_lo_raw) | (twin.u > cfg.u_hi_raw)))
    return cfg.n_neurons * n_sweeps, bad, sum(twin.clamp_counts.values())


STIMULI = {
    "full_scale_positive": lambda n: (lambda k: np.full(n, 511.99)),
    "full_scale_negative": lambda n: (lambda k: np.full(n, -512.0)),
    "step_neg_to_pos": lambda n: (lambda k: np.full(n, -512.0 if k < 4000 else 511.99)),
    "square_at_tick_rate": lambda n: (lambda k: np.full(n, 511.99 if k % 2 else -512.0)),
    "square_slow": lambda n: (lambda k: np.full(n, 511.99 if (k // 800) % 2 else -512.0)),
    "ramp_full_range": lambda n: (lambda k: np.full(n, -512.0 + 1023.99 * k / 8000)),
    "random_every_tick": lambda n: (lambda k, r=np.random.default_rng(5):
                                    r.uniform(-512, 511.99, n)),
}


@pytest.mark.parametrize("name", list(STIMULI))
def test_adversarial_currents_stay_in_the_proven_range(name):
    cfg = _core(12)
    updates, bad, clamps = _drive(cfg, STIMULI[name](12), 8000)
    record(f"izhikevich_{name}", 12, updates, bad + clamps, "6 presets, 0.5 s, default core")
    assert bad == 0 and clamps == 0


def test_ten_million_updates_mixed_presets():
    """1000 neurons of six presets, currents over the whole accepted range changing every
    100 sweeps, 10 000 sweeps (>= 10^7 updates): never out of range, no clamp."""
    n = 1000
    rng = np.random.default_rng(11)
    levels = rng.uniform(-512, 511.99, (100, n))
    cfg = _core(n)
    updates, bad, clamps = _drive(cfg, lambda k: levels[k // 100], 10_000)
    record("izhikevich_1e7_updates", n, updates, bad + clamps, "1000 neurons, 6 presets")
    assert updates >= 10**7 and bad == 0 and clamps == 0


@pytest.mark.parametrize("kw,match", [
    ({"param_sets": [(0.02, 0.2, 30.0, 8.0)]}, "not below threshold"),     # c at threshold
    ({"v_int_bits": 2}, "too narrow"),                                     # format edge
    ({"operand_width": 7}, "operand_width"),
    ({"param_sets": [(0.02, 0.2, -65.0, 1e6)]}, "diverges"),              # huge d
])
def test_parameter_extremes_are_refused_not_wrapped(kw, match):
    with pytest.raises(ConfigError, match=match):
        IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, **kw)
    record(f"izhikevich_refused_{'_'.join(kw)}", 1, 0, 0, match or "refused")


def test_reset_exactly_at_threshold_is_refused_by_golden():
    with pytest.raises(ValueError, match="threshold"):
        golden.simulate([(0.02, 0.2, 30.0, 8.0)], 10.0, n_neurons=1, duration_ms=10.0)
    record("golden_reset_at_threshold", 1, 0, 0, "c = v_th refused")


@pytest.mark.parametrize("dt_ms,scheme", [(1.0, "euler"), (2.0, "izhikevich"), (4.0, "rk4")])
def test_float_divergence_raises_and_never_returns_nan(dt_ms, scheme):
    """Full-scale inhibition with a step large enough that explicit integration overshoots
    without bound: the golden model names the divergence instead of returning inf or NaN."""
    with pytest.raises(golden.DivergenceError) as e:
        golden.simulate("RS", -500.0, n_neurons=1, duration_ms=200.0, dt_ms=dt_ms,
                        scheme=scheme)
    assert "diverged" in str(e.value) or "diverge" in str(e.value)
    record(f"golden_divergence_{scheme}", 1, 0, 0, f"dt {dt_ms} ms raises DivergenceError")


def test_lif_accumulator_at_its_limit():
    """64 inputs, every weight at the format's maximum, every input spiking every tick: the
    derived accumulator holds the sum (no wrap, no clamp) for 2000 ticks."""
    n_in = 64
    w = np.full((8, n_in), 0.99)
    cfg = LifConfig(n_neurons=8, form="discrete", weights=w, weight_bits=8,
                    current_format=(4, 12), param_sets=[{"alpha": 0.389, "u_th": 0.65}])
    twin = LifTwin(cfg)
    x = np.ones(n_in, dtype=bool)
    spikes = 0
    for _ in range(2000):
        spikes += int(twin.sweep(x).sum())
    clamps = sum(twin.clamp_report()["counts"].values())
    record("lif_accumulator_limit", 1, 2000 * 8, clamps, f"acc {cfg.acc_bits} bits")
    assert clamps == 0 and spikes > 0
    with pytest.raises(Exception, match="acc"):
        LifConfig(n_neurons=8, form="discrete", weights=w, weight_bits=8, acc_bits=8,
                  current_format=(4, 12), param_sets=[{"alpha": 0.389, "u_th": 0.65}])


def test_filter_with_quantized_coefficients_outside_the_unit_circle_is_refused():
    """A stable 1-16 Hz band-pass at 1 kHz whose coefficients, rounded to 3 decimals as
    published, move a pole onto or outside the unit circle: refused by the scene."""
    good = design_bandpass(1.0, 16.0, 1000.0, 2, "butter")
    assert good.check().stable
    b, a = np.round(good.b, 3), np.round(good.a, 3)
    rounded = IIRFilter(b=b, a=a)
    assert not rounded.check().stable
    text = DEFAULT_SCENE_TOML.replace(
        "filter_low_hz = 1", f"filter_low_hz = 1\nfilter_b = {b.tolist()}\n"
                             f"filter_a = {a.tolist()}")
    with pytest.raises(SceneError, match="unstable filter: pole"):
        parse_scene(text, "q.toml")
    record("filter_quantized_unstable", 2, 0, 0, "3-decimal coefficients refused")


STATE = st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0))


# the long lane (CI): six random configurations, each through the Amaranth simulator
@pytest.mark.long
@settings(max_examples=6, deadline=None, phases=[Phase.explicit, Phase.reuse, Phase.generate])
@given(rounding=st.sampled_from(["nearest", "truncate"]),
       width=st.sampled_from([18, 20]),
       sets=st.lists(st.sampled_from(SETS), min_size=1, max_size=3, unique=True),
       states=st.lists(STATE, min_size=8, max_size=8))
def test_property_rtl_equals_twin_on_random_configs_and_states(rounding, width, sets, states):
    """Amaranth simulator and twin: the same spikes and clamp counts from random initial
    states inside the proven ranges, random currents, random parameter-set mixes."""
    probe = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, param_sets=tuple(sets),
                             operand_width=width, rounding=rounding)
    (vlo, vhi), (ulo, uhi) = probe.proven["v"], probe.proven["u"]
    v0 = [vlo + (vhi - 1 - vlo) * a for a, _, _ in states]
    u0 = [ulo + (uhi - ulo) * b for _, b, _ in states]
    cur = [-100 + 611.99 * c for _, _, c in states]      # mostly spiking, some inhibited
    cfg = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, param_sets=tuple(sets),
                           neuron_sets=[i % len(sets) for i in range(8)], operand_width=width,
                           rounding=rounding, v_init=v0, u_init=u0, tick_source="external")
    n_sweeps = 40
    rtl = engine_for("izhikevich", "amaranth").run(cfg, np.array(cur), n_sweeps, 8)
    rtl_sweeps = [rtl.spike_ticks(i).tolist() for i in range(8)]
    twin = IzhikevichTwin(cfg)
    twin.set_currents(np.array(cur))
    twin_sweeps = [[] for _ in range(8)]
    for k in range(n_sweeps):
        for i in np.flatnonzero(twin.sweep()):
            twin_sweeps[i].append(k)
    mism = sum(a != b for a, b in zip(rtl_sweeps, twin_sweeps)) + \
        int(rtl.clamp_counts != twin.clamp_counts)
    record(f"property_rtl_twin_{rounding}_{width}_{len(sets)}", 1, 8 * n_sweeps, mism,
           "random states, currents, set mixes")
    assert mism == 0
