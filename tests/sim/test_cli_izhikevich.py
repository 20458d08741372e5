"""`cuneate simulate|generate izhikevich`: one core configuration, guarded knobs, visible clamps."""

import json
import re

import pytest
from cli_run import run_cli

from cuneate.golden import izhikevich as gz


def one_line_error(capsys, argv):
    rc, out, err = run_cli(capsys, argv)
    assert rc == 2 and out == "", (rc, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cuneate"), err
    return lines[0]


# Core options that a configuration refuses: `simulate` (hardware engines and golden alike) and
# `generate` share the configuration, so they refuse with the same reason.
CORE_REFUSALS = [
    (["--clock-hz", "41e6", "--neurons", "2500"],
     "41000000 / 16000 = 2562.5 is not an integer number of cycles per update"),
    (["--neurons", "1000000000"], "do not fit one sweep"),
    (["--u-int-bits", "6"], "u needs 10 integer bits"),
    (["--v-int-bits", "7"], "v needs"),
    (["--operand-width", "8"], "representation error"),
    (["--param-set", "0.02,0.2,40,8"], "is not below threshold 30"),
    (["--current-range", "10", "-10"], "current"),
]


@pytest.mark.parametrize("opts,reason", CORE_REFUSALS, ids=[r[1][:24] for r in CORE_REFUSALS])
def test_simulate_and_generate_refuse_the_same_core(capsys, tmp_path, opts, reason):
    msgs = [one_line_error(capsys, ["simulate", "izhikevich", "--engine", e] + opts)
            for e in ("golden", "fixed")]
    msgs.append(one_line_error(capsys, ["generate", "izhikevich", "--out", str(tmp_path)] + opts))
    for m in msgs:
        assert reason in m, m
    tails = {m.split(": ", 1)[1] for m in msgs}
    assert len(tails) == 1, tails              # the same reason word for word


def test_golden_refuses_reset_at_threshold_through_the_preset_override(capsys):
    msg = one_line_error(capsys, ["simulate", "izhikevich", "--c", "30"])
    assert "reset c = 30 is not below threshold 30" in msg
    with pytest.raises(ValueError, match="c = 30 mV is not below the threshold"):
        gz.simulate(gz.IzhikevichParams(0.02, 0.2, 30.0, 8.0), 10.0, duration_ms=10.0)


@pytest.mark.parametrize("argv,reason", [
    (["--engine", "fixed", "--duration-ms", "0.01"], "shorter than one update (dt = 0.0625 ms)"),
    (["--engine", "golden", "--dt-ms", "1", "--duration-ms", "0.5"], "shorter than one update"),
    (["--engine", "fixed", "--duration-ms", "1e12"], "GiB"),
    (["--engine", "icarus", "--neurons", "2500", "--duration-ms", "20000"], "--max-minutes"),
    (["--engine", "fixed", "--current", "300", "--current-range", "-100", "100"],
     "outside the core's accepted range [-100, 100]"),
    (["--engine", "fixed", "--build-dir", "/dev/null/x"], "--build-dir '/dev/null/x'"),
])
def test_simulate_guards(capsys, argv, reason):
    assert reason in one_line_error(capsys, ["simulate", "izhikevich"] + argv)


def test_generate_bad_out_is_one_line(capsys):
    assert "--out '/dev/null/x'" in one_line_error(
        capsys, ["generate", "izhikevich", "--out", "/dev/null/x"])


def test_update_rate_below_16khz_is_accepted(capsys):
    """8 kHz used to be refused for overflow; the state formats now follow from the proof."""
    rc, out, err = run_cli(capsys, ["simulate", "izhikevich", "--engine", "fixed", "--update-hz",
                                    "8000", "--clock-hz", "20e6", "--neurons", "2500",
                                    "--duration-ms", "2", "--json"])
    assert rc == 0, err
    assert json.loads(out)["dt_ms"] == 0.125


def test_large_current_keeps_golden_count_and_reports_no_clamp(capsys):
    """RS at I = 300 mV/ms for 1 s: the fixed engine matches golden's count (it used to give
    2005 against 692 with u pinned at its format's top, silently)."""
    counts = {}
    for engine in ("golden", "fixed"):
        rc, out, err = run_cli(capsys, ["simulate", "izhikevich", "--engine", engine,
                                        "--current", "300", "--duration-ms", "1000", "--json"])
        assert rc == 0, err
        data = json.loads(out)
        counts[engine] = len(data["spikes_ms"][0])
    assert counts["golden"] > 600
    assert abs(counts["fixed"] - counts["golden"]) <= 1, counts
    assert data["saturation"]["counts"] == dict.fromkeys(data["saturation"]["counts"], 0)
    assert not any(data["saturation"]["sticky"].values())
    assert data["formats"]["U"] == "sQ10.20"
    assert data["accepted_current_range"][0] == -512.0


def test_flagged_saturation_is_counted_in_json(capsys):
    """A deliberately narrow u format with saturation='flag': the clamp acts, and says so."""
    rc, out, err = run_cli(capsys, ["simulate", "izhikevich", "--engine", "fixed", "--current",
                                    "300", "--saturation", "flag", "--u-int-bits", "8",
                                    "--duration-ms", "100", "--json"])
    assert rc == 0, err
    sat = json.loads(out)["saturation"]
    assert sat["counts"]["u_high"] > 0 and sat["sticky"]["u_high"]
    assert sat["counts"]["v_low"] == 0 and not sat["sticky"]["v_low"]


def test_force_runs_a_long_estimate_with_progress(capsys):
    rc, out, err = run_cli(capsys, ["simulate", "izhikevich", "--engine", "fixed", "--neurons",
                                    "50", "--duration-ms", "200", "--max-minutes", "1e-6",
                                    "--force", "--json"])
    assert rc == 0
    assert len(json.loads(out)["spikes_ms"]) == 50
    # stderr is not a terminal here: the step is a timestamped line (a bar in a terminal)
    assert re.search(r"^\[\d\d:\d\d:\d\d\] simulating 50 neuron\(s\) on fixed .*\(3200 "
                     r"sweeps\) \.\.\.$", err, re.M), err


def test_generate_prints_formats_and_range(capsys, tmp_path):
    rc, out, err = run_cli(capsys, ["generate", "izhikevich", "--out", str(tmp_path)])
    assert rc == 0, err
    data = json.loads((tmp_path / "izhikevich_core.json").read_text())
    assert data["accepted_current_range"] == [-512.0, 511.99609375]
    assert set(data["clamps"]) >= {"v_low", "u_high", "u_low", "current", "y"}


def test_generate_takes_the_pipeline_depth(capsys, tmp_path):
    rc, out, err = run_cli(capsys, ["generate", "izhikevich", "--out", str(tmp_path),
                                    "--pipeline-stages", "7"])
    assert rc == 0, err
    data = json.loads((tmp_path / "izhikevich_core.json").read_text())
    assert data["pipeline_depth"] == 7 and data["latency_cycles"] == 7
    assert data["pipeline_cuts"] == [1, 2, 3, 4]
    rc, out, err = run_cli(capsys, ["generate", "izhikevich", "--out", str(tmp_path),
                                    "--pipeline-stages", "4"])
    assert rc == 2 and "--pipeline-stages" in err


@pytest.mark.parametrize("block,extra", [("izhikevich", ["--neurons", "3", "--current", "5", "10", "20"]),
                                         ("lif", [])])
def test_simulate_spikes_file_loads_back_equal_to_the_printed_trains(capsys, tmp_path, block,
                                                                    extra):
    import numpy as np

    from cuneate.sim.spikes import load_spikes
    f = tmp_path / "s.npz"
    rc, out, err = run_cli(capsys, ["-q", "simulate", block, "--engine", "fixed", "--json",
                                    "--duration-ms", "200", "--spikes", str(f), *extra])
    assert rc == 0, err
    printed = json.loads(out)["spikes_ms"]
    sf = load_spikes(f)
    assert sf.engine == "fixed" and len(sf) == len(printed) and sum(map(len, printed)) > 0
    for got, want in zip(sf.trains(), printed):
        assert np.array_equal(got, np.asarray(want, dtype=float))
    assert set(sf.population) == {block}
