"""The accuracy-cost sweep of the LIF core and the coincidence detector (word widths)."""

import math
from dataclasses import replace

import numpy as np

from cuneate.golden.izhikevich import group_spikes
from cuneate.hdl.coincidence import CoincidenceConfig, CoincidenceTwin
from cuneate.hdl.lif import LifConfig, LifTwin
from cuneate.sim.izhikevich.sweep import SweepPoint
from cuneate.sim.sweep import SweepSpec, reference_trains, run_sweep
from cuneate.sim.coincidence.sweep import (CoincidenceSweepPoint, afferent_battery,
                                       coincidence_grid, coincidence_point_trains)
from cuneate.sim.lif.sweep import (LifSweepPoint, lif_battery, lif_grid, lif_point_trains,
                                   lif_reference_trains)


def test_weight_width_sweep_against_float64_and_the_twin_driven_directly(tmp_path):
    """Discrete LIF with random weights: a wider weight word keeps more of float64's spikes,
    and the 8-bit default point is exactly the twin of a core configured by hand."""
    spec = SweepSpec(battery="lif-inputs", duration_ms=300.0)
    pts = lif_grid(form="discrete", weight_bits=(4, 8, 12), floats=("float64",))
    rows = {r["weight_bits"] if r["engine"] == "fixed" else r["engine"]: r
            for r in run_sweep(pts, spec, tmp_path, scheduler="sync")}
    assert all(r["status"] == "ok" for r in rows.values()), rows
    w4, w8, w12, f64 = rows[4], rows[8], rows[12], rows["float64"]
    frac = [r["vs_float64_fraction_within_tick"] for r in (w4, w8, w12)]
    errs = [r["vs_float64_count_error"] for r in (w4, w8, w12)]
    assert frac[0] < frac[1] <= frac[2] and frac[2] > 0.99 and frac[0] < 0.95, frac
    assert errs[0] > errs[1] >= errs[2], errs
    assert [r["acc_bits"] for r in (w4, w8, w12)] == [4 + 6, 8 + 6, 12 + 6]   # fan-in 64
    assert w8["multipliers"] == 1 and w8["neurons_per_core"] == 2500
    # the discrete reference is float64 itself, step for step
    assert f64["fraction_within_tick"] == 1.0 and f64["vs_float64_counts_equal"]
    # the default point is the core's default widths, run on a twin built by hand
    p8 = next(p for p in pts if p.weight_bits == 8)
    assert p8 == LifSweepPoint("fixed", form="discrete")
    defaults = LifConfig()
    assert (p8.v_frac_bits, p8.operand_width, p8.weight_bits, p8.decay, p8.rounding) == \
        (defaults.v_frac_bits, defaults.operand_width, defaults.weight_bits, defaults.decay,
         defaults.rounding)
    bat = lif_battery("lif-inputs")
    x = bat.inputs(300)
    assert abs(x.mean() - 0.2) < 0.01
    cfg = LifConfig(n_neurons=32, form="discrete", param_sets=list(bat.param_sets),
                    neuron_sets=list(bat.neuron_sets), weights=bat.weights, weight_bits=8,
                    current_format=(1, 1))
    ks, ns = LifTwin(cfg).run_raw(np.zeros(32, dtype=np.int64), 300, x)
    direct = group_spikes([ks], [ns], 32)
    swept = lif_point_trains(p8, spec)
    assert all(np.array_equal(np.asarray(d) + 1, s) for d, s in zip(direct, swept))
    assert w8["spikes"] == len(ks)


