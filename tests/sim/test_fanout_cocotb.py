"""The channel fan-out's generated Verilog on Icarus and Verilator: every current of every run
checked against the twin (exact) and golden (bounded), the handshake, the run timing, the
overrun and clamp counters; and the engines equal to the twin."""

import json

import numpy as np
import pytest

from cuneate.hdl.fanout import FanoutConfig, fanout_verilog
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.fanout.engines import run_fanout

#: 6 channels fanned out to 40 afferents of mixed kinds: SA (gated, positive), FA (abs), signed
#: gains, and gains large enough that the extreme samples clamp both ways
N = 40
_rng = np.random.default_rng(5)
TABLE = dict(n_channels=6, channel=[int(c) for c in _rng.integers(0, 6, N)],
             gain=[float(g) for g in np.round(_rng.uniform(-40, 160, N), 3)],
             rectify=[["none", "positive", "abs"][i % 3] for i in range(N)],
             threshold=[float(t) if i % 4 == 1 else None
                        for i, t in enumerate(np.round(_rng.uniform(-5, 20, N), 2))],
             sample_width=14, sample_max=64.0)


def _scoreboard(cfg, simulator, build_dir, runs, **config) -> dict:
    """The bench's scoreboard on ``cfg``'s Verilog; its report, after the checks every table
    shares (every current checked, twin exact, golden bounded, no unneeded clamp)."""
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "channel_fanout.v"
    src.write_text(fanout_verilog(cfg, lowered=simulator == "icarus"))
    r = run_cocotb(simulator, [src], "channel_fanout", "cuneate.sim.fanout.bench", build_dir,
                   config={"fanout": cfg.to_kwargs(), "runs": runs} | config,
                   testcase="scoreboard").report
    print(f"\n{simulator}: " + json.dumps(r))
    assert r["runs_checked"] == runs and r["currents_checked"] == runs * cfg.n_neurons
    assert r["twin_mismatches"] == r["golden_violations"] == r["unneeded_clamps"] == 0
    return r


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_scoreboard(simulator, build_root):
    cfg = FanoutConfig(**TABLE)
    assert cfg.can_clamp
    r = _scoreboard(cfg, simulator, build_root / f"fanout_{simulator}", 60, seed=7,
                    extreme_p=0.15, disturb_p=0.3)
    assert 0 < r["golden_max_ratio"] <= 1
    # the bench drove what it must check: clamps both ways, starts during runs, held writes
    assert r["clamps_low"] > 0 and r["clamps_high"] > 0
    assert r["overruns"] > 0 and r["held_cycles"] > 0


#: gains of about 1e18 (the shared exponent adds 46 bits to the product, more than the current
#: holds): every non-zero rectified sample clamps, the sign of gain and sample deciding which
#: way; the twin once wrapped these in int64 to the opposite clamp or to 0
WIDE = dict(n_channels=3, channel=[0, 1, 2, 0, 1, 2, 0, 1],
            gain=[1e18, -1e18, 5e17, -2.5e17, 7.5e17, 1e18, 0.0, -1e18],
            rectify=["none", "none", "abs", "positive", "none", "abs", "none", "positive"],
            threshold=[None, 2.0, None, None, -1.0, None, None, None])


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_scoreboard_at_gains_of_1e18(simulator, build_root):
    cfg = FanoutConfig(**WIDE)
    assert cfg.shift < -cfg.I.width
    r = _scoreboard(cfg, simulator, build_root / f"fanout_wide_{simulator}", 12, seed=3,
                    extreme_p=0.2, disturb_p=0.0)
    # both clamps counted, on the DUT's counters as in the twin (the bench compares them)
    assert r["clamps_low"] > 0 and r["clamps_high"] > 0
    assert r["clamp_counts"] == {"current_low": r["clamps_low"],
                                 "current_high": r["clamps_high"]}


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_the_hdl_engines_equal_the_twin(simulator, build_root):
    cfg = FanoutConfig(**TABLE)
    x = np.random.default_rng(1).uniform(-70, 70, (12, cfg.n_channels))  # some saturate
    fixed = run_fanout("fixed", cfg, x)
    hdl = run_fanout(simulator, cfg, x, build_dir=build_root / f"fanout_engine_{simulator}")
    assert np.array_equal(hdl.values, fixed.values)
    assert hdl.clamp_counts == fixed.clamp_counts and sum(fixed.clamp_counts.values()) > 0
    gold = run_fanout("golden", cfg, np.clip(x, cfg.S.min_value, cfg.S.max_value))
    assert gold.clamp_counts is None and gold.values.shape == fixed.values.shape


@pytest.mark.cocotb
def test_the_scoreboard_catches_a_datapath_fault(build_root, monkeypatch):
    """The RTL built with a faulty rectifier (``abs`` passes negative samples through): the
    bench must fail on the twin's currents."""
    from cuneate.hdl.fanout import core, datapath
    from cuneate.hdl.lib.fixed import select

    def faulty(s, mode, gated, theta):
        r = select(mode == datapath.POSITIVE, select(s < 0, 0, s), s)
        return select(gated & (s < theta), 0, r)
    monkeypatch.setattr(core, "rectify_gate", faulty)
    cfg = FanoutConfig(**TABLE)
    bd = build_root / "fanout_fault_icarus"
    bd.mkdir(parents=True, exist_ok=True)
    src = bd / "channel_fanout.v"
    src.write_text(fanout_verilog(cfg, lowered=True))
    from cuneate.sim.engines.cocotb import SimulatorFailed
    with pytest.raises(SimulatorFailed, match="twin mismatches"):
        run_cocotb("icarus", [src], "channel_fanout", "cuneate.sim.fanout.bench", bd,
                   config={"fanout": cfg.to_kwargs(), "runs": 5, "seed": 7},
                   testcase="scoreboard")
