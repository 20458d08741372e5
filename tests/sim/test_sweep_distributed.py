"""A sweep on a real dask.distributed cluster: a ``dask scheduler`` and two ``dask worker``
processes on 127.0.0.1, reached through ``--scheduler tcp://127.0.0.1:PORT``."""

import json
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cuneate.sim.cli import main

ACCURACY = ("status", "reference_spikes", "spikes", "counts_equal", "count_error",
            "fraction_within_tick", "mean_vp", "vs_euler_fraction_within_tick",
            "neurons_per_core", "multipliers", "state_bits", "updates_per_bio_s")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_workers(address: str, n: int, timeout_s: float = 120.0) -> None:
    from dask.distributed import Client
    with Client(address, timeout=timeout_s) as c:
        c.wait_for_workers(n, timeout=timeout_s)


@pytest.mark.long
def test_sweep_on_a_real_scheduler_and_two_workers_equals_sync(tmp_path):
    dask = Path(sys.executable).with_name("dask")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port",
                               str(port), "--dashboard-address", ":0"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        time.sleep(1.0)
        for i in range(2):
            procs.append(subprocess.Popen([str(dask), "worker", address, "--nthreads", "1",
                                           "--nworkers", "1", "--name", f"w{i}",
                                           "--dashboard-address", ":0"],
                                          stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL))
        _wait_for_workers(address, 2)
        argv = ["--update-hz", "8000,16000", "--operand-width", "18", "--duration-ms", "200",
                "--no-float"]
        assert main(["-q", "sweep", "--out", str(tmp_path / "d"), "--scheduler", address]
                    + argv) == 0
        assert main(["-q", "sweep", "--out", str(tmp_path / "s"), "--scheduler", "sync"]
                    + argv) == 0
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait(timeout=30)
    dist = json.loads((tmp_path / "d" / "sweep.json").read_text())["rows"]
    sync = json.loads((tmp_path / "s" / "sweep.json").read_text())["rows"]
    assert [r["label"] for r in dist] == [r["label"] for r in sync] and len(dist) == 2
    for a, b in zip(dist, sync):
        assert a["status"] == "ok"
        assert {k: a.get(k) for k in ACCURACY} == {k: b.get(k) for k in ACCURACY}
    # two points on two workers run alongside each other: their host time says so
    assert all(r["host_time"].startswith("alongside") for r in dist)
    assert all(r["host_time"] == "one point at a time" for r in sync)
