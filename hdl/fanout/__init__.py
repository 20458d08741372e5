"""The channel fan-out block: per-channel sensor samples in, the currents of every afferent that
listens to them out, into a core's current memory. The host streams a few dozen channels (one
per grating, or its band-passed signal) instead of one current per afferent.

``config``    :class:`FanoutConfig`
``datapath``  the stage functions (rectify and gate, product, rounded and flagged current)
``twin``      :class:`FanoutTwin`, the bit-exact integer model
``core``      :class:`ChannelFanout` (Amaranth) and its Verilog

The float64 reference is :func:`cuneate.golden.fanout.fanout_currents`. The twin is a vector
expression over the table (no loop to compile), so the block has no ``kernel``.
"""

from .config import CLAMP_KINDS, LATENCY, RECTIFY, ConfigError, FanoutConfig
from .core import COUNTER_BITS, ChannelFanout, fanout_verilog, generate_fanout
from .datapath import product, rectify_gate, to_current
from .twin import FanoutTwin

__all__ = ["FanoutConfig", "ConfigError", "FanoutTwin", "ChannelFanout", "fanout_verilog",
           "generate_fanout", "rectify_gate", "product", "to_current", "CLAMP_KINDS", "LATENCY",
           "RECTIFY", "COUNTER_BITS"]
