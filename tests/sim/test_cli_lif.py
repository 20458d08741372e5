"""`cuneate simulate lif`, `cuneate generate lif`, `cuneate lif skin|quantization`."""

import json

import numpy as np
import pytest
from cli_run import python_engine_runs, run_cli, simulate_json

from cuneate.sim.engines.toolchain import SIMULATORS


def test_simulate_json_contract_and_engines_agree(capsys):
    args = ["--neurons", "3", "--current", "20", "30", "60", "--duration-ms", "100",
            "--update-hz", "2000"]
    runs = python_engine_runs(capsys, "lif", *args)
    for e, r in runs.items():
        assert r["model"] == "lif" and r["engine"] == e and r["dt_ms"] == 0.5
        assert len(r["spikes_ms"]) == 3
    assert [len(s) for s in runs["golden"]["spikes_ms"]] == [
        len(s) for s in runs["fixed"]["spikes_ms"]]
    assert sum(len(s) for s in runs["fixed"]["spikes_ms"]) > 10
    assert runs["fixed"]["spikes_ms"] == runs["amaranth"]["spikes_ms"]
    # an analytic check of golden: constant input, ISI = t_ref + tau ln((I - v_reset)/(I - v_th))
    isi = 2.0 + 20.0 * np.log((60 - 11) / (60 - 18))
    assert abs(np.diff(runs["golden"]["spikes_ms"][2]).mean() - isi) <= 0.5
    assert runs["fixed"]["saturation"]["counts"] == {"current": 0, "input": 0, "v_low": 0}


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_simulate_on_hdl_simulators_matches_twin(simulator, capsys, tmp_path):
    args = ["--neurons", "2", "--current", "25", "40", "--duration-ms", "40", "--update-hz",
            "2000"]
    hw = simulate_json(capsys, "lif", "--engine", simulator, "--build-dir", str(tmp_path),
                       *args)
    tw = simulate_json(capsys, "lif", "--engine", "fixed", *args)
    assert hw["spikes_ms"] == tw["spikes_ms"] and sum(map(len, hw["spikes_ms"])) > 2


def test_simulate_discrete_with_weights(capsys, tmp_path):
    w = tmp_path / "w.csv"
    np.savetxt(w, np.array([[0.5, 0.25, -0.125], [0.75, 0.0, 0.25]]), delimiter=",")
    args = ["--form", "discrete", "--neurons", "2", "--current", "0", "--weights", str(w),
            "--weight-bits", "4", "--input-rate", "0.5", "--duration-ms", "10"]
    g, f = (simulate_json(capsys, "lif", "--engine", e, *args) for e in ("golden", "fixed"))
    assert g["spikes_ms"] == f["spikes_ms"]       # weights exact in 4 bits: same spikes
    assert sum(map(len, f["spikes_ms"])) > 5


@pytest.mark.parametrize("argv, msg", [
    (["simulate", "lif", "--decay", "shift"], "use decay='multiply'"),
    (["simulate", "lif", "--engine", "fixed", "--current", "500"], "outside the core's input"),
    (["simulate", "lif", "--weights", "/nonexistent.csv"], "no such file"),
    (["simulate", "lif", "--form", "discrete", "--alpha", "1"], "would not leak"),
    (["simulate", "lif", "--neurons", "2", "--current", "1", "2", "3"], "one per neuron"),
    (["generate", "lif", "--out", "{tmp}", "--neurons", "3000"], "do not fit"),
])
def test_refusals_are_one_line(capsys, argv, msg, tmp_path):
    rc, out, err = run_cli(capsys, [a.format(tmp=tmp_path) for a in argv])
    assert rc == 2 and msg in err and err.count("\n") == 1, err


def test_generate_writes_verilog_and_description(capsys, tmp_path):
    w = tmp_path / "w.csv"
    np.savetxt(w, np.full((16, 4), 0.5), delimiter=",")
    rc, out, err = run_cli(capsys, ["generate", "lif", "--out", str(tmp_path / "g"),
                                    "--neurons", "16", "--clock-hz", "256000", "--weights",
                                    str(w), "--weight-bits", "4", "--form", "discrete"])
    assert rc == 0, err
    v = (tmp_path / "g" / "lif_core.v").read_text()
    d = json.loads((tmp_path / "g" / "lif_core.json").read_text())
    assert "module lif_core" in v and "in_source" in v
    assert d["form"] == "discrete" and d["latency_cycles"] == 5
    assert d["n_inputs"] == 4 and d["accumulator_bits"] == 6 and d["formats"]["W"]["width"] == 4
    assert abs(d["constants"]["k[0]"]["quantized"] - 0.611) < 1e-4
    assert d["ports"]["in_source"]["width"] == 2


def test_quantization_command_prints_table(capsys):
    rc, out, _ = run_cli(capsys, ["lif", "quantization", "--json"])
    rows = {r["weights"]: r for r in json.loads(out)}
    assert rc == 0 and set(rows) == {"FP32", "INT8", "INT4"}
    rc, out, _ = run_cli(capsys, ["lif", "quantization"])
    assert "INT4" in out and "VP mean" in out


def test_skin_command(capsys):
    rc, out, _ = run_cli(capsys, ["lif", "skin", "--engine", "fixed"])
    assert rc == 0 and "row sum" in out and "the pressed one" in out


def test_simulate_with_synaptic_traces(capsys, tmp_path):
    """AMPA/GABA traces: the twin and the Amaranth simulator give identical spikes; golden
    (exact float kernel and weights) the same count within one spike per neuron."""
    w = tmp_path / "w.csv"
    np.savetxt(w, np.array([[20.0, 10.0, 5.0], [25.0, 0.0, 15.0]]), delimiter=",")
    args = ["--neurons", "2", "--current", "12", "--weights", str(w), "--synapses",
            "--input-types", "exc,exc,inh", "--input-rate", "0.05", "--update-hz", "2000",
            "--duration-ms", "300"]
    g, f, a = (simulate_json(capsys, "lif", "--engine", e, *args)
               for e in ("golden", "fixed", "amaranth"))
    assert f["spikes_ms"] == a["spikes_ms"]
    assert all(abs(len(x) - len(y)) <= 1 for x, y in zip(g["spikes_ms"], f["spikes_ms"]))
    assert sum(map(len, f["spikes_ms"])) > 5
