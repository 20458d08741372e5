"""The link's datapath step: the CRC-32 register (ISO-HDLC, reflected) one byte at a time,
written once for ints (host codec, device model) and Amaranth values (gateware).

The step is linear over GF(2) in (register, byte); the gateware's XOR trees are derived from
the bitwise definition, so the RTL cannot disagree with the model."""

from __future__ import annotations

__all__ = ["crc32_update", "crc32_table"]


_POLY_REFLECTED = 0xEDB88320      # 0x04C11DB7 with its bits reversed (LSB-first register)


def _crc32_step_int(crc: int, byte: int) -> int:
    crc ^= byte
    for _ in range(8):
        crc = (crc >> 1) ^ _POLY_REFLECTED if crc & 1 else crc >> 1
    return crc


# The step is linear over GF(2) in (crc, byte): output bit i is the XOR of the input bits in
# _CRC_TAPS[i] (bits 0-31 of crc, then bits 0-7 of the byte as 32-39), derived from the
# bitwise definition above so that the RTL cannot disagree with it.
_CRC_TAPS = tuple(
    tuple(j for j in range(40)
          if (_crc32_step_int(1 << j if j < 32 else 0, 1 << (j - 32) if j >= 32 else 0)
              >> i) & 1)
    for i in range(32))
# the step on the byte values, for the host's byte loop (crc32_table): step(crc, b) is
# (crc >> 8) ^ _CRC_TABLE[(crc ^ b) & 0xFF] because the step is linear
_CRC_TABLE = tuple(_crc32_step_int(i, 0) for i in range(256))


def crc32_update(crc, byte):
    """CRC-32 register (32 bits, reflected: LSB first) after one more byte; no init, no final
    xor. On ints: the bitwise definition; on Amaranth values: one XOR tree per output bit from
    the same definition (the gateware uses this function)."""
    from amaranth.hdl import Cat
    from ..lib.fixed import is_hdl
    if not (is_hdl(crc) or is_hdl(byte)):
        return _crc32_step_int(int(crc), int(byte))
    bits = Cat(crc, byte)
    out = []
    for taps in _CRC_TAPS:
        x = bits[taps[0]]
        for t in taps[1:]:
            x = x ^ bits[t]
        out.append(x)
    return Cat(*out)




def crc32_table() -> tuple[int, ...]:
    """The step on byte values: ``crc32_update(crc, b) == (crc >> 8) ^ table[(crc ^ b) & 0xFF]``
    because the step is linear."""
    return _CRC_TABLE
