"""hdl/lib/config.py: the checks every block's configuration shares, refused the same way by
each configuration type."""

import re

import pytest

from cuneate.hdl.coincidence.config import CoincidenceConfig
from cuneate.hdl.izhikevich.config import IzhikevichConfig
from cuneate.hdl.lib.config import ConfigError, whole_cycles_per_tick
from cuneate.hdl.lif.config import LifConfig
from cuneate.hdl.plasticity.config import PlasticityConfig

CONFIGS = [IzhikevichConfig, LifConfig, CoincidenceConfig, PlasticityConfig]


POSITIVE = "positive finite number"     # "update_hz must be a ...", "... must be ...s"


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("clock_hz, update_hz, message", [
    (float("nan"), 16e3, POSITIVE),
    (float("inf"), 16e3, POSITIVE),
    (-16e3 * 100, 16e3, POSITIVE),
    (True, 16e3, POSITIVE),
    (40e6, float("nan"), POSITIVE),
    (40e6, float("inf"), POSITIVE),
    (40e6, 0.0, POSITIVE),
    (1e300, 1e-10, "= inf is not an integer number of cycles per update"),   # overflows
    (16e3 * 40.5, 16e3, "clock_hz / update_hz = 648000 / 16000 = 40.5 is not an integer "
                        "number of cycles per update"),
])
def test_every_block_refuses_rates_that_are_no_whole_number_of_cycles(config, clock_hz,
                                                                      update_hz, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        config(clock_hz=clock_hz, update_hz=update_hz)


def test_whole_cycles_per_tick_allows_float_rounding_only():
    assert whole_cycles_per_tick(40e6, 16e3) == 2500
    assert whole_cycles_per_tick(0.1 * 3 * 1e6, 1e5) == 3        # 300000.00000000006 Hz
    with pytest.raises(ConfigError):
        whole_cycles_per_tick(40e6 + 1, 16e3)
    with pytest.raises(ConfigError):
        whole_cycles_per_tick(1e3, 16e3)                         # under one cycle
