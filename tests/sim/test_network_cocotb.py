"""The afferent -> cuneate network's generated Verilog on Icarus and Verilator: every afferent
sweep and every detector tick checked against the twins (exact) and golden (bounded), with
ticks taken at the earliest sweep boundary, random host writes and output back-pressure;
every spike crosses the link and leaves on the stream exactly once."""

import json

import pytest

from cuneate.hdl.network import NetworkConfig, network_verilog
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS

DET = dict(n_sources=5, n_targets=3, delays_ticks=[[0, 0, 0, 3, 3], [0] * 5, [3, 3, 0, 0, 0]],
           max_delay_ticks=8, weights=[[5.0] * 5] * 3)


@pytest.mark.cocotb
# Verilator in the default lane, Icarus (slower on this netlist) in the long lane
@pytest.mark.parametrize("simulator", [pytest.param(s, marks=pytest.mark.long)
                                       if s == "icarus" else s for s in SIMULATORS])
def test_network_scoreboard(simulator, build_root):
    # 48 afferents, the last five are the detector's sources: the core's sweep outlasts the
    # detector's tick, so the sweep boundary decides when the last neurons' spikes are stamped
    cfg = NetworkConfig(n_afferents=48, detector=DET, first_source=43, clock_hz=16e3 * 64,
                        tick_source="external")
    assert cfg.n_afferents + 8 > cfg.det.cycles_needed
    bd = build_root / f"network_{simulator}"
    bd.mkdir(parents=True, exist_ok=True)
    src = bd / "afferent_cuneate_network.v"
    src.write_text(network_verilog(cfg, lowered=simulator == "icarus"))
    spec = {"network": cfg.to_kwargs(), "ticks": 500, "seed": 7, "current_range": [5.0, 60.0]}
    r = run_cocotb(simulator, [src], "afferent_cuneate_network",
                   "cuneate.sim.network.bench", bd, config=spec,
                   testcase="scoreboard").report
    core, det = r.pop("core"), r.pop("detector")
    print(f"\n{simulator}: " + json.dumps(r))
    assert r["sweeps_checked"] == 500 and det["ticks_checked"] == 500
    assert core["twin_mismatches"] == 0 == core["flag_mismatches"]
    assert core["golden_bound_violations"] == 0
    assert det["input_mismatches"] == det["trace_mismatches"] == det["current_mismatches"] == 0
    assert det["trace_golden_violations"] == 0
    assert r["link_events"] == r["link_expected"] > 30
    assert r["stream_out"] == r["stream_expected"] and r["cuneate_spikes"] > 0
    assert r["overrun_count"] > 0          # ticks were held high: taken at the boundary
