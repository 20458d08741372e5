"""Per-cycle scoreboard of the generated Izhikevich core on Icarus and Verilator.

Every update leaving the pipeline is checked against the bit-exact twin (zero mismatches, clamp
flags included) and the float64 golden step from the DUT's own state (within the derived bound
for every unflagged update), while the host rewrites currents during sweeps. Two cases run long
enough to reach the extremes: the full-scale case holds the default formats at +-512 mV/ms
(u reaches its ceiling, then the flip drives v to its deepest transient) with no clamp acting;
the clamp case narrows the formats (saturation="flag") so that every clamp kind acts, and checks
the flags, counters and sticky bits. Every pipeline depth (``pipeline_stages``) runs on its
smallest core with back-to-back sweeps (a neuron's next read as its write-back lands)
and host writes in flight; the deepest also with every clamp acting.
"""

import json

import pytest

from cuneate.hdl.izhikevich import izhikevich_verilog
from cuneate.hdl.izhikevich.config import PIPELINE_STAGES
from cuneate.sim.izhikevich.bench import make_config
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS

CASES = {
    # a few hundred neurons, four presets interleaved, idle cycles between sweeps
    "n240_mixed": {"core": {"n_neurons": 240, "clock_hz": 16e3 * 256, "update_hz": 16e3,
                            "param_sets": ["RS", "IB", "CH", "FS"],
                            "neuron_sets": [i % 4 for i in range(240)],
                            "spike_fifo_depth": 256},
                   "sweeps": 30, "current_range": [-5.0, 120.0], "writes_per_sweep": 12},
    # the default 2500-neuron, 40 MHz / 16 kHz configuration, back-to-back sweeps
    "n2500_default": {"core": {"n_neurons": 2500, "clock_hz": 40e6, "update_hz": 16e3,
                               "spike_fifo_depth": 2048},
                      "sweeps": 6, "current_range": [0.0, 500.0], "writes_per_sweep": 20},
    # full scale: the six presets held at -512 / +511.996 mV/ms, flipped every 1000 sweeps
    "full_scale_long": {"core": {"n_neurons": 12, "clock_hz": 16e3 * 16, "update_hz": 16e3,
                                 "param_sets": ["RS", "IB", "CH", "FS", "LTS", "RZ"],
                                 "neuron_sets": [i // 2 for i in range(12)],
                                 "spike_fifo_depth": 64},
                        "sweeps": 2200, "current_range": [-512.0, 511.99609375],
                        "flip_every": 1000},
    # formats narrower than the proven range: every clamp kind acts, flagged and counted
    "clamps": {"core": {"n_neurons": 16, "clock_hz": 16e3 * 20, "update_hz": 16e3,
                        "param_sets": ["RS", "FS", "IB", "CH"],
                        "neuron_sets": [i % 4 for i in range(16)],
                        "v_int_bits": 8, "u_int_bits": 5, "y_int_bits": 5,
                        "current_range": [-400.0, 400.0], "saturation": "flag",
                        "spike_fifo_depth": 64},
               "sweeps": 400, "current_range": [-512.0, 511.99609375],
               "writes_per_sweep": 0.25},
}
# every pipeline depth on its smallest core with back-to-back sweeps (n_neurons = depth + 1:
# a neuron's memories are read again, a cycle ahead of its fetch, as its registered
# write-back lands, the write bypassed into the read), host writes in flight; the deepest
# depth also with every clamp kind acting
for _depth in PIPELINE_STAGES:
    CASES[f"depth{_depth}_back_to_back"] = {
        "core": {"n_neurons": _depth + 1, "clock_hz": 16e3 * (_depth + 1), "update_hz": 16e3,
                 "param_sets": ["RS", "IB", "CH", "FS", "LTS", "RZ"][:_depth],
                 "neuron_sets": [i % min(_depth, 6) for i in range(_depth + 1)],
                 "spike_fifo_depth": 64,
                 "pipeline_stages": _depth},
        "sweeps": 600, "current_range": [-5.0, 120.0], "writes_per_sweep": 1.5}
CASES[f"depth{max(PIPELINE_STAGES)}_clamps"] = dict(
    CASES["clamps"], core=dict(CASES["clamps"]["core"], pipeline_stages=max(PIPELINE_STAGES)))
# the depths between the reference depth and the deepest run on Icarus in the long lane (on
# Verilator, as their k-induction, in the release lane), as do the deepest pipeline's clamps on
# Verilator (Icarus runs them in the default lane)
_BETWEEN = [d for d in PIPELINE_STAGES if d not in (min(PIPELINE_STAGES), max(PIPELINE_STAGES))]
LONG_CASES = {("icarus", f"depth{d}_back_to_back") for d in _BETWEEN}
LONG_CASES |= {("verilator", f"depth{max(PIPELINE_STAGES)}_clamps")}
# each depth's back-to-back run on one simulator in the default lane (5 on Icarus), the
# others in the long lane; the default core on Verilator in the default lane, on Icarus in the long lane,
# as is the 2200-sweep full-scale run (on Verilator in the release lane)
LONG_CASES |= {("verilator", f"depth{min(PIPELINE_STAGES)}_back_to_back"),
               ("icarus", f"depth{max(PIPELINE_STAGES)}_back_to_back"),
               ("icarus", "n2500_default"), ("icarus", "full_scale_long"),
               ("verilator", "clamps"), ("verilator", "n240_mixed"),
               # depth 9 stays in the default lane through its clamps on Icarus
               ("verilator", f"depth{max(PIPELINE_STAGES)}_back_to_back")}
RELEASE_CASES = {("verilator", f"depth{d}_back_to_back") for d in _BETWEEN}
RELEASE_CASES |= {("verilator", "full_scale_long")}


def _lane(case):
    return (pytest.mark.long if case in LONG_CASES else
            pytest.mark.release if case in RELEASE_CASES else ())


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator,case", [
    pytest.param(s, c, id=f"{s}-{c}", marks=_lane((s, c)))
    for s in SIMULATORS for c in CASES])
def test_scoreboard(simulator, case, build_root):
    spec = dict(CASES[case], seed=11)
    cfg = make_config(spec["core"])
    build_dir = build_root / f"izh_{case}_{simulator}"
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "izhikevich_core.v"
    src.write_text(izhikevich_verilog(cfg))
    run = run_cocotb(simulator, [src], "izhikevich_core", "cuneate.sim.izhikevich.bench",
                     build_dir, config=spec, testcase="scoreboard")
    r = run.report
    print(f"\n{simulator} {case}: " + json.dumps(r))
    assert r["sweeps_checked"] == spec["sweeps"]
    assert r["updates_checked"] == spec["sweeps"] * cfg.n_neurons
    assert r["twin_mismatches"] == 0 and r["flag_mismatches"] == 0
    assert r["golden_bound_violations"] == 0 and r["golden_v_max_ratio"] <= 1.0
    assert r["spike_disagreements"] == 0
    assert r["spikes"] > 0 and r["stream_matches"]
    assert r["clamp_counter_mismatches"] == 0 and r["sticky_mismatches"] == 0
    assert r["clear_mismatches"] == 0
    if case.endswith("clamps"):
        # every clamp kind acted, and was flagged, counted and excused from the golden bound
        assert all(n > 0 for n in r["clamp_counts"].values()), r["clamp_counts"]
        assert r["flagged_updates"] > 0
    else:
        assert r["flagged_updates"] == 0 and not any(r["clamp_counts"].values())
