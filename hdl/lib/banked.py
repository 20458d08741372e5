"""Per-neuron memories read a cycle ahead into a register beside each block RAM.

A block RAM's data output is slow: on the ECP5 a DP16KD without its output register takes
5.6-5.8 ns from the clock to its data, and a memory deeper than one block adds the
multiplexer that picks the block. :func:`prefetched_memory` therefore splits a memory into
**banks** of one block-RAM shape's depth (each bank maps onto whole blocks with nothing after
them), addresses every bank one cycle ahead (``read_addr`` is the address of the neuron issued
in the *next* cycle) and registers each bank's data in the cycle it leaves the RAM. That
register has only the RAM before it, so the ECP5 flow moves it into the DP16KD's own output
register (:mod:`cuneate.hdl.flow.ecp5_pack`); the bank multiplexer and, for a host-written
memory, the write bypass then act in the following cycle, between registers.

Timing, for the neuron issued (fetched) in cycle ``f``: its address is on ``read_addr`` in
``f - 1``; the RAM samples it at the end of ``f - 1``; the bank registers hold its word in
``f + 1``, where :attr:`PrefetchedMemory.data` (combinational from them) is valid - the cycle
in which a plain synchronous read at ``f`` would have its data. So a core swaps this in for a
synchronous read port without moving any stage. Two things differ from a read at ``f``:

* a write landing at the end of ``f - 1`` is not yet in the sampled word: with
  ``bypass=True`` the write is compared with the address and its data replaces the RAM's, so
  an update still sees the memory as it is in its fetch cycle;
* a word written by the pipeline itself must land by then: a core whose write-back of a
  neuron is issued ``D - 1`` cycles after its fetch (and lands at the end of that cycle, or
  of the next with ``write_register``) reads the neuron again a cycle ahead of
  ``f + n_neurons``, so it needs ``n_neurons >= D`` (``D + 1`` with the register), the
  write landing with the read bypassed.

**Read from the fetch's register** (the deepest pipelines): ``read_addr`` may instead be the
fetch's own registered address. Every bank then samples at the end of ``f``, its word is
valid in ``f + 2`` (a stage later) and the block RAMs' address pins are driven from a
register, not from the issue's multiplexers. With every write registered too
(``write_register``), such a memory samples and takes writes exactly a cycle later than one
read ahead, so what an update sees is unchanged: a write issued in ``f - 1`` lands as the
word is sampled and is bypassed into it, one issued in ``f`` lands after.

Bank shape: the block shape (``(depth, width)`` of the device's block RAM, e.g. the DP16KD's
:data:`DP16KD_SHAPES`) with the fewest whole blocks for the memory, the deeper on a tie (fewer
banks); one bank of the memory's own depth when it fits a block's depth. The last bank is
padded to the bank depth, so each bank is whole blocks. The first bank keeps the memory's name
(a one-bank memory is the same memory as before), the others add ``_<bank>``.
"""

from __future__ import annotations

import math

from amaranth import Array, Module, Mux, Shape, Signal
from amaranth.lib.memory import Memory

__all__ = ["DP16KD_SHAPES", "block_shapes", "bank_shape", "blocks_for", "PrefetchedMemory",
           "prefetched_memory", "bank_word"]

#: ``(depth, width)`` modes of the ECP5 DP16KD (18 Kbit), the default block shape
DP16KD_SHAPES = ((16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36))


def block_shapes(shapes) -> tuple | None:
    """``shapes`` as a tuple of ``(depth, width)`` integer pairs, or None when they are not
    positive integers with power-of-two depths (or there are none)."""
    try:
        out = tuple((int(d), int(w)) for d, w in shapes)
        ok = bool(out) and all(d > 0 and w > 0 and d & (d - 1) == 0 and (d, w) == (dd, ww)
                               for (d, w), (dd, ww) in zip(out, shapes))
    except (TypeError, ValueError):
        return None
    return out if ok else None


def blocks_for(depth: int, width: int, shape) -> int:
    """Whole blocks of ``shape`` (``(depth, width)``) for a ``depth`` x ``width`` memory."""
    d, w = shape
    return math.ceil(depth / d) * math.ceil(width / w)


def bank_shape(depth: int, width: int, shapes) -> tuple:
    """``(block shape, blocks)``: the shape with the fewest whole blocks for a ``depth`` x
    ``width`` memory (the deeper on a tie)."""
    return min(((tuple(s), blocks_for(depth, width, s)) for s in shapes),
               key=lambda sb: (sb[1], -sb[0][0]))


class PrefetchedMemory:
    """What :func:`prefetched_memory` built: ``data`` (the word of the neuron fetched two
    cycles before, see the module docstring), ``wr_addr``/``wr_data``/``wr_en`` (the write the
    owner drives), ``banks`` (the :class:`~amaranth.lib.memory.Memory` of each bank) and
    ``bank_depth``."""

    def __init__(self, data, wr_addr, wr_data, wr_en, banks, bank_depth, pending=None):
        self.data, self.banks, self.bank_depth = data, banks, bank_depth
        self.wr_addr, self.wr_data, self.wr_en = wr_addr, wr_data, wr_en
        #: ``(en, addr, data)`` of the registered write on its way to the RAM
        #: (``write_register``), else None
        self.pending = pending


