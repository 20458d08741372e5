"""Recorded traces: CSV, NPZ, MATLAB (nested structs); NaN, gaps and non-monotonic time
stamps reported with their position, never repaired."""

import numpy as np
import pytest
import scipy.io

from cuneate.sim import cli
from cuneate.sim.scenes import DEFAULT_SCENE_TOML
from cuneate.sim.host.traces import TraceError, load_trace

T = np.arange(50) / 1000.0
X = np.stack([np.linspace(0, 0.01, 50), np.linspace(0, 0.008, 50)], axis=1)


def _csv(path, t=T, x=X, head="Time,g0,g1"):
    rows = [head] + [",".join(repr(float(v)) for v in (ti, *xi)) for ti, xi in zip(t, x)]
    path.write_text("\n".join(rows) + "\n")
    return path


def test_three_formats_load_the_same_trace(tmp_path):
    a = load_trace(_csv(tmp_path / "a.csv"))
    np.savez(tmp_path / "b.npz", Time=T, DeltaBraggW=X)
    b = load_trace(tmp_path / "b.npz")
    # an interrogator export: struct FBG with Time and DeltaBraggW, plus a load cell
    scipy.io.savemat(tmp_path / "c.mat", {"FBG": {"Time": T, "DeltaBraggW": X},
                                          "LoadCell": {"Fz": np.zeros(50)}})
    c = load_trace(tmp_path / "c.mat", struct="FBG")
    for tr in (a, b, c):
        assert tr.d_lambda_nm.shape == (50, 2) and tr.fs_hz == pytest.approx(1000.0)
        assert np.allclose(tr.d_lambda_nm, X)
    # configurable field names, pm and ms units
    scipy.io.savemat(tmp_path / "d.mat", {"S": {"t_ms": T * 1e3, "shift": X * 1e3}})
    d = load_trace(tmp_path / "d.mat", struct="S", time_key="t_ms", data_key="shift",
                   time_unit="ms", shift_unit="pm")
    assert np.allclose(d.d_lambda_nm, X)


@pytest.mark.parametrize("mutate,expect", [
    (lambda t, x: x.__setitem__((17, 1), np.nan), "row 17, grating 1: sample is nan"),
    (lambda t, x: x.__setitem__((3, 0), np.inf), "row 3, grating 0: sample is inf"),
    (lambda t, x: t.__setitem__(9, t[8]), "row 9: time stamp 0.008 does not increase"),
    (lambda t, x: t.__setitem__(slice(30, None), t[30:] + 0.005), "row 30: gap of 0.006 s"),
])
def test_bad_samples_are_reported_with_their_position(tmp_path, mutate, expect):
    t, x = T.copy(), X.copy()
    mutate(t, x)
    np.savez(tmp_path / "bad.npz", Time=t, DeltaBraggW=x)
    with pytest.raises(TraceError, match=expect.replace("(", r"\(")) as ei:
        load_trace(tmp_path / "bad.npz")
    assert str(ei.value).startswith(str(tmp_path / "bad.npz"))
    _csv(tmp_path / "bad.csv", t, x)
    with pytest.raises(TraceError, match=expect.split(":")[0]):
        load_trace(tmp_path / "bad.csv")


def test_csv_errors_name_row_and_column(tmp_path):
    p = tmp_path / "e.csv"
    p.write_text("Time,g0\n0.0,1.0\n0.001,abc\n")
    with pytest.raises(TraceError, match=r"row 1, column 'g0': not a number: 'abc'"):
        load_trace(p)
    p.write_text("t,g0\n0.0,1.0\n")
    with pytest.raises(TraceError, match=r"no time column 'Time'"):
        load_trace(p)
    with pytest.raises(TraceError, match=r"no 'Nope' in the file"):
        scipy.io.savemat(tmp_path / "f.mat", {"Time": T})
        load_trace(tmp_path / "f.mat", data_key="Nope")
    with pytest.raises(TraceError, match="sampled at 1000 Hz but the scene's sensor samples "
                                         "at 100 Hz"):
        load_trace(_csv(tmp_path / "g.csv"), expect_fs_hz=100.0)


def test_recorded_scene_runs_and_bad_trace_exits_2(tmp_path, capsys):
    t = np.arange(400) / 1000.0
    ramp = np.clip((t - 0.05) / 0.1, 0, 1) * 0.01
    np.savez(tmp_path / "rec.npz", Time=t, DeltaBraggW=np.stack([ramp, 0.8 * ramp], axis=1))
    text = (DEFAULT_SCENE_TOML.replace('kind = "grasp"', 'kind = "recorded"\nfile = "rec.npz"')
            .replace('window = "loading"\n', "")
            .replace('engines = ["golden", "fixed", "verilator"]', 'engines = ["fixed"]')
            .replace('kind = "tree"', 'kind = "none"'))
    (tmp_path / "s.toml").write_text(text)
    assert cli.main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 0
    assert "fixed" in capsys.readouterr().out
    x = np.stack([ramp, ramp], axis=1)
    x[123, 0] = np.nan
    np.savez(tmp_path / "rec.npz", Time=t, DeltaBraggW=x)
    assert cli.main(["-q", "run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "rec.npz: row 123, grating 0: sample is nan" in err and err.count("\n") == 1