def test_continuous_currents_refusals_and_float64_at_the_same_dt(tmp_path):
    spec = SweepSpec(battery="lif-currents", duration_ms=300.0, reference_hz=64e3)
    ref = reference_trains(spec)
    via_hook = lif_reference_trains(spec)
    assert len(ref) == len(via_hook) == 24
    assert all(np.array_equal(a, b) for a, b in zip(ref, via_hook))
    # the reference against the closed form: from rest, a constant current crosses the
    # threshold after tau ln(I / (I - v_th)), then every t_ref + tau ln((I - v_reset) /
    # (I - v_th)); exact integration reports each crossing at the end of its fine tick
    bat = lif_battery("lif-currents")
    i = bat.labels.index("tau_m 20 I=25")
    dt, I, tau = 1000.0 / 64e3, 25.0, 20.0
    t, want = tau * math.log(I / (I - 18.0)), []
    t_grid = math.ceil(t / dt) * dt
    while t_grid <= 300.0:
        want.append(t_grid)
        t_grid += 2.0 + math.ceil(tau * math.log((I - 11.0) / (I - 18.0)) / dt) * dt
    assert len(want) > 10 and np.allclose(ref[i], want, atol=1e-9)
    pts = [LifSweepPoint("float64"), LifSweepPoint("float32"), LifSweepPoint("fixed"),
           LifSweepPoint("fixed", rounding="truncate"), LifSweepPoint("fixed", v_frac_bits=8),
           LifSweepPoint("fixed", v_frac_bits=6), LifSweepPoint("fixed", operand_width=4),
           LifSweepPoint("fixed", decay="shift")]
    f64, f32, fx, tr, v8, v6, op4, shift = run_sweep(pts, spec, tmp_path, scheduler="sync")
    # float64 at the point's own dt is what vs_float64 measures against: identical
    assert f64["vs_float64_fraction_within_tick"] == 1.0 and f64["vs_float64_counts_equal"]
    assert f64["vs_float64_mean_vp"] == 0.0
    # against the fine-step reference even float64 is mostly more than a tick off (the
    # quantization of every threshold crossing to the 16 kHz grid, accumulated per interval)
    assert f64["fraction_within_tick"] < 0.5 and f64["count_error"] <= 5
    assert f32["vs_float64_counts_equal"]
    assert fx["vs_float64_counts_equal"] and fx["vs_float64_fraction_within_tick"] > 0.99
    assert fx["state_bits"] == 8 + 16 + 6 and fx["clamped_updates"] == 0   # sQ8.16 + ref
    assert tr["vs_float64_fraction_within_tick"] < fx["vs_float64_fraction_within_tick"]
    assert v8["vs_float64_fraction_within_tick"] < tr["vs_float64_fraction_within_tick"]
    assert v6["status"] == "refused" and "more fraction bits than the state" in v6["reason"]
    assert op4["status"] == "refused" and "relative error" in op4["reason"]
    assert shift["status"] == "refused" and "2**-8" in shift["reason"]
    assert "fraction_within_tick" not in v6 and "\n" not in op4["reason"]


def test_decay_by_shift_on_power_of_two_time_constants(tmp_path):
    spec = SweepSpec(battery="lif-pow2", duration_ms=200.0, reference_hz=32e3)
    mul, sh = run_sweep(lif_grid(decay=("multiply", "shift"), floats=()), spec, tmp_path,
                        scheduler="sync")
    assert mul["status"] == sh["status"] == "ok"
    assert (mul["multipliers"], sh["multipliers"]) == (1, 0)
    assert sh["vs_float64_fraction_within_tick"] < mul["vs_float64_fraction_within_tick"]


def test_keys_and_labels_differ_with_every_knob():
    spec = SweepSpec(battery="lif-currents")
    p = LifSweepPoint("fixed")
    changes = dict(engine="float64", update_hz=8e3, form="discrete", v_frac_bits=12,
                   operand_width=16, weight_bits=4, decay="shift", rounding="truncate",
                   max_decay_error=0.5)
    keys = {p.key(spec)} | {replace(p, **{k: v}).key(spec) for k, v in changes.items()}
    assert len(keys) == 1 + len(changes)
    assert LifSweepPoint("fixed").key(spec) == p.key(spec)
    assert p.key(SweepSpec(battery="lif-pow2")) != p.key(spec)
    assert p.key(SweepSpec(battery="lif-currents", duration_ms=300.0)) != p.key(spec)
    assert SweepPoint("fixed").key(spec) != p.key(spec)
    labels = [q.label() for q in lif_grid(v_frac_bits=(12, 16), operand_width=(14, 18),
                                          rounding=("nearest", "truncate"))]
    assert len(set(labels)) == len(labels) == 10


