"""Shared pytest fixtures: one build directory tree for all HDL simulator cases."""

import os
from pathlib import Path

import pytest

from cuneate.sim.toolchain import apply_simulator_env

apply_simulator_env()


@pytest.fixture(scope="session")
def build_root() -> Path:
    """Root of per-case simulator build directories (``CUNEATE_BUILD_DIR`` or ``build/tests``)."""
    root = Path(os.environ.get("CUNEATE_BUILD_DIR", Path(__file__).resolve().parents[1]
                               / "build" / "tests"))
    root.mkdir(parents=True, exist_ok=True)
    return root
