"""The brief's LIF experiments: the 3x3 skin on every engine and the quantization table."""

import numpy as np
import pytest

from cuneate.sim.lif.experiments import quantization_table, skin_3x3
from cuneate.sim.engines.toolchain import SIMULATORS


@pytest.fixture(scope="module")
def skin_fixed():
    return skin_3x3("fixed")


@pytest.mark.parametrize("engine", ["golden", "fixed", "amaranth"])
def test_skin_behaves_as_stated(engine, skin_fixed):
    r = skin_3x3(engine)
    assert r.width_monotonic and r.amplitude_monotonic
    assert r.pressed_wins and r.counts[1, 1] > 0
    assert r.row_sums == r.col_sums and r.row_sums[0] == r.row_sums[2]   # symmetric press
    if engine == "golden":
        assert np.all(np.abs(r.counts - skin_fixed.counts) <= 1)
    else:
        assert r.spikes_ms == skin_fixed.spikes_ms


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_skin_on_hdl_simulators(simulator, skin_fixed, tmp_path):
    r = skin_3x3(simulator, build_dir=tmp_path)
    assert r.spikes_ms == skin_fixed.spikes_ms
    assert r.width_monotonic and r.amplitude_monotonic and r.pressed_wins


def test_skin_corner_press_wins():
    r = skin_3x3("fixed", pressed=0)
    assert r.winner == 0 and r.row_sums[0] > r.row_sums[2] and r.col_sums[0] > r.col_sums[2]


def test_quantization_error_grows_as_bits_drop():
    rows = {r.weights: r for r in quantization_table(seed=1)}
    fp, i8, i4 = rows["FP32"], rows["INT8"], rows["INT4"]
    assert fp.count_error_mean == 0 and fp.vp_mean == 0
    assert 0 < i8.weight_rms_error < i4.weight_rms_error
    assert i8.count_error_rel < i4.count_error_rel and i8.vp_mean < i4.vp_mean
    assert i8.count_error_rel < 0.05
