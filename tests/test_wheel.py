"""The built wheel works on its own: every module and data file the package needs is in it.

The source tree (as git sees it: tracked and new, not ignored) is copied to a scratch directory,
built into a wheel, and the wheel installed (without dependencies) into a fresh virtual
environment that borrows the test environment's third-party packages through a path entry (the
editable install of the project itself is not visible there). ``cuneate doctor`` and a short
``cuneate simulate`` on the bit-exact twin and on the Verilator harness (whose C++ source is
package data) must then work from the installed wheel: an editable install hides files the
wheel would miss.
"""

from __future__ import annotations

import json
import shutil
import site
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _source_files() -> list[str]:
    r = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT,
                       capture_output=True, text=True)
    if r.returncode != 0:
        pytest.fail(f"git ls-files failed: {r.stderr}")
    return [f for f in r.stdout.splitlines() if (ROOT / f).is_file()]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    base = tmp_path_factory.mktemp("wheel")
    src = base / "src"
    for f in _source_files():
        dst = src / f
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / f, dst)
    dist = base / "dist"
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                        "--no-build-isolation", "-q", "-w", str(dist), str(src)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    wheel = next(dist.glob("cuneate-*.whl"))
    env_dir = base / "venv"
    venv.EnvBuilder(with_pip=True).create(env_dir)
    py = env_dir / "bin" / "python"
    r = subprocess.run([str(py), "-m", "pip", "install", "--no-deps", "--no-index", "-q",
                        str(wheel)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    # third-party packages from the test environment (paths only: its .pth files, among them
    # the editable install of this project, are not processed)
    target = Path(subprocess.run([str(py), "-c", "import sysconfig; "
                                  "print(sysconfig.get_paths()['purelib'])"],
                                 capture_output=True, text=True).stdout.strip())
    deps = [sysconfig.get_paths()["purelib"], *site.getsitepackages()]
    (target / "cuneate-test-deps.pth").write_text("\n".join(dict.fromkeys(deps)) + "\n")
    return env_dir, wheel, base


def _run(env_dir: Path, cwd: Path, *args) -> subprocess.CompletedProcess:
    return subprocess.run([str(env_dir / "bin" / "cuneate"), *args], cwd=cwd,
                          capture_output=True, text=True, timeout=900)


def test_the_wheel_holds_every_package_and_data_file(installed):
    import zipfile
    _, wheel, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    for f in ("cuneate/__init__.py", "cuneate/hdl/izhikevich/core.py",
              "cuneate/sim/scenes/examples/ridge_angle.toml", "cuneate/sim/engines/harness.cpp",
              "cuneate/boards/ulx3s.py", "cuneate/golden/coincidence.py"):
        assert f in names, f
    # every C++ harness and header the package compiles at run time (the board engine's serial
    # harness was missing: package data named sim/engines alone)
    harnesses = [f for f in _source_files() if f.endswith((".cpp", ".h"))
                 and not f.startswith(("tests/", "benchmarks/", "scripts/"))]
    assert {"sim/link/serial_harness.cpp", "sim/engines/batch_harness.h"} <= set(harnesses)
    assert [f for f in harnesses if f"cuneate/{f}" not in names] == []
    assert not any(n.startswith(("cuneate/tests/", "cuneate/benchmarks/")) for n in names)


# the long lane (CI): builds and installs the wheel in a fresh environment
@pytest.mark.long
def test_installed_wheel_runs_doctor_and_simulate(installed):
    env_dir, _, base = installed
    r = _run(env_dir, base, "doctor", "--json")
    assert r.returncode == 0, r.stdout + r.stderr
    assert json.loads(r.stdout)["ok"] is True
    r = subprocess.run([str(env_dir / "bin" / "python"), "-c",
                        "import cuneate; print(cuneate.__file__, cuneate.__version__)"],
                       cwd=base, capture_output=True, text=True)
    assert str(env_dir) in r.stdout, r.stdout + r.stderr         # the wheel, not the checkout
    runs = {}
    for engine in ("fixed", "verilator-fast"):
        r = _run(env_dir, base, "simulate", "izhikevich", "--engine", engine, "--current", "10",
                 "--duration-ms", "200", "--json")
        assert r.returncode == 0, r.stderr
        runs[engine] = json.loads(r.stdout)["spikes_ms"]
    assert runs["fixed"] == runs["verilator-fast"] and len(runs["fixed"][0]) > 0
    r = _run(env_dir, base, "run", "--list-examples")
    assert r.returncode == 0 and "examples/ridge_angle.toml" in r.stdout


@pytest.mark.long
def test_installed_wheel_runs_the_board_engine(installed):
    """The default scene on the board engine from the wheel: its serial harness (package data)
    compiled with the board top, the host stack on a simulated line; the board's 80 trains
    equal the twin's. About 25 s with the model in the build cache, a minute or two without."""
    env_dir, _, base = installed
    r = _run(env_dir, base, "-q", "run", "--engines", "fixed,board", "--out",
             str(base / "board"), "--json")
    assert r.returncode == 0, r.stderr[-2000:]
    agreement = json.loads(r.stdout)["agreement"]
    pair = next(v for k, v in agreement.items() if "board" in k)
    assert pair["identical_trains"] == pair["neurons"] == 80, agreement
