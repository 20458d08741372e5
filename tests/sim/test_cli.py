"""The `cuneate` CLI: doctor, simulate (golden), filter check, generate, argument errors."""

import json
import subprocess
import sys

import pytest
from cli_run import run_cli



def test_doctor_json_reports_required_tools(capsys):
    rc, out, _ = run_cli(capsys, ["doctor", "--json"])
    data = json.loads(out)
    tools = data["tools"]
    for name in ("python", "amaranth", "yosys (amaranth)", "cocotb", "verilator", "icarus"):
        assert tools[name]["required"]
        assert tools[name]["ok"], tools[name]
    major, minor = (int(x) for x in tools["verilator"]["version"].split("."))
    assert (major, minor) >= (5, 36)
    assert rc == 0 and data["ok"] is True


def test_doctor_names_the_fix_for_a_missing_tool(monkeypatch, capsys):
    import shutil
    real = shutil.which
    monkeypatch.setattr(shutil, "which", lambda n, *a, **k: None if n == "iverilog" else
                        real(n, *a, **k))
    rc, out, _ = run_cli(capsys, ["doctor", "--json"])
    data = json.loads(out)
    assert rc == 1 and not data["ok"]
    assert "apt-get install -y iverilog" in data["tools"]["icarus"]["fix"]


def test_simulate_golden_json_contract(capsys):
    rc, out, _ = run_cli(capsys, ["simulate", "izhikevich", "--engine", "golden", "--preset",
                                  "RS", "--current", "10", "--duration-ms", "1000", "--neurons",
                                  "2", "--json"])
    assert rc == 0
    data = json.loads(out)
    assert data["engine"] == "golden" and data["model"] == "izhikevich"
    assert data["dt_ms"] == 0.0625 and len(data["spikes_ms"]) == 2
    assert data["spikes_ms"][0] == data["spikes_ms"][1] and len(data["spikes_ms"][0]) == 23
    rc, out, _ = run_cli(capsys, ["simulate", "izhikevich", "--current", "10", "--duration-ms",
                                  "500", "--scheme", "rk4", "--dt-ms", "0.03125", "--a", "0.1",
                                  "--d", "2", "--json"])
    data = json.loads(out)
    assert data["params"] == {"a": 0.1, "b": 0.2, "c": -65.0, "d": 2.0}
    assert data["dt_ms"] == 0.03125 and len(data["spikes_ms"][0]) > 23


@pytest.mark.parametrize("argv, match", [
    (["simulate", "izhikevich", "--current", "abc"], "not a number"),
    (["simulate", "izhikevich", "--duration-ms", "-5"], "must be > 0"),
    (["simulate", "izhikevich", "--neurons", "0"], "must be >= 1"),
    (["simulate", "izhikevich", "--preset", "XYZ"], "invalid choice"),
    (["simulate", "izhikevich", "--neurons", "3", "--current", "1", "2"], "one per neuron"),
    (["simulate", "izhikevich", "--engine", "fixed", "--scheme", "rk4"], "forward Euler"),
    (["simulate", "izhikevich", "--engine", "fixed", "--dt-ms", "0.1"], "update-hz"),
    (["simulate", "izhikevich", "--engine", "fixed", "--current", "600"], "outside"),
    (["simulate", "izhikevich", "--current", "nan"], "not a finite number"),
    (["generate", "izhikevich", "--neurons", "3000", "--out", "x"], "do not fit"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_arguments_exit_2_with_one_line(capsys, argv, match):
    rc, out, err = run_cli(capsys, argv)
    assert rc == 2 and out == ""
    assert match in err and len(err.strip().splitlines()) == 1


def test_simulate_divergence_is_reported_not_nan(capsys):
    rc, out, err = run_cli(capsys, ["-q", "simulate", "izhikevich", "--current", "-2000",
                                    "--dt-ms", "1", "--duration-ms", "50", "--json"])
    assert rc == 2 and out == "" and "diverged" in err and "neuron 0" in err
    assert len(err.strip().splitlines()) == 1


def test_filter_check(capsys):
    rc, out, _ = run_cli(capsys, ["filter", "check", "--b", "0.045", "0", "-0.045", "--a", "1",
                                  "-1.9093", "0.9099"])
    assert rc == 0 and "stable" in out.lower()
    # the coefficients as published have a real pole at 1.0627: refused
    rc, out, err = run_cli(capsys, ["filter", "check", "--b", "0.045", "0", "-0.045", "--a",
                                    "1", "-1.919", "0.91", "--json"])
    data = json.loads(out)
    # a bad filter is bad input: exit 2 (it was 1), the report on stdout, one line naming it
    assert rc == 2 and data["stable"] is False
    assert err.strip().splitlines() == [err.strip()] and "is unstable: pole z = 1.06" in err
    assert data["max_radius"] == pytest.approx((1.919 + (1.919**2 - 4 * 0.91) ** 0.5) / 2,
                                               rel=1e-6)


def test_console_script_generate(tmp_path):
    exe = [sys.executable, "-m", "cuneate.sim.cli"]
    r = subprocess.run(exe + ["generate", "izhikevich", "--neurons", "64", "--clock-hz",
                              "1.024e6", "--out", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "izhikevich_core.v").exists() and (tmp_path / "izhikevich_core.json").exists()
