"""SymbiYosys on the one-update datapath: no narrowing can wrap for any state in the box and
any accepted current (a proof), and the state box itself is not closed under one update (a
counterexample, caught by the flagged u_high clamp)."""

import numpy as np
import pytest

from cuneate.hdl.izhikevich.formal import prove
from cuneate.hdl.izhikevich import IzhikevichConfig, IzhikevichTwin
from cuneate.sim.hardcases import record


def _cfg(*sets):
    return IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, param_sets=tuple(sets))


def test_datapath_cannot_wrap_for_a_mix_of_sets(tmp_path):
    r = prove(_cfg("IB", "FS"), tmp_path, "datapath")
    record("formal_datapath_IB_FS", 1, 0, int(r["status"] != "pass"), "SymbiYosys, z3")
    assert r["status"] == "pass", r


def test_state_box_is_not_inductive_and_the_clamp_flags_it(tmp_path):
    cfg = _cfg("RS")
    r = prove(cfg, tmp_path, "state_box")
    assert r["status"] == "fail"
    c = r["counterexample"]
    # the counterexample lies in the box and is accepted ...
    assert cfg.v_floor_raw <= c["v"] <= cfg.VTH.raw and cfg.u_lo_raw <= c["u"] <= cfg.u_hi_raw
    assert cfg.i_lo_raw <= c["I"] <= cfg.i_hi_raw
    # ... and the twin confirms it: one update leaves the box, and a flagged clamp says so
    out = IzhikevichTwin(cfg, kernel="stages").update(np.array([c["v"]]), np.array([c["u"]]),
                                                      np.array([c["I"]]), np.array([0]))
    assert bool(out["u_high"][0] or out["u_low"][0] or out["v_low"][0])
    record("formal_state_box_RS_counterexample", 1, 1, 0, "found and confirmed by the twin")


@pytest.mark.long
@pytest.mark.parametrize("preset", ["RS", "IB", "CH", "FS", "LTS", "RZ"])
def test_datapath_cannot_wrap(preset, tmp_path):
    r = prove(_cfg(preset), tmp_path, "datapath")
    record(f"formal_datapath_{preset}", 1, 0, int(r["status"] != "pass"), "SymbiYosys, z3")
    assert r["status"] == "pass", r


def test_cli_prove(capsys):
    from cuneate.sim.cli import main
    assert main(["prove", "--preset", "IB", "--preset", "FS"]) == 0
    assert "PASS" in capsys.readouterr().out
    assert main(["prove", "--property", "state_box"]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "counterexample: v = " in out
    assert main(["prove", "--preset", "XX"]) == 2
