"""Resources of the coincidence detector and the network from yosys synth_ecp5 and
synth_xilinx -family xc6s (long lane: synthesis)."""

import json

import pytest

from cuneate.hdl.coincidence import CoincidenceConfig
from cuneate.hdl.coincidence import synth_resources
from cuneate.sim.cli import main


@pytest.mark.long
def test_detector_maps_memories_and_multipliers():
    cfg = CoincidenceConfig()                   # the brief's detector: 4 -> 3, 512-tick history
    res = synth_resources(cfg)
    e, x = res["ecp5"]["summary"], res["xc6s"]["summary"]
    print(f"\necp5 {e}\nxc6s {x}")
    # the 512 x 4-bit history is one block RAM; the state and delay/weight words are small
    assert e["DP16KD"] == 1 and x["RAMB8BWER"] + x["RAMB16BWER"] == 1
    # two trace multipliers and the Izhikevich core's four (dt = 1/16 ms: shifts), at most
    # one duplicated by synthesis; no LUT multipliers for the large products
    assert 6 <= e["MULT18X18D"] <= 7 and 6 <= x["DSP48A1"] <= 7
    assert e["LUT4 equiv."] < 3000 and x["LUT"] < 2000 and e["FF"] < 2000


@pytest.mark.long
def test_generate_network_with_resources(tmp_path, capsys):
    rc = main(["generate", "network", "--out", str(tmp_path), "--resources"])
    out = capsys.readouterr().out
    assert rc == 0 and "synth_ecp5" in out and "xc6s" in out
    d = json.loads((tmp_path / "afferent_cuneate_network.json").read_text())
    r = d["resources"]
    assert r["ecp5"]["summary"]["MULT18X18D"] >= 10 and r["xc6s"]["summary"]["DSP48A1"] >= 10
