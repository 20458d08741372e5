"""`cuneate simulate network` on every engine and `cuneate generate network`: the afferent ->
cuneate network end to end, the HDL simulators equal to the twin spike for spike."""

import json

import numpy as np
import pytest
from cli_run import assert_refused, python_engine_runs, simulate_json

from cuneate.hdl.network import NetworkConfig
from cuneate.sim.cli import main
from cuneate.sim.network.engines import current_writes, run_network
from cuneate.sim.engines.toolchain import SIMULATORS

ARGS = ["--delays-ms", "0,0,1,1;0,0,0,0;1,1,0,0", "--current", "20", "30", "15", "45", "60",
        "18", "10", "10", "--duration-ms", "60"]


def test_simulate_network_json_contract_and_engines_agree(capsys):
    runs = python_engine_runs(capsys, "network", *ARGS)
    for e, r in runs.items():
        assert r["model"] == "network" and r["engine"] == e and r["neurons"] == 11
        assert [p["count"] for p in r["populations"]] == [8, 3]
        assert len(r["spikes_ms"]) == 11
    f, a, g = runs["fixed"], runs["amaranth"], runs["golden"]
    assert f["spikes_ms"] == a["spikes_ms"]
    assert sum(map(len, f["spikes_ms"][8:])) > 0
    # every afferent spike of a source crossed the link once
    assert a["counters"]["link_count"] == sum(map(len, f["spikes_ms"][:4]))
    assert a["counters"]["merged_count"] == 0 and a["counters"]["overrun_count"] == 0
    # golden (float64 afferents and PSPs) against fixed: same counts, close times
    assert [len(s) for s in g["spikes_ms"]] == [len(s) for s in f["spikes_ms"]]
    for x, y in zip(g["spikes_ms"], f["spikes_ms"]):
        assert np.max(np.abs(np.subtract(x, y)), initial=0) <= 0.25


def test_changing_currents_are_written_before_their_tick():
    det = dict(n_sources=2, n_targets=1, delays_ticks=[[0, 2]], max_delay_ticks=4)
    cfg = NetworkConfig(n_afferents=6, detector=det, clock_hz=16e3 * 64,
                        tick_source="external")
    n = 500
    cur = np.zeros((n, 6))
    cur[100:, 0] = 40.0                    # afferent 0 switched on at tick 100
    cur[150:, 1] = 40.0
    w = current_writes(cfg, cur)
    assert sorted(w) == [0, 100, 150] and w[100] == [(0, int(cfg.core.I.to_raw(40.0)))]
    f, a = (run_network(e, cfg, cur) for e in ("fixed", "amaranth"))
    assert len(f.spikes_ms) == len(a.spikes_ms) == cfg.n_afferents + cfg.n_targets
    for x, y in zip(f.spikes_ms, a.spikes_ms):
        assert np.array_equal(x, y)
    aff = f.population("afferent")
    assert 100 * cfg.dt_ms < aff[0][0] and 150 * cfg.dt_ms < aff[1][0] and len(aff[2]) == 0


@pytest.mark.long
@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_simulate_network_on_hdl_simulators_matches_twin(simulator, capsys, tmp_path):
    hw = simulate_json(capsys, "network", "--engine", simulator, "--build-dir", str(tmp_path),
                       *ARGS)
    tw = simulate_json(capsys, "network", "--engine", "fixed", *ARGS)
    assert hw["spikes_ms"] == tw["spikes_ms"] and sum(map(len, hw["spikes_ms"][8:])) > 0
    assert hw["counters"]["link_count"] == sum(map(len, tw["spikes_ms"][:4]))
    assert hw["counters"]["afferent_overflow"] == 0 == hw["counters"]["cuneate_overflow_count"]


def test_generate_network(capsys, tmp_path):
    rc = main(["generate", "network", "--out", str(tmp_path), "--afferents", "16",
               "--first-source", "12", "--delays-ms", "0,0,2,2;2,2,0,0"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    v = (tmp_path / "afferent_cuneate_network.v").read_text()
    assert "module afferent_cuneate_network" in v and "out_population" in v
    d = json.loads((tmp_path / "afferent_cuneate_network.json").read_text())
    assert d["block"] == "AfferentCuneateNetwork" and d["first_source"] == 12
    assert d["latency"]["afferent_update_to_psp_onset_ticks"] == "2 + delay[t, s]"
    assert d["detector"]["delays_ticks"] == [[0, 0, 32, 32], [32, 32, 0, 0]]
    assert d["ports"]["i_wr_data"]["direction"] == "in" and d["populations"] == [
        "afferent", "cuneate"]
    assert "stamped with detector tick k + 1" in out.out


@pytest.mark.parametrize("argv,match", [
    (["simulate", "network", "--first-source", "6"],
     "the detector's 4 sources from afferent 6 on do not fit the core's 8 afferents"),
    (["simulate", "network", "--current", "1", "2"], "--current takes one value or one per "
                                                     "afferent (8)"),
    (["simulate", "network", "--engine", "fixed", "--current", "1e6"],
     "outside the core's accepted range"),
    (["generate", "network", "--out", "/tmp/x", "--afferents", "3"],
     "n_afferents must be an integer >= 6"),
])
def test_network_refusals_exit_2_with_one_line(capsys, argv, match):
    assert_refused(capsys, argv, match)
