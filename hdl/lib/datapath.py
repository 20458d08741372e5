"""Helpers for stage functions that run on NumPy int64 arrays (twins) and Amaranth values (RTL)
alike.

Each block writes its datapath once, as functions of its configuration and its operands; the
twin calls them on arrays (one element per neuron), the RTL on signals (one pipeline stage per
function). The selection helpers here pick per-neuron constants by the neuron's parameter-set
index: a constant when every set agrees, a multiplexer of constants in RTL, fancy indexing in
the twin.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from amaranth import Const, Mux

from .fixed import is_hdl

__all__ = ["lookup", "select_by", "const_like", "false_like"]


def lookup(table: Sequence[int], sel, width: int | None = None):
    """``table[sel]``: a constant when every entry is equal, else a mux of constants in RTL
    (``width`` bits, default the range of the table) and fancy indexing in the twin."""
    if len(set(table)) == 1:
        return table[0]
    if is_hdl(sel):
        out = Const(table[-1], range(min(table), max(table) + 1) if width is None else width)
        for i in range(len(table) - 2, -1, -1):
            out = Mux(sel == i, table[i], out)
        return out
    return np.asarray(table, dtype=np.int64)[np.asarray(sel)]


def select_by(sel, options):
    """``options[sel]`` (a mux in RTL, per-element choice in the twin; a plain index when
    ``sel`` is a Python integer)."""
    if isinstance(sel, int):
        return options[sel]
    if is_hdl(sel):
        out = options[-1]
        for i in range(len(options) - 2, -1, -1):
            out = Mux(sel == i, options[i], out)
        return out
    return np.choose(np.asarray(sel), [np.broadcast_to(o, np.shape(sel)) for o in options])


def const_like(like, c: int):
    """The constant ``c`` as ``like`` is: an Amaranth constant, or an int64 array of its shape."""
    return Const(c) if is_hdl(like) else np.full(np.shape(like), c, dtype=np.int64)


def false_like(like):
    """A false flag as ``like`` is: a 1-bit constant, or a boolean array of its shape."""
    return Const(0, 1) if is_hdl(like) else np.zeros(np.shape(like), dtype=bool)
