"""Waveform windows (the Amaranth engine's VCD; the HDL simulators in the cocotb lane) and
progress lines when stderr is not a terminal."""

import io
import re
import time

import pytest

from cuneate.sim import progress
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.engines.waves import Waves
from cuneate.sim.izhikevich.engines import run_engine


def _vcd_signals_and_times(path):
    """Parse a VCD strictly enough to trust it: the header's variables, then every value change
    naming a declared identifier, timestamps increasing. (Amaranth names internal signals with
    ``$``, which pyvcd's reader refuses but GTKWave and Surfer read.)"""
    names, ids, times = set(), set(), []
    header = True
    for line in open(path):
        s = line.strip()
        if header:
            m = re.match(r"\$var \S+ \d+ (\S+) (\S+)", s)
            if m:
                ids.add(m.group(1))
                names.add(m.group(2))
            header = not s.startswith("$enddefinitions")
            continue
        if not s or s.startswith("$"):
            continue
        if s.startswith("#"):
            t = int(s[1:])
            assert not times or t > times[-1], f"time going back: {s}"
            times.append(t)
        elif s[0] in "bBrR":
            assert s.split()[1] in ids, s
        else:
            assert s[0] in "01xXzZ" and s[1:] in ids, s
    assert not header, "no $enddefinitions"
    return names, times


def test_amaranth_writes_a_windowed_vcd_and_gtkw(tmp_path):
    w = Waves(tmp_path, start=3, ticks=4)
    run = run_engine("amaranth", {"n_neurons": 8}, [10.0] * 8, 2.0, waves=w)
    dump, gtkw = tmp_path / "amaranth.vcd", tmp_path / "amaranth.gtkw"
    assert dump.is_file() and gtkw.is_file()
    names, times = _vcd_signals_and_times(dump)
    for s in ("clk", "tick", "sweep_done", "spike_valid", "spike_index", "upd_v"):
        assert s in names, s
    assert times, "no value changes in the window"
    # the window holds 4 of the run's sweeps of 8 cycles (two clock edges each), not all
    assert run.n_ticks == 32
    assert 4 * 8 <= len(times) <= (4 + 2) * 8 * 2 + 4
    text = gtkw.read_text()
    assert "sweep_done" in text and "spike_valid" in text and str(dump.resolve()) in text


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", [
    # Verilator's traced model is a build of its own (about 100 s): the long lane runs it
    pytest.param(s, marks=pytest.mark.long if s == "verilator" else ()) for s in SIMULATORS])
def test_hdl_simulators_write_their_dump(simulator, tmp_path, build_root):
    w = Waves(tmp_path, start=2, ticks=3)
    run_engine(simulator, {"n_neurons": 8}, [10.0] * 8, 2.0,
               build_dir=build_root / f"waves_{simulator}", waves=w)
    dump = w.path(simulator)
    assert dump.is_file() and dump.stat().st_size > 0
    assert (dump.with_suffix(".gtkw")).is_file()
    if dump.suffix == ".vcd":
        names, times = _vcd_signals_and_times(dump)
        assert {"sweep_done", "spike_valid"} <= names and times
    else:
        assert dump.read_bytes()[:1] == b"\x00"     # FST header block


def test_engines_without_waveforms_refuse():
    with pytest.raises(ValueError, match="writes no waveforms"):
        run_engine("fixed", {"n_neurons": 8}, [10.0] * 8, 1.0, waves=Waves("x"))


def test_log_mode_prints_timestamped_heartbeats():
    buf = io.StringIO()
    progress.configure("log", stream=buf, heartbeat_s=0.5)
    try:
        with progress.step("building the reference", total=10, unit="point") as st:
            st.set(3)
            deadline = time.monotonic() + 30.0      # a loaded machine may starve the ticker
            while (buf.getvalue().count("... building the reference 30 %") < 2
                   and time.monotonic() < deadline):
                time.sleep(0.1)
    finally:
        progress.configure("quiet")
    lines = buf.getvalue().splitlines()
    assert all(re.match(r"\[\d\d:\d\d:\d\d\] ", x) for x in lines)
    assert "building the reference (10 points) ..." in lines[0]      # plural (was "point")
    beats = [x for x in lines if "... building the reference 30 %" in x]
    assert len(beats) >= 2 and "(3/10 points)" in beats[0]
    assert "building the reference: done in" in lines[-1]


def test_quiet_mode_prints_nothing():
    buf = io.StringIO()
    progress.configure("quiet", stream=buf)
    with progress.step("x"):
        progress.say("y")
    assert buf.getvalue() == ""


def test_a_bench_reports_progress_about_twice_a_second(tmp_path):
    """Called every tick, a bench writes its count at once and then at most every 0.4 s (it
    wrote every 1000 ticks: a Verilator engine sat at 0 % for its first 1000)."""
    import json
    pytest.importorskip("cocotb")
    from cuneate.sim.engines import bench
    cfg = {"progress_file": str(tmp_path / "p.json")}
    bench._last_progress[0] = 0.0
    bench.bench_progress(cfg, 1)
    assert json.loads((tmp_path / "p.json").read_text()) == {"done": 1}
    bench.bench_progress(cfg, 2)                 # within the interval: not written
    assert json.loads((tmp_path / "p.json").read_text()) == {"done": 1}
    bench.bench_progress(cfg, 3, force=True)
    assert json.loads((tmp_path / "p.json").read_text()) == {"done": 3}
