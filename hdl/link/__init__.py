"""The link block: the host link over a UART (COBS frames with a CRC-32, a version and
sequence numbers) between a host and a core on the board.

``config``    :class:`LinkConfig`: link parameters checked against the core they serve
``codec``     the wire format: frames, COBS, messages (the host's codec)
``datapath``  the CRC-32 step, one definition for ints and Amaranth values
``twin``      :class:`LinkModel`: the device's answers on the bit-exact Izhikevich twin
``core``      :class:`HostLink` and :class:`LinkedCore` (Amaranth) and their Verilog
``network``   :class:`LinkedNetwork`: the on-chip afferent -> cuneate network behind the link
``fanout``    :class:`LinkedFanoutCore`, :class:`LinkedFanoutNetwork`: channel samples in, fanned
              out on chip to a core or to the network's afferents
``lif``       :class:`LinkedLif`: a LIF core behind the link
"""

from .codec import (COUNTER_NAMES, MAX_FRAME, MIN_FRAME, CobsError, FrameDecoder, FrameError,
                    Message, decode_frame, encode_frame)
from .config import LinkConfig, link_config
from .core import HostLink, LinkedCore, link_verilog
from .fanout import LinkedFanoutCore, LinkedFanoutNetwork
from .lif import LinkedLif
from .network import LinkedNetwork
from .twin import LinkModel

__all__ = ["LinkConfig", "link_config", "HostLink", "LinkedCore", "LinkedNetwork",
           "LinkedFanoutCore", "LinkedFanoutNetwork", "LinkedLif", "link_verilog",
           "COUNTER_NAMES", "MAX_FRAME", "MIN_FRAME", "CobsError", "FrameError", "FrameDecoder",
           "LinkModel", "Message", "encode_frame", "decode_frame"]
