"""The Verilator build cache: one compile per design, reused from any build directory."""

import json

import numpy as np
import pytest

from cuneate.sim.engines import cocotb as runner
from cuneate.sim.lif.engines import LifProgram, engine_config, run_lif


def _run(build_dir, current=25.0, n=8):
    cfg = engine_config({"update_hz": 1000.0}, n)
    return run_lif("verilator", cfg, LifProgram.constant(np.full(n, current), 40),
                   build_dir=build_dir)


# the long lane (CI): compiles a Verilator model twice
@pytest.mark.long
@pytest.mark.cocotb
def test_verilator_model_is_built_once_and_reused(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("CUNEATE_SIM_CACHE", str(cache))
    a = _run(tmp_path / "a")
    entries = list(cache.glob("verilator-lif_core-*"))
    assert len(entries) == 1
    stamp = entries[0] / "built.json"
    assert json.loads(stamp.read_text())["toplevel"] == "lif_core"
    binary = entries[0] / "lif_core"
    built_at = binary.stat().st_mtime_ns
    b = _run(tmp_path / "b")
    # the second run used the cached model: no new entry, the binary untouched, no model in
    # the run's own directory, and the same spikes
    assert list(cache.glob("verilator-lif_core-*")) == entries
    assert binary.stat().st_mtime_ns == built_at
    assert not (tmp_path / "b" / "lif_core").exists() and (tmp_path / "b").is_dir()
    assert a.spikes_ms == b.spikes_ms and sum(map(len, a.spikes_ms)) > 0
    # another design: a new entry, built on the runtime library the first build kept (copied
    # in before Verilator wrote the entry's makefile, and not recompiled after it)
    c = _run(tmp_path / "c", n=9)
    new = [e for e in cache.glob("verilator-lif_core-*") if e not in entries]
    assert len(new) == 1
    kept = list(cache.glob("runtime-*"))
    assert len(kept) == 1
    for obj in runner.RUNTIME_OBJECTS:
        copied = new[0] / f"{obj}.o"
        assert copied.read_bytes() == (kept[0] / f"{obj}.o").read_bytes()
        assert copied.stat().st_mtime_ns < (new[0] / "Vtop.mk").stat().st_mtime_ns
    assert c.spikes_ms[:8] == a.spikes_ms and sum(map(len, c.spikes_ms)) > 0


@pytest.mark.long
@pytest.mark.cocotb
def test_cache_off_builds_in_the_run_directory(tmp_path, monkeypatch):
    monkeypatch.setenv("CUNEATE_SIM_CACHE", "off")
    assert runner.sim_cache_root() is None
    _run(tmp_path / "run")
    assert list((tmp_path / "run").rglob("lif_core")) != []


def test_cache_key_follows_the_design(tmp_path):
    v1 = tmp_path / "a.v"
    v1.write_text("module m; endmodule\n")
    k = runner._cache_key([v1], "m", ["-O3"], False)
    # the same bytes under the same file name in another directory: the same model
    same_name = tmp_path / "x"
    same_name.mkdir()
    (same_name / "a.v").write_text("module m; endmodule\n")
    assert runner._cache_key([same_name / "a.v"], "m", ["-O3"], False) == k
    (same_name / "a.v").write_text("module m; wire w; endmodule\n")
    assert runner._cache_key([same_name / "a.v"], "m", ["-O3"], False) != k
    assert runner._cache_key([v1], "m", ["-O2"], False) != k
    assert runner._cache_key([v1], "m", ["-O3"], True) != k
    assert runner._cache_key([v1], "top", ["-O3"], False) != k