def test_coincidence_detector_weight_widths(tmp_path):
    spec = SweepSpec(battery="cuneate-afferents", duration_ms=300.0, reference_hz=32e3)
    pts = coincidence_grid(weight_bits=(4, 12), operand_width=(18, 14), floats=("float64",))
    rows = {r["label"]: r for r in run_sweep(pts, spec, tmp_path, scheduler="sync")}
    w4 = rows["fixed coincidence 16 kHz w4 tr.16 op18 nearest"]
    w12 = rows["fixed coincidence 16 kHz w12 tr.16 op18 nearest"]
    f64 = rows["float64 coincidence 16 kHz"]
    assert w4["status"] == w12["status"] == "ok" and w12["spikes"] > 10
    assert w4["vs_float64_fraction_within_tick"] < w12["vs_float64_fraction_within_tick"]
    assert w12["vs_float64_counts_equal"] and w12["weight_format"] == "uQ3.9"
    assert f64["vs_float64_fraction_within_tick"] == 1.0
    op14 = rows["fixed coincidence 16 kHz w12 tr.16 op14 nearest"]
    assert op14["status"] == "refused" and "Izhikevich arithmetic refused" in op14["reason"]
    # the 12-bit point is the twin of a detector configured by hand from the battery
    bat = afferent_battery("cuneate-afferents", 300.0)
    cfg = CoincidenceConfig.from_ms(bat.delays_ms, update_hz=16e3, weights=bat.weights,
                                    max_delay_ticks=200, clock_hz=16e3 * 200,
                                    weight_bits=12)
    direct = CoincidenceTwin(cfg).run([np.rint(np.asarray(s) * 16).astype(int)
                                       for s in bat.spike_times_ms], 4800)
    swept = coincidence_point_trains(CoincidenceSweepPoint("fixed"), spec)
    assert all(np.array_equal(d, s) for d, s in zip(direct, swept))
    assert sum(map(len, direct)) == w12["spikes"]
    assert sum(map(len, reference_trains(spec))) == w12["reference_spikes"]


def test_block_batteries_through_the_cli(tmp_path, capsys):
    """`cuneate sweep --battery lif-inputs --weight-bits ...` and the coincidence battery run
    end to end; the CSV carries the block's own columns; bad knobs are one-line errors."""
    import csv

    from cuneate.sim.cli import main
    out = tmp_path / "lif"
    assert main(["sweep", "--out", str(out), "--battery", "lif-inputs", "--weight-bits", "4,8",
                 "--no-float", "--scheduler", "sync", "--duration-ms", "200"]) == 0
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["weight_bits"] for r in rows] == ["4", "8"]
    assert float(rows[0]["vs_float64_fraction_within_tick"]) < \
        float(rows[1]["vs_float64_fraction_within_tick"])
    assert "of float64 at the same dt" in capsys.readouterr().out
    out = tmp_path / "cun"
    assert main(["sweep", "--out", str(out), "--battery", "cuneate-afferents", "--no-float",
                 "--scheduler", "sync", "--duration-ms", "200"]) == 0
    with open(out / "sweep.csv") as f:
        assert list(csv.DictReader(f))[0]["trace_frac_bits"] == "16"
    capsys.readouterr()
    for argv, expect in ((["--battery", "lif-currents", "--decay", "bogus"], "unknown decay"),
                         (["--battery", "cuneate-afferents", "--update-hz", "10000"],
                          "multiple of 4000 Hz")):
        assert main(["sweep", "--out", str(tmp_path / "x"), *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert expect in err and "\n" not in err
