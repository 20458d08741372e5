"""Shared pytest fixtures: one build directory tree for all HDL simulator cases, and a headless
browser that renders report pages."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from cuneate.sim.engines.toolchain import apply_simulator_env

apply_simulator_env()


@pytest.fixture(scope="session")
def build_root() -> Path:
    """Root of per-case simulator build directories (``CUNEATE_BUILD_DIR`` or ``build/tests``)."""
    root = Path(os.environ.get("CUNEATE_BUILD_DIR", Path(__file__).resolve().parents[1]
                               / "build" / "tests"))
    root.mkdir(parents=True, exist_ok=True)
    return root


def _render(page: Path):
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail("chromium is not installed (make setup installs it from apt)")
    proc = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu",
                           "--enable-logging=stderr", "--v=0", "--virtual-time-budget=3000",
                           "--dump-dom", page.as_uri()],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout, [ln for ln in proc.stderr.splitlines() if ":CONSOLE" in ln]


@pytest.fixture
def chromium():
    """``chromium(page) -> (dom, console_lines)``: the page rendered by headless Chromium and
    the messages it logged to the console."""
    return _render
