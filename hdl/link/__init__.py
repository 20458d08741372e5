"""The UART face: the host link over a UART (COBS frames with a CRC-32, a version and
sequence numbers) between a host and any block behind it on the board.

``config``    :class:`LinkConfig`: link parameters checked against the payload they serve
``codec``     the wire format: frames, COBS, messages (the host's codec)
``datapath``  the CRC-32 step, one definition for ints and Amaranth values
``decoder``, ``executor``, ``batcher``, ``encoder``
              the link's stream components (frames in, writes out; spikes in, frames out)
``core``      :class:`HostLink` (the components and a UART) and :class:`LinkedTop` (a block's
              payload behind it: every board top), and their Verilog
``twin``      :class:`LinkModel`: the device's answers on the block's bit-exact twin
``formal_core``  the k-induction of the decoder and executor against the wire format
"""

from .codec import (COUNTER_NAMES, MAX_FRAME, MIN_FRAME, CobsError, FrameDecoder, FrameError,
                    Message, decode_frame, encode_frame)
from .config import LinkConfig, link_config
from .core import HostLink, LinkedTop, link_verilog
from .twin import LinkModel

__all__ = ["LinkConfig", "link_config", "HostLink", "LinkedTop", "link_verilog",
           "COUNTER_NAMES", "MAX_FRAME", "MIN_FRAME", "CobsError", "FrameError", "FrameDecoder",
           "LinkModel", "Message", "encode_frame", "decode_frame"]
