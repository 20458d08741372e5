"""The accuracy-versus-cost sweep: Dask, per-point cache and resume, outputs, refusals."""

import csv
import json
import re

import numpy as np
import pytest

from cuneate.sim.cli import main
from cuneate.sim.izhikevich.sweep import SweepPoint, battery, grid
from cuneate.sim.sweep import SweepSpec, evaluate, pareto_front, reference_trains, run_sweep


# the long lane (CI): a local Dask cluster starts its workers
@pytest.mark.long
def test_small_sweep_on_a_local_dask_cluster(tmp_path, capsys):
    out = tmp_path / "s"
    assert main(["sweep", "--out", str(out), "--update-hz", "16000", "--operand-width", "18,14",
                 "--rounding", "nearest,truncate", "--duration-ms", "300",
                 "--workers", "1"]) == 0
    text = capsys.readouterr().out
    rows = {r["label"]: r for r in json.loads((out / "sweep.json").read_text())["rows"]}
    assert len(rows) == 6 and "report:" in text
    fx = rows["fixed 16 kHz w18 v.18 u.20 nearest"]
    tr = rows["fixed 16 kHz w18 v.18 u.20 truncate"]
    f64, f32 = rows["float64 euler 16 kHz"], rows["float32 euler 16 kHz"]
    assert fx["status"] == "ok" and fx["neurons_per_core"] == 2500 and fx["multipliers"] == 4
    # the arithmetic against float64 Euler at the same dt: the core close to float32, and
    # truncation clearly worse than rounding to nearest
    assert fx["vs_euler_fraction_within_tick"] > 0.95 and f32["vs_euler_counts_equal"]
    assert tr["vs_euler_fraction_within_tick"] < fx["vs_euler_fraction_within_tick"]
    # against the fine-step reference the scheme's own error dominates: float64 Euler at
    # 16 kHz is no closer to RK4 than the core
    assert abs(f64["fraction_within_tick"] - fx["fraction_within_tick"]) < 0.05
    # a configuration the core refuses is a row with its reason, not a crash
    w14 = rows["fixed 16 kHz w14 v.18 u.20 nearest"]
    assert w14["status"] == "refused" and "fraction bits" in w14["reason"]
    with open(out / "sweep.csv") as f:
        assert len(list(csv.DictReader(f))) == 6
    assert (out / "pareto.png").stat().st_size > 5000
    assert "Pareto" in (out / "index.html").read_text()
    # the headline is the error against the reference and the deterministic costs; host
    # seconds of points run one at a time (one worker) are not marked as parallel
    line = next(x for x in text.splitlines() if x.strip().startswith("fixed 16 kHz w18 v.18 "
                                                                       "u.20 nearest"))
    assert re.search(r"count error \d+, VP \d+\.\d{3}, same-dt 0\.\d{4}; 2500 neurons/core, "
                     r"4 mult, \d+ state bits; host [\d.]+ s/bio s$", line.strip()), line
    assert fx["updates_per_bio_s"] == 16000.0 and fx["host_time"] == "one point at a time"
    pareto = json.loads((out / "sweep.json").read_text())["pareto"]
    assert set(pareto) == {"updates_per_bio_s", "state_bits", "multipliers"}


# the long lane (CI): a sweep run twice
@pytest.mark.long
def test_interrupted_sweep_resumes_from_its_cache(tmp_path):
    spec = SweepSpec(duration_ms=100.0)
    pts = grid(update_hz=(16e3,), operand_width=(18,), floats=("float32",))
    logs = []
    first = run_sweep(pts, spec, tmp_path, scheduler="sync", log=logs.append)
    assert logs[-1] == "sweep: 2 points, 0 cached, 2 to run"
    # one result lost (an interrupted run): only that point runs again
    (tmp_path / f"{pts[1].key(spec)}.json").unlink()
    again = run_sweep(pts, spec, tmp_path, scheduler="sync", log=logs.append)
    assert logs[-1] == "sweep: 2 points, 1 cached, 1 to run"
    assert [r["fraction_within_tick"] for r in again] == \
        [r["fraction_within_tick"] for r in first]
    # another battery or duration is another key
    assert pts[0].key(SweepSpec(duration_ms=200.0)) != pts[0].key(spec)


