"""Per-cycle scoreboard of the generated IzhikevichArray on Icarus and Verilator: every update
of every core (the array generated with its per-core probe ports) equals that core's twin and
stays within the golden bound, with host writes by global id during the sweeps; the one spike
stream carries every spike once as a global id with its sweep, each core's in its order; the
summed ``sweep_count`` agrees. Small arrays at the default and the deepest pipeline in the
default lane, a larger array in the long lane."""

import json

import pytest

from cuneate.hdl.izhikevich import izhikevich_array_verilog
from cuneate.hdl.izhikevich.config import PIPELINE_STAGES
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.izhikevich.bench import make_config


def _case(cores, n, depth, sweeps, current_range=(-5.0, 150.0), **extra):
    sets = ["RS", "IB", "CH", "FS"]
    return {"cores": cores, "sweeps": sweeps, "current_range": list(current_range),
            "writes_per_sweep": 3,
            "core": {"n_neurons": n, "clock_hz": 16e3 * (n + 4), "update_hz": 16e3,
                     "param_sets": sets, "neuron_sets": [i % 4 for i in range(n)],
                     "spike_fifo_depth": 64, "pipeline_stages": depth, **extra}}


CASES = {f"k3_n12_depth{d}": _case(3, 12, d, 60) for d in (5, max(PIPELINE_STAGES))}
# parameter sets per core: core 0 all RS, core 1 all FS, core 2 the four sets in turn
CASES["k3_n12_per_core_sets"] = dict(_case(3, 12, 5, 60),
                                     neuron_sets=[0] * 12 + [3] * 12 + [i % 4 for i in range(12)])
# eight cores whose global ids are wider than one core's (long lane); 4000 neurons, the first
# writes taking 8 sweeps (release lane); strong currents so that every core spikes
LONG = {"k8_n40": _case(8, 40, 5, 16, current_range=(60.0, 200.0), spike_fifo_depth=128),
        "k8_n500": _case(8, 500, 5, 32, current_range=(60.0, 200.0), spike_fifo_depth=512)}


def _run(simulator, case, spec, build_root):
    cfg = make_config(spec["core"])
    build_dir = build_root / f"izh_array_{case}_{simulator}"
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "izhikevich_array.v"
    src.write_text(izhikevich_array_verilog(cfg, spec["cores"], probes=True,
                                            neuron_sets=spec.get("neuron_sets")))
    run = run_cocotb(simulator, [src], "izhikevich_array", "cuneate.sim.izhikevich.bench",
                     build_dir, config=dict(spec, seed=5), testcase="array_check")
    r = run.report
    print(f"\n{simulator} {case}: " + json.dumps(r))
    K = spec["cores"]
    assert r["sweeps_checked"] == K * spec["sweeps"]
    assert r["updates_checked"] == K * spec["sweeps"] * cfg.n_neurons
    assert r["twin_mismatches"] == 0 and r["flag_mismatches"] == 0
    assert r["golden_bound_violations"] == 0 and r["golden_v_max_ratio"] <= 1.0
    assert r["spikes"] > 0 and r["stream_matches"] and r["stream_core_order"]
    assert r["count_mismatches"] == 0 and r["current_violations"] == 0
    assert r["overrun"] == 0 and r["spike_overflow"] == 0


def _lane(simulator, case):
    """The default lane runs both depths on Icarus; Verilator (which compiles each design, the
    slower first run) runs them in the long lane, as do the per-core sets on both."""
    marks = pytest.mark.long if simulator == "verilator" or case == "k3_n12_per_core_sets" else ()
    return pytest.param(simulator, case, marks=marks, id=f"{simulator}-{case}")


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator,case", [_lane(s, c) for s in SIMULATORS for c in CASES])
def test_array_check(simulator, case, build_root):
    _run(simulator, case, CASES[case], build_root)


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator,case", [
    # Verilator compiles eight cores with their probes for a minute or more: the long lane
    # runs the eight-core array on Icarus, Verilator runs the three-core arrays
    pytest.param("icarus", "k8_n40", marks=pytest.mark.long, id="icarus-k8_n40"),
    *[pytest.param(s, c, marks=pytest.mark.release, id=f"{s}-{c}")
      for s, c in (("verilator", "k8_n40"), ("icarus", "k8_n500"), ("verilator", "k8_n500"))]])
def test_array_check_long(simulator, case, build_root):
    _run(simulator, case, LONG[case], build_root)
