"""Shared pytest fixtures: one build directory tree for all HDL simulator cases, and a headless
browser that renders report pages; :data:`LONG_LANE`, default-lane cases run in the long lane
for the default lane's budget."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from cuneate.sim.engines.toolchain import apply_simulator_env

apply_simulator_env()

#: Cases marked ``long`` here (the long lane, which CI also runs) to keep ``make test`` within
#: its 12 minutes: each repeats on a second simulator, a second variant or a longer run what a
#: case left in the default lane checks (named after each).
LONG_LANE = {
    # Verilator's case; Icarus's stays in the default lane
    "tests/sim/test_coincidence_cocotb.py::test_scoreboard[verilator-brief]",
    "tests/sim/axi/test_cocotb.py::test_axi_face[verilator]",
    "tests/sim/link/test_cocotb.py::test_link_round_trip_and_faults[verilator]",
    "tests/sim/test_network_cocotb.py::test_network_scoreboard[verilator]",
    "tests/sim/test_driver.py::test_cocotb_transport_equals_twin[verilator]",
    "tests/sim/test_nir_cocotb.py::test_scoreboard[verilator]",
    # the ridge scene on Verilator; fixed against golden and the other scenes' HDL engines stay
    "tests/sim/test_scene_ridge.py::test_ridge_scene_on_verilator_equals_fixed",
    # second variants: the other current forms, roundings and spacings stay
    "tests/golden/test_izhikevich_speed.py::test_same_spikes_and_state_mixed_sets_all_current_forms[float64-izhikevich]",
    "tests/hdl/test_izhikevich_kernel.py::test_long_run_equal_spikes_state_and_clamp_accounting[mix-nearest]",
    "tests/hdl/test_network.py::test_rtl_equals_twin_and_every_spike_crosses_the_link_once[spaced-0.3]",
    "tests/sim/test_coincidence_cocotb.py::test_scoreboard[icarus-mixed]",
    "tests/sim/test_izhikevich_cocotb.py::test_scoreboard[icarus-n240_mixed]",
    "tests/sim/test_izhikevich_array_cocotb.py::test_array_check[icarus-k3_n12_depth9]",
    "tests/hdl/test_izhikevich_behaviours.py::test_behaviour_on_golden_and_twin[K]",
    # the verilator-fast engine's equality with fixed (its refusals stay), the published gain's
    # units (the tactile chain's other checks stay)
    "tests/sim/test_verilator_fast.py::test_verilator_fast_engine_equals_fixed_engine",
    "tests/golden/test_tactile.py::test_published_gain_needs_ten_picometre_units",
}


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.nodeid in LONG_LANE:
            item.add_marker(pytest.mark.long)


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
