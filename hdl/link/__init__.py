"""The link block: the host link over a UART (COBS frames with a CRC and sequence numbers)
between a host and a core on the board.

``codec``  the wire format: frames, CRC, COBS, messages (host codec and bit-exact model)
``core``   :class:`HostLink` and :class:`LinkedCore` (Amaranth) and their Verilog
"""

from .codec import (COUNTER_NAMES, MAX_FRAME, MIN_FRAME, CobsError, FrameDecoder, FrameError,
                    LinkModel, Message, decode_frame, encode_frame)
from .core import HostLink, LinkConfig, LinkedCore, link_config, link_verilog

__all__ = ["LinkConfig", "link_config", "HostLink", "LinkedCore", "link_verilog",
           "COUNTER_NAMES", "MAX_FRAME", "MIN_FRAME", "CobsError", "FrameError", "FrameDecoder",
           "LinkModel", "Message", "encode_frame", "decode_frame"]