# the long lane (CI): a battery of 20 behaviours
@pytest.mark.long
def test_the_published_behaviours_are_a_battery_of_the_sweep():
    """The 19 expressible panels (own parameters, initial state and stimulus) run on every
    engine of a sweep; the core holds every published stimulus without a clamp, float32 keeps
    every spike count of float64 Euler, and the fixed-point core keeps every count but the
    depolarizing after-potential's (Q), whose last spike sits on a threshold the update's
    rounding decides; truncation is further from Euler than rounding to nearest."""
    bat = battery("behaviours")
    assert bat.n == 19 and not any(lab.startswith("T ") for lab in bat.labels)
    spec = SweepSpec(battery="behaviours", duration_ms=300.0)
    ref = reference_trains(spec)
    assert len(ref) == 19 and sum(map(len, ref)) > 100
    rows = {p.label(): evaluate(p, spec, ref)
            for p in grid(rounding=("nearest", "truncate"), floats=("float32",))}
    near, trunc = rows["fixed 16 kHz w18 v.18 u.20 nearest"], \
        rows["fixed 16 kHz w18 v.18 u.20 truncate"]
    f32 = rows["float32 euler 16 kHz"]
    assert all(r["status"] == "ok" and r["trains"] == 19 for r in rows.values()), rows
    assert near["clamped_updates"] == 0 and trunc["clamped_updates"] == 0
    assert f32["vs_euler_counts_equal"]
    assert trunc["vs_euler_fraction_within_tick"] < near["vs_euler_fraction_within_tick"]
    # per train: the core against float64 Euler at its dt
    from cuneate.golden import izhikevich as giz
    from cuneate.hdl.izhikevich import IzhikevichTwin
    from cuneate.sim.izhikevich.sweep import fixed_config as _fixed_config, run_fixed as _run_fixed
    dt, n = 1.0 / 16.0, 4800
    euler = giz.simulate(list(bat.params), bat.currents(dt, n), n_steps=n, dt_ms=dt,
                         v0=np.asarray(bat.v0), u0=np.asarray(bat.u0)).spike_counts
    twin = IzhikevichTwin(_fixed_config(SweepPoint("fixed"), bat))
    fixed = [len(s) for s in _run_fixed(twin, bat, dt, n)]
    differ = [lab for lab, a, b in zip(bat.labels, euler, fixed) if a != b]
    assert differ == ["Q depolarizing after-potential"], differ
    q = bat.labels.index("Q depolarizing after-potential")
    assert abs(int(euler[q]) - fixed[q]) == 1


# the long lane (CI): 20 behaviours on three engines
@pytest.mark.long
def test_the_price_of_float32_parity_on_the_behaviours():
    """Over 1 s of the published behaviours the default core (sQ10.8 currents, 18-bit operands)
    changes two counts against float64 Euler: bistability (P), whose 0.24 mV/ms holding current
    is 0.238 in sQ10.8, and the DAP (Q). Four more current fraction bits fix P, wider operands Q:
    sQ10.12 with 24-bit operands keeps every count and is at least float32's equal."""
    from cuneate.golden.metrics import compare_populations
    from cuneate.hdl.izhikevich import IzhikevichTwin
    from cuneate.sim.izhikevich.sweep import fixed_config as _fixed_config
    from cuneate.sim.izhikevich.sweep import run_fixed as _run_fixed
    from cuneate.sim.izhikevich.sweep import simulate_float
    bat = battery("behaviours")
    dt, n = 1.0 / 16.0, 16000
    euler = simulate_float(bat, dt, n, "euler")
    f32 = compare_populations(euler, simulate_float(bat, dt, n, "euler", np.float32), dt, 0.005)
    assert f32["counts_equal"]

    def core(**kw):
        twin = IzhikevichTwin(_fixed_config(SweepPoint("fixed", **kw), bat))
        c = compare_populations(euler, _run_fixed(twin, bat, dt, n), dt, 0.005)
        assert sum(twin.clamp_counts.values()) == 0
        return c, [lab[0] for lab, x in zip(bat.labels, c["per_train"])
                   if x["count_difference"]]
    default, differ = core()
    assert differ == ["P", "Q"] and default["fraction_within_tick"] < \
        f32["fraction_within_tick"] - 0.05
    _, differ = core(current_frac_bits=12)
    assert differ == ["Q"]                 # the current LSB decided bistability
    _, differ = core(operand_width=24)
    assert differ == ["P"]                 # the operands decided the DAP
    parity, differ = core(operand_width=24, current_frac_bits=12)
    assert differ == [] and parity["fraction_within_tick"] >= f32["fraction_within_tick"]