def bank_word(words, bank):
    """The registered word of bank ``bank`` among ``words`` (one per bank)."""
    return Array(words)[bank]


def prefetched_memory(m: Module, name: str, shape, depth: int, init, read_addr, shapes,
                      bypass: bool = False, write_register: bool = False,
                      attrs: dict | None = None, pick=bank_word) -> PrefetchedMemory:
    """A ``depth``-word memory of ``shape`` (an Amaranth shape or a width; signed words stay
    signed) in banks of the best of ``shapes``, read at
    ``read_addr`` (one cycle ahead) into a register per bank; ``init`` its initial words;
    ``bypass``: a write landing as the word is sampled replaces it (host-written memories);
    ``write_register``: the write (address, data, enable) is registered before the RAM, so it
    lands a cycle later (the state's write-back: the result's routing to the block RAM gets
    a cycle of its own); ``pick``: how the word is chosen among the banks' registered words
    by the bank index (:func:`bank_word`; a proof's mutant passes a wrong one). See the module
    docstring for the timing.

    Every bank carries ``no_rw_check``: the word a block RAM returns while the other port
    writes the same address is never used (the state memory is not read then; a host
    memory's bypass replaces it), so synthesis adds no collision logic after the RAM."""
    shape = Shape.cast(shape)
    width = shape.width
    (bank_d, _), _ = bank_shape(depth, width, shapes)
    n_banks = math.ceil(depth / bank_d)
    if n_banks == 1:
        bank_d = depth
    lo_bits = (bank_d - 1).bit_length() if n_banks > 1 else None
    init = list(init)
    wr_addr = Signal(range(depth), name=f"{name}_wr_addr")
    wr_data = Signal(shape, name=f"{name}_wr_data")
    wr_en = Signal(name=f"{name}_wr_en")
    ram_addr, ram_data, ram_en = wr_addr, wr_data, wr_en
    if write_register:
        ram_addr = Signal(range(depth), name=f"{name}_wr_addr_r", reset_less=True)
        ram_data = Signal(shape, name=f"{name}_wr_data_r", reset_less=True)
        ram_en = Signal(name=f"{name}_wr_en_r")
        m.d.sync += [ram_addr.eq(wr_addr), ram_data.eq(wr_data), ram_en.eq(wr_en)]
    banks, words = [], []
    for b in range(n_banks):
        mem = Memory(shape=shape, depth=bank_d, init=init[b * bank_d:(b + 1) * bank_d],
                     attrs={**(attrs or {}), "no_rw_check": 1})
        m.submodules[name if b == 0 else f"{name}_{b}"] = mem
        rd, wr = mem.read_port(), mem.write_port()
        if lo_bits is None:
            m.d.comb += [rd.addr.eq(read_addr), wr.addr.eq(ram_addr), wr.en.eq(ram_en)]
        else:
            m.d.comb += [rd.addr.eq(read_addr[:lo_bits]), wr.addr.eq(ram_addr[:lo_bits]),
                         wr.en.eq(ram_en & (ram_addr[lo_bits:] == b))]
        m.d.comb += [wr.data.eq(ram_data), rd.en.eq(1)]
        q = Signal(shape, name=f"{name}_q{b}", reset_less=True)    # beside the block RAM
        m.d.sync += q.eq(rd.data)
        banks.append(mem)
        words.append(q)
    data = Signal(shape, name=f"{name}_word")
    if n_banks == 1:
        word = words[0]
    else:
        sel_a = Signal(range(n_banks), name=f"{name}_bank_a", reset_less=True)
        sel_b = Signal(range(n_banks), name=f"{name}_bank_b", reset_less=True)
        m.d.sync += [sel_a.eq(read_addr[lo_bits:]), sel_b.eq(sel_a)]
        word = pick(words, sel_b)
    if bypass:
        hit_a = Signal(name=f"{name}_bypass_a", reset_less=True)
        hit_b = Signal(name=f"{name}_bypass_b", reset_less=True)
        wd_a = Signal(shape, name=f"{name}_bypass_data_a", reset_less=True)
        wd_b = Signal(shape, name=f"{name}_bypass_data_b", reset_less=True)
        m.d.sync += [hit_a.eq(ram_en & (ram_addr == read_addr)), wd_a.eq(ram_data),
                     hit_b.eq(hit_a), wd_b.eq(wd_a)]
        word = Mux(hit_b, wd_b, word)
    m.d.comb += data.eq(word)
    pending = (ram_en, ram_addr, ram_data) if write_register else None
    return PrefetchedMemory(data, wr_addr, wr_data, wr_en, banks, bank_d, pending)
