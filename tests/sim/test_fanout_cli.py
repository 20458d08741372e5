"""`cuneate simulate fanout` (golden and fixed) and `cuneate generate fanout`: a small known table
against the float64 reference, a clamp counted, the table file round trip, one-line refusals."""

import json
import math

import numpy as np
import pytest
from cli_run import assert_refused

from cuneate.golden.fanout import fanout_currents
from cuneate.sim.cli import main

# 2 channels -> 4 afferents (afferent i on channel i % 2)
TABLE = ["--channels", "2", "--gain", "1.5", "-2", "0.5", "3",
         "--rectify", "none", "positive", "abs", "none", "--threshold", "none", "none", "none",
         "1"]
CHANNEL = [0, 1, 0, 1]
GAIN = [1.5, -2.0, 0.5, 3.0]
RECT = ["none", "positive", "abs", "none"]
THETA = [np.nan, np.nan, np.nan, 1.0]


def _run(capsys, *argv):
    rc = main(list(argv))
    out = capsys.readouterr()
    assert rc == 0, out.err
    return out.out


def _sim(capsys, *args):
    return json.loads(_run(capsys, "simulate", "fanout", "--json", *args))


@pytest.mark.parametrize("engine", ["golden", "fixed"])
def test_simulate_currents_equal_the_reference(capsys, engine):
    for samples in (["3", "-2"], ["-0.75", "1.25"]):
        r = _sim(capsys, "--engine", engine, "--duration-ms", "5", *TABLE, "--sample", *samples)
        assert r["model"] == "fanout" and r["engine"] == engine and r["runs"] == 5
        assert r["channels"] == 2 and r["afferents"] == 4 and r["dt_ms"] == 1.0
        want = fanout_currents(np.array([float(x) for x in samples]), CHANNEL, GAIN, RECT, THETA)
        cur = np.asarray(r["currents"])
        assert cur.shape == (5, 4)
        assert np.allclose(cur, want[None, :], rtol=0, atol=0 if engine == "golden" else 2**-9)
        assert np.allclose(r["current_range"], np.stack([want, want], axis=1),
                           rtol=0, atol=2**-9)
        if engine == "golden":
            assert r["saturation"] is None
        else:
            assert r["saturation"]["counts"] == {"current_low": 0, "current_high": 0}
    text = _run(capsys, "simulate", "fanout", "--engine", engine, *TABLE, "--sample", "3", "-2")
    assert "afferent 0 (channel 0, gain 1.5, none): I = 4.5 mV/ms" in text
    assert "afferent 2 (channel 0, gain 0.5, abs): I = 1.5 mV/ms" in text
    assert "afferent 3 (channel 1, gain 3, none, gated below 1): I = 0 mV/ms" in text
    if engine == "golden":
        assert "clamps: none on golden" in text
    else:
        assert "clamps: current_low 0, current_high 0 (of 40 currents" in text


def test_simulate_sine_follows_the_reference(capsys):
    a, runs = 4.0, 8
    r = _sim(capsys, *TABLE, "--sine", str(a), "--duration-ms", str(runs))
    k = np.arange(runs)[:, None]
    s = a * np.sin(2 * math.pi * (k / runs + np.arange(2)[None, :] / 2))
    want = fanout_currents(s, CHANNEL, GAIN, RECT, THETA)
    assert np.allclose(r["currents"], want, rtol=0, atol=1e-12)
    assert np.ptp(np.asarray(r["currents"])[:, 0]) > 7      # afferent 0 follows +-4 x 1.5


def test_fixed_counts_a_clamp(capsys):
    # 100 x 10 = 1000 and -1000 mV/ms do not fit the current format sQ10.8 (+-512)
    args = ["--channels", "2", "--afferents", "4", "--gain", "100", "--sample", "10", "-10",
            "--duration-ms", "3"]
    r = _sim(capsys, "--engine", "fixed", *args)
    assert r["saturation"]["counts"] == {"current_low": 6, "current_high": 6}
    cur = np.asarray(r["currents"])
    assert np.all(cur[:, [0, 2]] == 512 - 2**-8) and np.all(cur[:, [1, 3]] == -512)
    g = _sim(capsys, "--engine", "golden", *args)
    assert np.all(np.asarray(g["currents"])[:, [0, 2]] == 1000) and g["saturation"] is None
    text = _run(capsys, "simulate", "fanout", "--engine", "fixed", *args)
    assert "clamps: current_low 6, current_high 6 (of 12 currents" in text