def test_a_scene_is_a_battery_of_the_sweep(tmp_path):
    """A scene's driven neurons with its front end's currents: the sweep's float64 Euler and
    default fixed-point trains are the ones `cuneate run` produces on its golden and fixed
    engines (same currents, same core), and a sweep point runs on the scene."""
    from cuneate.hdl.izhikevich import IzhikevichTwin
    from cuneate.sim.scenes import run_scene
    from cuneate.sim.scenes import example_path, load_scene
    from cuneate.sim.izhikevich.sweep import fixed_config as _fixed_config
    from cuneate.sim.izhikevich.sweep import run_fixed as _run_fixed
    from cuneate.sim.izhikevich.sweep import simulate_float
    run = run_scene(load_scene(example_path("pulse_amplitudes")), engines=["golden", "fixed"])
    bat = battery("scene:pulse_amplitudes")
    assert bat.n == len(run.neurons) and bat.duration_ms == 400.0
    assert np.array_equal(bat.samples, run.currents)
    n = int(round(bat.duration_ms / run.dt_ms))
    assert n == run.n_ticks
    for engine, trains in (
            ("golden", simulate_float(bat, run.dt_ms, n, "euler")),
            ("fixed", _run_fixed(IzhikevichTwin(_fixed_config(SweepPoint("fixed"), bat)),
                                 bat, run.dt_ms, n))):
        assert sum(map(len, trains)) > 500
        assert all(np.array_equal(a, b) for a, b in zip(trains, run.spikes[engine])), engine
    spec = SweepSpec(battery="scene:pulse_amplitudes", duration_ms=400.0)
    rows = run_sweep([SweepPoint("fixed"), SweepPoint("fixed", rounding="truncate"),
                      SweepPoint("float64")], spec, tmp_path, scheduler="sync")
    fx, tr, f64 = rows
    assert fx["status"] == "ok" and fx["trains"] == bat.n and fx["clamped_updates"] == 0
    assert f64["spikes"] == sum(map(len, run.spikes["golden"]))
    assert fx["vs_euler_fraction_within_tick"] > 0.99
    assert tr["vs_euler_fraction_within_tick"] <= fx["vs_euler_fraction_within_tick"]


def test_pareto_front_by_hand():
    rows = [{"key": k, "status": "ok", "fraction_within_tick": a, "cost": c}
            for k, a, c in (("a", 0.9, 1.0), ("b", 0.95, 2.0), ("c", 0.9, 3.0),
                            ("d", 0.99, 10.0), ("e", 0.5, 0.5))]
    rows.append({"key": "f", "status": "refused"})
    assert sorted(pareto_front(rows, "cost", "fraction_within_tick",
                               lower_is_better=False)) == ["a", "b", "d", "e"]
    # the default accuracy is an error (mean VP to the reference): lower is better
    err = [{"key": k, "status": "ok", "mean_vp": v, "cost": c}
           for k, v, c in (("a", 0.1, 1.0), ("b", 0.05, 2.0), ("c", 0.1, 3.0),
                           ("d", 0.01, 10.0), ("e", 0.5, 0.5))]
    assert sorted(pareto_front(err, "cost")) == ["a", "b", "d", "e"]


