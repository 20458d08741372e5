"""Per-cycle scoreboard of the generated LIF core on Icarus and Verilator.

Every update leaving the pipeline is checked against the bit-exact twin (zero mismatches: v,
refractory counter, spike, accumulated input, clamp flags) and against the float64 golden update
from the DUT's own state (within the derived bound for every unflagged update), while the host
rewrites currents during sweeps and input spikes arrive between ticks. Three cases: continuous
with two parameter sets and a multiplier, continuous shift-and-subtract, discrete with 4-bit
weights; AMPA/GABA synaptic traces (each trace update also within its golden bound); a
current-based synapse with per-source input delays (NIR's CubaLIF and Delay); and one
that narrows formats so that every clamp kind acts and is flagged and counted.
"""

import json

import numpy as np
import pytest

from cuneate.hdl.lif import CLAMP_KINDS, LifConfig, lif_verilog
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS

_W = np.random.default_rng(4).integers(-8, 8, (16, 8)) / 8.0

CASES = {
    "continuous_multiply": {
        "core": {"n_neurons": 16, "tick_source": "external",
                 "param_sets": [{"tau_m_ms": 2.0, "t_ref_ms": 0.25},
                                {"tau_m_ms": 1.0, "v_rest": -2.0, "t_ref_ms": 0.0}],
                 "neuron_sets": [i % 2 for i in range(16)],
                 "weights": (np.abs(_W) * 8).tolist(), "weight_bits": 8},
        "sweeps": 100, "current_range": [-20.0, 127.0]},
    "continuous_shift": {
        "core": {"n_neurons": 12, "tick_source": "external", "decay": "shift",
                 "param_sets": [{"tau_m_ms": 1.0}, {"tau_m_ms": 0.5,
                                                              "t_ref_ms": 0.125}],
                 "neuron_sets": [i % 2 for i in range(12)], "max_decay_error": 0.07},
        "sweeps": 100, "current_range": [0.0, 127.0]},
    "discrete_int4": {
        "core": {"n_neurons": 16, "tick_source": "external", "form": "discrete",
                 "weights": _W.tolist(), "weight_bits": 4, "current_format": [4, 12],
                 "param_sets": [{"alpha": 0.389, "u_th": 0.65},
                                {"alpha": 0.9, "u_th": 1.0, "refractory_steps": 2}],
                 "neuron_sets": [i % 2 for i in range(16)]},
        "sweeps": 100, "current_range": [-0.25, 0.25], "input_spike_p": 0.5},
    "discrete_weight_writes": {
        "core": {"n_neurons": 10, "tick_source": "external", "form": "discrete",
                 "weights": _W[:10, :5].tolist(), "weight_bits": 4, "weights_writable": True,
                 "current_format": [4, 12],
                 "param_sets": [{"alpha": 0.5, "u_th": 0.65, "refractory_steps": 1}]},
        "sweeps": 100, "current_range": [-0.25, 0.25], "input_spike_p": 0.5},
    "synapses": {
        "core": {"n_neurons": 12, "tick_source": "external", "synapses": True,
                 "weights": (np.abs(_W[:12, :4]) * 16).tolist(),
                 "input_types": ["exc", "inh", "exc", "exc"], "update_hz": 4000.0,
                 "param_sets": [{"tau_m_ms": 4.0, "t_ref_ms": 1.0}]},
        "sweeps": 100, "current_range": [0.0, 20.0], "input_spike_p": 0.4},
    # NIR's CubaLIF: a signed current-based synapse, and per-source input delays
    "discrete_cuba_delays": {
        "core": {"n_neurons": 12, "tick_source": "external", "form": "discrete",
                 "weights": _W[:12, :6].tolist(), "weight_bits": 6, "current_format": [4, 12],
                 "syn_alpha": 0.75, "input_delays": [0, 1, 3, 0, 2, 5],
                 "param_sets": [{"alpha": 0.9, "u_th": 0.8},
                                {"alpha": 0.6, "u_th": 0.5, "refractory_steps": 1}],
                 "neuron_sets": [i % 2 for i in range(12)]},
        "sweeps": 100, "current_range": [-0.1, 0.2], "input_spike_p": 0.4},
    # the default size: 2500 neurons at 40 MHz / 16 kHz, brief's excitatory cell
    "n2500_default": {
        "core": {"n_neurons": 2500, "clock_hz": 40e6, "tick_source": "external",
                 "spike_fifo_depth": 2048,
                 "v_init": np.random.default_rng(0).uniform(0.0, 18.0, 2500).tolist()},
        "sweeps": 3, "current_range": [-128.0, 127.0], "writes_per_sweep": 20,
        "period": 2504},
    "clamps": {
        "core": {"n_neurons": 12, "tick_source": "external",
                 "weights": [[0.0, 0.0]] * 6 + [[100.0, 100.0]] * 6,
                 "input_limit": [-50.0, 150.0], "saturation": "flag",
                 "current_range": [-60.0, 100.0], "v_int_bits": 6,
                 "param_sets": [{"tau_m_ms": 0.5, "v_reset": -20.0}]},
        "sweeps": 100, "current_range": [-128.0, 127.0], "writes_per_sweep": 4},
}


