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


@pytest.mark.long
def test_datapath_cannot_wrap_for_a_mix_of_sets(capsys):
    """Through the command a user types (about a minute with z3; the per-preset proofs through
    the API are in the long lane too)."""
    import json
    from cuneate.sim.cli import main
    code = main(["prove", "--preset", "IB", "--preset", "FS", "--json"])
    r = json.loads(capsys.readouterr().out)
    record("formal_datapath_IB_FS", 1, 0, int(r["status"] != "pass"), "SymbiYosys, z3")
    assert code == 0 and r["status"] == "pass" and r["param_sets"] == ["IB", "FS"], r
    assert r["property"] == "datapath" and not r["counterexample"]


def test_cli_prove_names_a_counterexample_and_refuses_an_unknown_preset(capsys):
    from cuneate.sim.cli import main
    assert main(["prove", "--property", "state_box"]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "counterexample: v = " in out
    assert main(["prove", "--preset", "XX"]) == 2


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
# RS in CI; the other presets in the release lane (make test-release)
@pytest.mark.parametrize("preset", ["RS", *[pytest.param(p, marks=pytest.mark.release)
                                            for p in ("IB", "CH", "FS", "LTS", "RZ")]])
def test_datapath_cannot_wrap(preset, tmp_path):
    r = prove(_cfg(preset), tmp_path, "datapath")
    record(f"formal_datapath_{preset}", 1, 0, int(r["status"] != "pass"), "SymbiYosys, z3")
    assert r["status"] == "pass", r


# the long lane (CI): RS here, CH beside it, the other presets in the release lane
@pytest.mark.long
def test_the_core_steps_compute_the_four_stage_update(tmp_path):
    """The pipelined steps (the core's and the twin's arithmetic) give the four-stage update's
    v, u, spike and clamp flags for every state of the box and every accepted current; their
    own narrowings hold; the q w product is compared over every v of the box."""
    cfg = _cfg("RS")
    r = prove(cfg, tmp_path, "steps", solver="yices")
    record("formal_steps_RS", 1, 0, int(r["status"] != "pass"), "SymbiYosys, yices + numpy")
    assert r["status"] == "pass", r
    t = r["products"]
    assert t["mismatches"] == 0 and t["states"] == cfg.VTH.raw - cfg.v_floor_raw + 1


@pytest.mark.long
def test_the_steps_property_catches_a_fault(tmp_path, monkeypatch):
    """Each half of the steps property fails on a fault in the steps: u one LSB high in the
    last step (the solver), and the q rounding's w multiple dropped (the product table)."""
    from cuneate.hdl.izhikevich import datapath as izh
    cfg = _cfg("RS")
    true_select, true_product2 = izh.select_step, izh.product2_step

    def u_high(cfg_, x):
        out = dict(true_select(cfg_, x))
        out["u_next"] = out["u_next"] + 1
        return out
    monkeypatch.setattr(izh, "select_step", u_high)
    r = prove(cfg, tmp_path / "u", "steps", solver="yices")
    assert r["status"] == "fail" and any("check" in f for f in r["failed"]), r
    monkeypatch.setattr(izh, "select_step", true_select)

    def no_rounding(cfg_, x):
        return true_product2(cfg_, dict(x, qbit=0 * x["qbit"]))
    monkeypatch.setattr(izh, "product2_step", no_rounding)
    r = prove(cfg, tmp_path / "p", "steps", solver="yices")
    assert r["status"] == "fail" and r["failed"] == ["steps: q w product"], r
    assert r["products"]["mismatches"] > 0


@pytest.mark.parametrize("sets", [
    # CH (the default lane proves RS) in CI; the other presets in the release lane
    pytest.param(("CH",), marks=pytest.mark.long),
    *[pytest.param((p,), marks=pytest.mark.release) for p in ("IB", "FS", "LTS", "RZ")],
    *[pytest.param(s, marks=pytest.mark.release) for s in (("IB", "FS"), ("CH", "LTS", "RZ"))]],
    ids="+".join)
def test_the_core_steps_compute_the_four_stage_update_for_every_preset(sets, tmp_path):
    """The other five presets (RS runs in the default lane), each alone at its own formats
    (long lane); as two mixes of sets, the constants selected per neuron, in the release lane
    (the selection is the same function on both sides of the property, so a mix proves each
    set's arithmetic again, at formats wide enough for all of them, in 10-25 minutes)."""
    r = prove(_cfg(*sets), tmp_path, "steps", solver="yices")
    record(f"formal_steps_{'_'.join(sets)}", 1, 0, int(r["status"] != "pass"),
           "SymbiYosys, yices + numpy")
    assert r["status"] == "pass" and r["products"]["mismatches"] == 0, r
