"""The compiled Verilator run (C++ harness, no Python per cycle) equals the twin exactly, its
update dump passes the per-sweep checker, and that checker catches the same injected RTL faults
(a flipped product bit, a wrong rounding)."""

import numpy as np
import pytest

import cuneate.hdl.izhikevich.datapath as izh
from cuneate.hdl.lib.fixed import round_shift_add
from cuneate.hdl.izhikevich import izhikevich_verilog
from cuneate.hdl.izhikevich import CLAMP_KINDS, IzhikevichConfig, IzhikevichTwin
from cuneate.sim.izhikevich.engines import run_engine
from cuneate.sim.engines.verilator_fast import check_dump, raw_cycle_rate, run_harness

N = 16
FLAG_CORE = {"n_neurons": N, "clock_hz": 16e3 * N, "update_hz": 16e3, "tick_source": "external",
             "param_sets": ["RS", "FS", "IB", "CH"], "neuron_sets": [i % 4 for i in range(N)],
             "v_int_bits": 8, "u_int_bits": 5, "y_int_bits": 5,
             "current_range": [-400.0, 400.0], "saturation": "flag",
             "spike_fifo_depth": N + 4}


def flag_config():
    return IzhikevichConfig.from_kwargs(FLAG_CORE)


def schedule(cfg, rng, starts):
    """Segments of raw currents over the whole current format (beyond the accepted range, so
    the current clamp acts too)."""
    return [(k, rng.integers(cfg.I.min_raw, cfg.I.max_raw, cfg.n_neurons, endpoint=True))
            for k in starts]


def twin_updates(cfg, segments, n_sweeps):
    """Every update of the stage-function twin under the same schedule: (n, 5) like the dump."""
    twin = IzhikevichTwin(cfg, kernel="stages")
    rows, seg = [], -1
    for k in range(n_sweeps):
        while seg + 1 < len(segments) and segments[seg + 1][0] <= k:
            seg += 1
            twin.I[:] = segments[seg][1]
        out = twin.update(twin.v, twin.u, twin.I, twin.sel)
        rows.append(np.stack([out["v"], out["u"], twin.I, out["spike"], out["clamp"]], 1))
        twin.v, twin.u = out["v"].copy(), out["u"].copy()
    return np.concatenate(rows).astype(np.int64)


@pytest.mark.parametrize("depth", [5, pytest.param(8, marks=pytest.mark.long)])
def test_verilator_fast_equals_twin_every_update_with_a_schedule(tmp_path, depth):
    cfg = IzhikevichConfig.from_kwargs(flag_config().to_kwargs(pipeline_stages=depth))
    rng = np.random.default_rng(5)
    segs = schedule(cfg, rng, [0, 120, 121, 300])
    run = run_harness(cfg, segs, 400, dump=True, build_root=tmp_path)
    expect = twin_updates(cfg, segs, 400)
    assert run.updates.shape == expect.shape
    diff = np.flatnonzero(np.any(run.updates != expect, axis=1))
    assert diff.size == 0, f"first differing update {diff[:1]}: {run.updates[diff[0]]} " \
                           f"vs twin {expect[diff[0]]}"
    # spikes from the update port, the spike stream and the clamp counters agree
    sweeps = np.repeat(np.arange(400), N)
    hit = expect[:, 3] == 1
    assert np.array_equal(run.spike_sweeps, sweeps[hit])
    assert np.array_equal(run.spike_neurons, np.tile(np.arange(N), 400)[hit])
    assert run.summary["stream_spikes"] == run.summary["spikes"] == int(hit.sum()) > 0
    counts = {k: int(((expect[:, 4] >> b) & 1).sum()) for b, k in enumerate(CLAMP_KINDS)}
    assert run.summary["clamp_counts"] == counts and all(counts.values()), counts
    assert all(run.clamp_sticky().values())
    assert run.summary["cycles_per_s"] > 0 and run.summary["sweeps_done"] == 400


def test_verilator_fast_engine_equals_fixed_engine(tmp_path):
    core = {"param_sets": (("RS"), ("FS")), "neuron_sets": [0, 1] * 10}
    currents = list(np.linspace(-5.0, 40.0, 20))
    fast = run_engine("verilator-fast", core, currents, 150.0, build_dir=tmp_path)
    fixed = run_engine("fixed", core, currents, 150.0)
    assert fast.spikes_ms == fixed.spikes_ms and sum(map(len, fast.spikes_ms)) > 0
    assert fast.clamp_counts == fixed.clamp_counts
    assert fast.clamp_sticky == fixed.clamp_sticky
    rate = raw_cycle_rate(IzhikevichConfig.from_kwargs(
        {"n_neurons": 20, "clock_hz": 16e3 * 20, "tick_source": "external"}), 20000, tmp_path)
    assert rate["cycles"] == 20000 and rate["raw"]


