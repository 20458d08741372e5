"""A NIR network on chip: a chain of LIF cores sharing one tick (the hardware a NIR graph is
mapped onto by :mod:`cuneate.sim.nir`).

``config``  :class:`NirNetworkConfig` (one :class:`~cuneate.hdl.lif.LifConfig` per layer)
``twin``    :class:`NirNetworkTwin`, the bit-exact model (one LIF twin per layer)
``core``    :class:`NirNetwork` (Amaranth) and its Verilog
"""

from .config import ConfigError, NirNetworkConfig
from .core import NirNetwork, generate_nir_network, nir_network_verilog
from .twin import NetworkRun, NirNetworkTwin

__all__ = ["ConfigError", "NirNetworkConfig", "NirNetwork", "NirNetworkTwin", "NetworkRun",
           "generate_nir_network", "nir_network_verilog"]
