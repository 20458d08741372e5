"""The LIF block: a pipelined, fixed-point, time-multiplexed leaky integrate-and-fire core
(continuous form by exact exponential decay, or the discrete u[t] = alpha u[t-1] + sum w x),
with a weight memory for input spikes and optional AMPA/GABA synaptic traces.

``config``    :class:`LifConfig` and the parameter sets (:class:`LifSet`)
``datapath``  the stage functions, run by the twin and the RTL alike
``twin``      :class:`LifTwin`, the bit-exact integer model
``kernel``    the twin's compiled (numba) loop
``core``      :class:`LifCore` (Amaranth) and its Verilog
"""

from .config import (CLAMP_KINDS, DECAYS, FORMS, PIPELINE_DEPTH, SATURATION, ConfigError,
                     LifConfig, LifSet)
from .core import LifCore, generate_lif, lif_verilog
from .datapath import clamp_bits, gather_input, leak_operand, leak_product, update_state
from .twin import LifTwin

__all__ = ["ConfigError", "LifConfig", "LifSet", "LifTwin", "LifCore", "PIPELINE_DEPTH",
           "CLAMP_KINDS", "FORMS", "DECAYS", "SATURATION", "gather_input", "leak_operand",
           "leak_product", "update_state", "clamp_bits", "lif_verilog", "generate_lif"]
