"""The network block: afferents on an Izhikevich core feeding a coincidence detector on chip, one
tick for both, one host current port and one population-tagged spike stream.

``config``  :class:`NetworkConfig`
``twin``    :class:`NetworkTwin` (the two blocks' twins on one tick)
``core``    :class:`AfferentCuneateNetwork` (Amaranth) and its Verilog

The network has no arithmetic of its own (its blocks' datapaths do the work), hence no datapath
or kernel file.
"""

from .config import POPULATIONS, SWEEP_EXTRA, ConfigError, NetworkConfig
from .core import (COUNTER_BITS, REPORT_SETTLE, AfferentCuneateNetwork, generate_network,
                   network_verilog, synth_resources)
from .twin import NetworkTwin

__all__ = ["NetworkConfig", "NetworkTwin", "AfferentCuneateNetwork", "ConfigError",
           "network_verilog", "generate_network", "POPULATIONS", "SWEEP_EXTRA", "COUNTER_BITS",
           "REPORT_SETTLE", "synth_resources"]