def test_harness_refuses_bad_schedules(tmp_path):
    cfg = flag_config()
    with pytest.raises(ValueError, match="increasing"):
        run_harness(cfg, [(5, np.zeros(N, int)), (5, np.zeros(N, int))], 10,
                    build_root=tmp_path)
    with pytest.raises(ValueError, match="current format"):
        run_harness(cfg, [(0, np.full(N, cfg.I.max_raw + 1))], 10, build_root=tmp_path)


# ----------------------------------------------------------------------------------------------
# injected faults: the RTL is generated from a faulty stage function (the twin stays right)

def _flip_product_bit(cfg):
    orig = izh.product2_step

    def faulty(cfg_, x):
        out = orig(cfg_, x)
        out["p2"] = out["p2"] ^ (1 << (cfg.shift_p + 1))   # bit 1 of v' in the q w product
        return out
    return "product2_step", faulty


def _truncate_w(cfg):
    def faulty(x, const, shift, rounding="nearest"):
        return round_shift_add(x, const, shift, "truncate")
    return "round_shift_add", faulty


FAULTS = {"flipped-product-bit": _flip_product_bit, "w-rounding-truncates": _truncate_w}


def _faulty_verilog(cfg, fault, monkeypatch):
    name, fn = FAULTS[fault](cfg)
    with monkeypatch.context() as m:
        m.setattr(izh, name, fn)
        return izhikevich_verilog(cfg)


# the long lane (CI): one fault; the other in the release lane
@pytest.mark.long
@pytest.mark.parametrize("fault", [f if f == "flipped-product-bit" else
                                   pytest.param(f, marks=pytest.mark.release) for f in FAULTS])
def test_dump_checker_catches_injected_faults_verilator(
        fault, tmp_path, monkeypatch):
    cfg = flag_config()
    text = _faulty_verilog(cfg, fault, monkeypatch)
    assert text != izhikevich_verilog(cfg)
    rng = np.random.default_rng(9)
    segs = schedule(cfg, rng, [0])
    # the compiled run's dump, checked per sweep
    with monkeypatch.context() as m:
        name, fn = FAULTS[fault](cfg)
        m.setattr(izh, name, fn)
        run = run_harness(cfg, segs, 60, dump=True, build_root=tmp_path / "h")
    checker = check_dump(cfg, run)
    assert checker.stats.twin_mismatches > 0 and checker.failures()
    # the clean core passes the same check
    clean = check_dump(cfg, run_harness(cfg, segs, 60, dump=True, build_root=tmp_path / "h"))
    assert not clean.failures() and clean.current_violations == 0
    assert clean.stats.updates_checked == 60 * N


@pytest.mark.long
def test_verilator_fast_runs_an_array_equal_to_its_twin(tmp_path):
    """An array of three cores of twelve neurons (four parameter sets) compiled with the
    harness: every spike (sweep, global id) and every clamp count equal the array twin's, with
    current segments changing mid-run; every core's updates and the stream's spikes counted."""
    from cuneate.hdl.izhikevich.twin import IzhikevichArrayTwin
    K, n, sweeps = 3, 12, 200
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=16e3 * n, update_hz=16e3,
                           tick_source="external", param_sets=("RS", "IB", "CH", "FS"),
                           neuron_sets=[i % 4 for i in range(n)], spike_fifo_depth=64,
                           current_range=(-20.0, 120.0))
    rng = np.random.default_rng(3)
    # the last segment drives some currents past the accepted range: the current clamp acts
    segs = [(k, cfg.I.to_raw(rng.uniform(lo, hi, K * n)).astype(np.int64))
            for k, lo, hi in ((0, 0, 30), (37, -5, 60), (90, 0, 30), (151, 100, 140))]
    run = run_harness(cfg, segs, sweeps, n_cores=K, build_root=tmp_path)
    tw = IzhikevichArrayTwin(cfg, K)
    ref, seg = [], 0
    for k in range(sweeps):
        while seg < len(segs) and segs[seg][0] <= k:
            for i, r in enumerate(segs[seg][1]):
                tw.set_current_raw(i, int(r))
            seg += 1
        ref += [(k, int(i)) for i in np.flatnonzero(tw.sweep())]
    got = sorted(zip(run.spike_sweeps.tolist(), run.spike_neurons.tolist()))
    assert len(ref) > 100 and got == sorted(ref)
    # every global id spiked on the core that holds it, in every core
    assert {i // n for _, i in got} == set(range(K))
    s = run.summary
    assert s["updates"] == K * n * sweeps and s["sweeps_done"] == sweeps
    assert s["stream_spikes"] == len(ref) and not s["overrun"] and not s["spike_overflow"]
    counts = {k: sum(t.clamp_report()["counts"][k] for t in tw.twins) for k in s["clamp_counts"]}
    assert s["clamp_counts"] == counts and counts["current"] > 0