def test_table_file_round_trip(capsys, tmp_path):
    text = _run(capsys, "generate", "fanout", "--out", str(tmp_path), "--name", "fo",
                *TABLE, "--sample-hz", "2000")
    table = tmp_path / "fo.table.json"
    assert str(table) in text and "2 channels -> 4 afferents" in text
    kw = json.loads(table.read_text())
    assert kw["channel"] == CHANNEL and kw["gain"] == GAIN and kw["rectify"] == RECT
    assert kw["threshold"] == [None, None, None, 1.0] and kw["sample_hz"] == 2000
    for engine in ("golden", "fixed"):
        a = _sim(capsys, "--engine", engine, *TABLE, "--sample-hz", "2000", "--sample", "3", "-2")
        b = _sim(capsys, "--engine", engine, "--table", str(table), "--sample", "3", "-2")
        assert a == b and b["runs"] == 20 and b["table"] == kw


def test_generate_fanout(capsys, tmp_path):
    text = _run(capsys, "generate", "fanout", "--out", str(tmp_path), "--channels", "3",
                "--afferents", "6")
    v = (tmp_path / "channel_fanout.v").read_text()
    assert "module channel_fanout" in v and "ch_wr_data" in v and "i_wr_data" in v
    d = json.loads((tmp_path / "channel_fanout.json").read_text())
    assert d["block"] == "channel_fanout" and d["n_channels"] == 3 and d["n_neurons"] == 6
    kw = json.loads((tmp_path / "channel_fanout.table.json").read_text())
    assert kw["channel"] == [0, 1, 2, 0, 1, 2] and kw["gain"] == [1.0] * 6
    assert "11 cycles a run" in text
    # the header says what the file is and what made it, in deterministic bytes (no path of
    # --out, no time), above hardware that is the block's own Verilog
    head, body = v.split("\n\n", 1)
    from cuneate import __version__
    from cuneate.hdl.fanout import FanoutConfig, fanout_verilog
    assert head.startswith(f"// channel_fanout: channel_fanout, generated by cuneate "
                           f"{__version__}\n// command: cuneate generate fanout --channels 3 "
                           f"--afferents 6\n")
    assert "current_format sQ10.8" in head and "// latency: 5 cycles" in head
    assert "//   ch_wr_data               in   16 signed  its sample, raw in the sample " \
           "format" in head
    assert str(tmp_path) not in v
    assert body == fanout_verilog(FanoutConfig.from_kwargs(kw))
    _run(capsys, "generate", "fanout", "--out", str(tmp_path / "again"), "--channels", "3",
         "--afferents", "6")
    assert (tmp_path / "again" / "channel_fanout.v").read_text() == v


@pytest.mark.parametrize("argv,match", [
    (["simulate", "fanout", "--rectify", "none", "sideways"], "--rectify"),
    (["simulate", "fanout", "--afferents", "4", "--gain", "1", "2", "3"],
     "--gain takes one value or one per afferent (4), got 3"),
    (["simulate", "fanout", "--channels", "3", "--sample", "1", "2"],
     "--sample takes one value or one per channel (3), got 2"),
    (["simulate", "fanout", "--channels", "2", "--channel", "0", "1", "2", "1"],
     "--channel: afferent 2 listens to channel 2, outside 0 .. 1"),
    (["simulate", "fanout", "--threshold", "2000"],
     "--threshold: afferent 0: threshold 2000 is outside the sample format"),
    (["simulate", "fanout", "--engine", "fixed", "--sample", "5000"],
     "--sample 5000 is outside the sample format"),
    (["generate", "fanout", "--out", "/nonexistent/x", "--table", "t.json", "--gain", "2"],
     "--table and --gain exclude each other"),
    (["simulate", "fanout", "--clock-hz", "1e4"], "--clock-hz/--sample-hz: a fan-out run"),
])
def test_refusals_exit_2_with_one_line_naming_the_option(capsys, argv, match):
    assert_refused(capsys, argv, match)


def test_table_file_refusals(capsys, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"n_channels": 2, "channel": [0, 3], "gain": [1, 1]}))
    desc = tmp_path / "desc.json"
    desc.write_text(json.dumps({"block": "channel_fanout"}))
    for path, match in ((bad, "afferent 1 listens to channel 3"), (desc, "unknown key 'block'")):
        rc = main(["simulate", "fanout", "--table", str(path)])
        err = capsys.readouterr().err
        assert rc == 2 and f"--table {str(path)!r}" in err and match in err, err
        assert err.count("\n") == 1
