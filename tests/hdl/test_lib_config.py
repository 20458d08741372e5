"""hdl/lib/config.py: the checks every block's configuration shares, refused the same way by
each configuration type."""

import pytest

from cuneate.hdl.coincidence.config import CoincidenceConfig
from cuneate.hdl.izhikevich.config import IzhikevichConfig
from cuneate.hdl.lib.config import ConfigError, whole_cycles_per_tick
from cuneate.hdl.lif.config import LifConfig
from cuneate.hdl.plasticity.config import PlasticityConfig

CONFIGS = [IzhikevichConfig, LifConfig, CoincidenceConfig, PlasticityConfig]


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("clock_hz, message", [
    (float("nan"), "clock_hz and update_hz must be positive finite numbers"),
    (float("inf"), "clock_hz and update_hz must be positive finite numbers"),
    (-16e3 * 100, "clock_hz and update_hz must be positive finite numbers"),
    (True, "clock_hz and update_hz must be positive finite numbers"),
    (16e3 * 40.5, "clock_hz / update_hz = 648000 / 16000 = 40.5 is not an integer number of "
                  "cycles per update"),
])
def test_every_block_refuses_a_clock_that_is_no_whole_number_of_cycles(config, clock_hz,
                                                                       message):
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(".", r"\.")):
        config(clock_hz=clock_hz, update_hz=16e3)


def test_whole_cycles_per_tick_allows_float_rounding_only():
    assert whole_cycles_per_tick(40e6, 16e3) == 2500
    assert whole_cycles_per_tick(0.1 * 3 * 1e6, 1e5) == 3        # 300000.00000000006 Hz
    with pytest.raises(ConfigError):
        whole_cycles_per_tick(40e6 + 1, 16e3)
    with pytest.raises(ConfigError):
        whole_cycles_per_tick(1e3, 16e3)                         # under one cycle