@pytest.mark.parametrize("argv,expect", [
    (["--update-hz", "x"], "--update-hz: expected a comma-separated list"),
    (["--update-hz", "-5"], "--update-hz: rates must be > 0"),
    (["--operand-width", "40"], "--operand-width: widths must lie in 8..32"),
    (["--rounding", "up"], "--rounding: nearest and/or truncate"),
    (["--current-frac-bits", "40"], "--current-frac-bits: fraction bits must lie in 0..24"),
    (["--schemes", "heun"], "--schemes: euler, izhikevich and/or rk4"),
    (["--battery", "nope"], "--battery: unknown battery 'nope'"),
    (["--battery", "scene:skin_3x3"], "does not drive independent Izhikevich neurons"),
    (["--battery", "scene:nope"], "scene 'nope' is neither an example"),
])
def test_refusals(argv, expect, tmp_path, capsys):
    assert main(["sweep", "--out", str(tmp_path), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert expect in err and "\n" not in err


@pytest.mark.long
def test_sweep_with_synthesis_and_place_and_route(tmp_path):
    """The sweep's synthesis path (yosys synth_ecp5, nextpnr-ecp5 fmax) on one fixed core,
    16 kHz at 18-bit operands, sized for 40 MHz; its neighbours in update rate in the release
    lane."""
    spec = SweepSpec(duration_ms=100.0, synth=True, fmax=True)
    pts = grid(update_hz=(16e3,), operand_width=(18,), schemes=("euler",))
    rows = {r["label"]: r for r in run_sweep(pts, spec, tmp_path, workers=2)}
    a = rows["fixed 16 kHz w18 v.18 u.20 nearest"]
    assert a["neurons_per_core"] == 2500 and a["MULT18X18D"] >= 4 and a["DP16KD"] > 0
    assert all(r["status"] == "ok" for r in rows.values())
    assert a["fmax_mhz"] >= 40.0


@pytest.mark.release
def test_sweep_with_synthesis_and_update_rates(tmp_path):
    """Update rates (powers of two and not) at 18-bit operands, with yosys synth_ecp5 and
    nextpnr-ecp5 (fmax) of each fixed core sized for 40 MHz."""
    spec = SweepSpec(duration_ms=1000.0, synth=True, fmax=True)
    pts = grid(update_hz=(8e3, 16e3, 20e3), operand_width=(18,), schemes=("euler", "rk4"))
    rows = {r["label"]: r for r in run_sweep(pts, spec, tmp_path, workers=2)}
    a, b = rows["fixed 16 kHz w18 v.18 u.20 nearest"], rows["fixed 8 kHz w18 v.18 u.20 nearest"]
    assert a["neurons_per_core"] == 2500 and b["neurons_per_core"] == 5000
    assert a["MULT18X18D"] >= 4 and b["DP16KD"] > a["DP16KD"]
    assert rows["fixed 20 kHz w18 v.18 u.20 nearest"]["multipliers"] == 5
    assert all(r["status"] == "ok" for r in rows.values())
    # every fixed core placed and routed on the LFE5U-85F meets its 40 MHz clock
    fixed = [r for r in rows.values() if r["engine"] == "fixed"]
    assert len(fixed) == 3 and all(r["fmax_mhz"] >= 40.0 for r in fixed)


def test_hardcases_summary_prints_the_records(tmp_path, capsys):
    from cuneate.sim.hardcases import record
    record("a_case", 3, 3000, 0, "three", path=tmp_path)
    record("b_case", 1, 10, 0, path=tmp_path)
    assert main(["hardcases", "summary", "--dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].split()[:4] == ["a_case", "3", "3000", "0"]
    assert out[-1].split() == ["total", "4", "3010", "0"]
    record("c_case", 1, 10, 2, path=tmp_path)            # a mismatch makes it fail
    assert main(["hardcases", "summary", "--dir", str(tmp_path)]) == 1
    assert main(["hardcases", "summary", "--dir", str(tmp_path / "none")]) == 2


# the long lane (CI): a sweep repeated
@pytest.mark.long
def test_repeats_keep_the_fastest_host_time_and_the_same_accuracy(tmp_path):
    spec = SweepSpec(duration_ms=100.0)
    pts = grid(update_hz=(16e3,), operand_width=(18,), floats=())
    once = run_sweep(pts, spec, tmp_path / "a", scheduler="sync")[0]
    rep = run_sweep(pts, spec, tmp_path / "b", scheduler="sync", repeats=3)[0]
    runs = rep["host_s_per_bio_s_runs"]
    assert len(runs) == 3 and rep["host_s_per_bio_s"] == min(runs)
    assert rep["host_time"] == "one point at a time, fastest of 3 runs"
    for k in ("count_error", "mean_vp", "fraction_within_tick", "vs_euler_fraction_within_tick"):
        assert rep[k] == once[k]