#: cases Verilator runs in the long lane (Icarus runs them in the default lane): each Verilator
#: case compiles its own model
VERILATOR_LONG = {"continuous_shift", "discrete_int4", "discrete_cuba_delays"}


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator,case", [
    pytest.param(s, c, id=f"{s}-{c}",
                 marks=pytest.mark.long if s == "verilator" and c in VERILATOR_LONG else ())
    for s in SIMULATORS for c in CASES])
def test_scoreboard(simulator, case, build_root):
    spec = dict(CASES[case], seed=5)
    cfg = LifConfig.from_kwargs(spec["core"])
    build_dir = build_root / f"lif_{case}_{simulator}"
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "lif_core.v"
    src.write_text(lif_verilog(cfg))
    run = run_cocotb(simulator, [src], "lif_core", "cuneate.sim.lif.bench", build_dir,
                     config=spec | {"core": cfg.to_kwargs()}, testcase="scoreboard")
    r = run.report
    print(f"\n{simulator} {case}: " + json.dumps(r))
    assert r["sweeps_checked"] == spec["sweeps"]
    assert r["updates_checked"] == spec["sweeps"] * cfg.n_neurons
    assert r["twin_mismatches"] == 0
    assert r["golden_bound_violations"] == 0 and r["golden_max_ratio"] <= 1.0
    assert r["spike_disagreements"] == 0
    assert r["spikes"] > 0 and r["stream_matches"]
    assert r["count_mismatches"] == 0 and r["clamp_counter_mismatches"] == 0
    assert r["sticky_mismatches"] == 0 and r["current_violations"] == 0
    if cfg.n_inputs:
        assert r["input_spikes"] > 0 and r["merged_flag"] == r["merged_expected"]
    if case == "discrete_weight_writes":
        assert r["weight_writes"] > 20
    if case in ("synapses", "discrete_cuba_delays"):
        assert r["trace_bound_violations"] == 0 and 0 < r["trace_golden_max_ratio"] <= 1.0
    if case == "clamps":
        assert all(r["clamp_counts"][k] > 0 for k in CLAMP_KINDS), r["clamp_counts"]
    else:
        assert r["flagged_updates"] == 0 and not any(r["clamp_counts"].values())


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator,sweeps", [
    pytest.param("verilator", 2500, marks=pytest.mark.release, id="verilator-2500"),
    *[pytest.param(s, 10000, marks=pytest.mark.release, id=f"{s}-10000") for s in SIMULATORS]])
def test_scoreboard_long(simulator, sweeps, build_root):
    """Thousands of sweeps of two parameter sets with input spikes and AMPA/GABA traces: steady
    states (2500 sweeps are 156 ms, eight of the slower tau_m), long refractory sequences and
    trace build-up stay bit-exact and within bounds. The RTL equals the one-step datapath for
    every input sequence by k-induction (tests/hdl/test_lif_proof.py); the 10000-sweep runs on
    both simulators re-measure that in the release lane."""
    core = {"n_neurons": 12, "tick_source": "external", "synapses": True,
            "weights": (np.abs(_W[:12, :4]) * 16).tolist(),
            "input_types": ["exc", "inh", "exc", "exc"],
            "param_sets": [{"tau_m_ms": 20.0, "t_ref_ms": 2.0},
                           {"tau_m_ms": 10.0, "t_ref_ms": 1.0}],
            "neuron_sets": [i % 2 for i in range(12)]}
    spec = {"core": core, "sweeps": sweeps, "current_range": [0.0, 30.0],
            "input_spike_p": 0.05, "seed": 9}
    cfg = LifConfig.from_kwargs(core)
    build_dir = build_root / f"lif_long_{simulator}_{sweeps}"
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "lif_core.v"
    src.write_text(lif_verilog(cfg))
    r = run_cocotb(simulator, [src], "lif_core", "cuneate.sim.lif.bench", build_dir,
                   config=spec | {"core": cfg.to_kwargs()}, testcase="scoreboard").report
    print(f"\n{simulator} long: " + json.dumps(r))
    assert r["sweeps_checked"] == sweeps and r["twin_mismatches"] == 0
    assert r["golden_bound_violations"] == 0 and r["trace_bound_violations"] == 0
    assert r["spike_disagreements"] == 0 and r["stream_matches"] and r["spikes"] > 100
