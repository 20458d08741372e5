"""The Izhikevich block: a pipelined, fixed-point, time-multiplexed Izhikevich core.

One home for everything of the block:

``config``    :class:`IzhikevichConfig`: sizes, rates, parameter sets, every format and constant,
              the refusals of what cannot be held
``range``     the state range proven for the accepted currents, the one-step error bound
``datapath``  the stage functions and the pipelined steps, run by the twin and the RTL alike
``twin``      :class:`IzhikevichTwin`, the bit-exact integer model, and
              :class:`IzhikevichArrayTwin` (one twin per core of an array)
``kernel``    the twin's compiled (numba) loop, proven bit-exact against the stage functions
``core``      :class:`IzhikevichCore` (Amaranth) and its Verilog
``array``     :class:`IzhikevichArray`: cores behind one host write port and one spike stream
``formal``    SymbiYosys checks of the datapath and of the pipeline against it
"""

from .config import CLAMP_KINDS, PIPELINE_DEPTH, SATURATION, ConfigError, IzhikevichConfig
from .core import IzhikevichCore, generate_izhikevich, izhikevich_verilog
from .datapath import clamp_bits, multiply1, multiply2, operands, update_state
from .twin import IzhikevichArrayTwin, IzhikevichTwin
from .array import IzhikevichArray, izhikevich_array_verilog

__all__ = ["ConfigError", "IzhikevichConfig", "IzhikevichTwin", "IzhikevichCore",
           "IzhikevichArray", "IzhikevichArrayTwin", "izhikevich_array_verilog",
           "PIPELINE_DEPTH", "CLAMP_KINDS", "SATURATION", "operands", "multiply1",
           "multiply2", "update_state", "clamp_bits", "izhikevich_verilog",
           "generate_izhikevich"]
