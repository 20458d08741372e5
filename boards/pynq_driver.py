"""PYNQ driver of a cuneate block behind the AXI face in a Zynq overlay (the block design that
``cuneate build arty_z7|pynq_z2`` writes beside this file). Standalone: it needs numpy and,
on the board, pynq; the register map is read from ``src/<name>.regmap.json`` beside it.

    from pynq import Overlay
    from cuneate_pynq_z2_pynq import CuneateCore
    ov = Overlay("cuneate_pynq_z2_bd.bit")          # the .hwh of the same name beside it
    core = CuneateCore(ov.core.mmio, ov.dma, "src/cuneate_pynq_z2.regmap.json")
    core.check()                                     # ID and the map's major version
    core.write(0, currents)                          # raw values in VALUE_FORMAT, one burst
    core.step(1)                                     # one sweep
    sweep, ids = core.read_sweep()                   # its spikes (one S2MM packet)
    core.counters()

Streams (the register map's ``streams``): a write beat holds the raw value sign-extended in
its low field and the address in its high field; a spike beat the id in its low field and
the sweep number in its high field; a sweep ends with TLAST (an AXI DMA S2MM transfer ends
there: one transfer a sweep), an empty sweep sends one marker beat (id all ones). Not run on
a board here.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

__all__ = ["CuneateCore", "pack_writes", "unpack_spikes", "MAGIC", "MAJOR"]

#: ``ID``: the bytes "cune" as a little-endian word; the register map's major version
MAGIC = int.from_bytes(b"cune", "little")
MAJOR = 1
_DTYPES = {2: np.uint32, 4: np.uint64}


def pack_writes(streams: dict, first: int, raw) -> np.ndarray:
    """Write beats for the raw values ``raw`` at addresses ``first``, ``first + 1``, ...:
    one element per beat (``write_tdata_bits`` wide)."""
    fb = streams["write_field_bytes"]
    if fb not in _DTYPES:
        raise ValueError(f"write beats of {16 * fb} bits: no numpy integer holds them")
    F = np.uint64(8 * fb)
    v = np.asarray(raw, dtype=np.int64).astype(np.uint64) & np.uint64((1 << (8 * fb)) - 1)
    a = np.arange(first, first + len(v), dtype=np.uint64) << F
    return (v | a).astype(_DTYPES[fb])


def unpack_spikes(streams: dict, beats) -> tuple[int, list[int]]:
    """A sweep's packet of spike beats -> ``(sweep number, ids)`` (``[]`` for an empty
    sweep's marker). Raises ``ValueError`` on a packet mixing sweeps or a marker among
    spikes."""
    F = 8 * streams["spike_field_bytes"]
    b = [int(x) for x in beats]
    sweeps = {x >> F for x in b}
    if len(sweeps) != 1:
        raise ValueError(f"a packet of sweeps {sorted(sweeps)}")
    ids = [x & ((1 << F) - 1) for x in b]
    if streams["marker_id"] in ids:
        if len(ids) != 1:
            raise ValueError("an empty sweep's marker among spikes")
        ids = []
    return sweeps.pop(), ids


class CuneateCore:
    """The block through ``mmio`` (``read(offset)``, ``write(offset, value)``: pynq's
    ``MMIO``) and ``dma`` (pynq's ``DMA``: ``sendchannel``, ``recvchannel``); ``regmap`` the
    path of the register map JSON (or its data)."""

    def __init__(self, mmio, dma, regmap, allocate=None):
        self.mmio, self.dma = mmio, dma
        if not isinstance(regmap, dict):
            regmap = json.loads(Path(regmap).read_text())
        self.map = regmap
        self.offset = {r["name"]: r["offset"] for r in regmap["registers"]}
        self.streams = regmap["streams"]
        if allocate is None:
            from pynq import allocate
        self._allocate = allocate

    def read(self, name: str) -> int:
        return int(self.mmio.read(self.offset[name]))

    def write_reg(self, name: str, value: int) -> None:
        self.mmio.write(self.offset[name], int(value))

    def check(self) -> None:
        """Raise ``RuntimeError`` unless the core answers with the map this driver reads."""
        ident, version = self.read("ID"), self.read("VERSION")
        if ident != MAGIC or version >> 16 != MAJOR:
            raise RuntimeError(f"not a cuneate core of map {MAJOR}.x: ID {ident:#x}, "
                               f"VERSION {version:#x}")

    def write(self, first: int, raw) -> None:
        """One burst of raw values (their sweep: the next one started)."""
        beats = pack_writes(self.streams, first, raw)
        buf = self._allocate(shape=beats.shape, dtype=beats.dtype)
        buf[:] = beats
        self.dma.sendchannel.transfer(buf)
        self.dma.sendchannel.wait()

    def step(self, n: int = 1) -> None:
        """Run ``n`` sweeps, then stop."""
        self.write_reg("STEP", n)

    def read_sweep(self, max_spikes: int | None = None) -> tuple[int, list[int]]:
        """The next sweep's spikes: ``(sweep number, ids)``."""
        n = max_spikes or self.map["registers"][[r["name"] for r in self.map["registers"]]
                                                .index("N_SPIKE_IDS")]["value"]
        dtype = _DTYPES[self.streams["spike_field_bytes"]]
        buf = self._allocate(shape=(max(int(n), 1),), dtype=dtype)
        self.dma.recvchannel.transfer(buf)
        self.dma.recvchannel.wait()
        got = int(self.dma.recvchannel.transferred) // np.dtype(dtype).itemsize
        return unpack_spikes(self.streams, buf[:got])

    def counters(self) -> dict:
        """The face's counters by name."""
        names = [r["name"] for r in self.map["registers"] if r["offset"] >= 0x60]
        return {n.lower(): self.read(n) for n in names}
