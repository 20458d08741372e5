"""The coincidence block: the second layer's cuneate neurons as coincidence detectors. Afferent
spikes enter a delay-line history, each (target, source) pair has a conduction delay and a
weight, bi-exponential PSPs drive Izhikevich targets; a target fires when delayed inputs
coincide.

``config``    :class:`CoincidenceConfig`
``datapath``  the detector's own stage functions (input sum, PSP current)
``twin``      :class:`CoincidenceTwin`, the bit-exact integer model
``kernel``    the twin's compiled (numba) loop
``core``      :class:`CoincidenceDetector` (Amaranth) and its Verilog

The brain nucleus gives the neurons their name in prose and in scenes (``model = "cuneate"``);
the block, its files and its commands are ``coincidence``.
"""

from .config import (CLAMP_KINDS, CYCLES_PER_TARGET_EXTRA, TRACE_NAMES, CoincidenceConfig,
                     ConfigError)
from .core import (COUNTER_BITS, CoincidenceDetector, coincidence_verilog, generate_coincidence,
                   synth_resources)
from .datapath import accumulate, clamp_bits_hdl, psp_current
from .twin import CoincidenceTwin

__all__ = ["CoincidenceConfig", "ConfigError", "CoincidenceTwin", "CoincidenceDetector",
           "accumulate", "psp_current", "clamp_bits_hdl", "coincidence_verilog",
           "generate_coincidence", "CLAMP_KINDS", "CYCLES_PER_TARGET_EXTRA", "TRACE_NAMES",
           "COUNTER_BITS", "synth_resources"]
