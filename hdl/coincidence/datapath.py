"""The coincidence detector (cuneate neurons): delayed afferent spikes, bi-exponential PSPs and
Izhikevich targets. Its own stage functions, written once for the twin and the RTL.

Per tick ``T`` and target ``t`` (configuration: :class:`~cuneate.hdl.coincidence.config
.CoincidenceConfig`)::

    a_t   = sum_s  J w[t, s] * x_s(T - delay[t, s])          (input spikes, from the history)
    I_t   = x_d - x_r                                        (traces as fetched)
    x'    = y - k y,   y = x + a_t,   k = 1 - exp(-dt/tau)   (decay and rise trace)
    v', u', spike  = the Izhikevich core's update with current I_t

so a spike of source ``s`` stamped with tick ``T`` adds ``J w (exp(-j dt/tau_d) - exp(-j dt/
tau_r))`` to the current of tick ``T + delay + j`` - the golden PSP of
:mod:`cuneate.golden.coincidence` (unnormalized) sampled on the tick grid, 0 at lag 0.

Input spikes arrive as events (``in_valid``, ``in_source``) at any cycle and are collected in a
pending bit vector; the next tick stamps them (an event on the tick cycle itself belongs to the
tick after). Two events of one source before one tick are one spike: the second is counted in
``merged_count`` (afferents spike at most once per tick; nothing is dropped silently). The
history is a ring of ``max_delay_ticks`` words of ``n_sources`` bits in block RAM; delays and
weights are a ROM of ``n_targets x n_sources`` words; each target's state (v, u, x_d, x_r) is one
block-RAM word.

Schedule of a tick (a multi-cycle datapath, one target at a time): on the tick the pending
word is written to history slot ``T mod D``; per target, one (source) input per cycle is read
from the ROM, then from the history (two read latencies), and accumulated; then four update
cycles: (1) ``I``, ``y`` and the Izhikevich operands, (2) the trace products and multipliers 1
and 3, (3) the trace updates and multipliers 2 and 4, (4) threshold, reset and clamps, write
back, ``upd_*`` and the spike event (``spike_valid``, ``spike_target``, ``spike_tick``) on the
next cycle. A tick needs ``n_targets (n_sources + 8) + 2`` cycles; a tick that arrives while
one is processed sets ``tick_overrun`` and is counted, never silently lost.

All arithmetic is written once: :func:`accumulate` and :func:`psp_current`
(:mod:`cuneate.hdl.coincidence.datapath`), the trace stages of :mod:`cuneate.hdl.lib.synapses`
and the Izhikevich stages of :mod:`cuneate.hdl.izhikevich.datapath` - each runs on NumPy ints
(twin) and Amaranth values (RTL).
"""

from __future__ import annotations

from amaranth import Cat

from ..lib.fixed import narrow, round_shift, select
from .config import CLAMP_KINDS, CoincidenceConfig

__all__ = ["accumulate", "psp_current", "clamp_bits_hdl"]


def accumulate(acc, bit, w):
    """One input of the sum: ``acc + (w if bit else 0)``."""
    return acc + select(bit, w, 0)


def psp_current(cfg: CoincidenceConfig, xd, xr, a):
    """Update cycle 1: the PSP current ``x_d - x_r`` (traces as fetched) rounded to the
    Izhikevich current format, and ``y = x + a`` for both traces."""
    i = narrow(round_shift(xd - xr, cfg.i_shift, cfg.rounding), cfg.iz.I, cfg.i_raw_bounds,
               "PSP current")
    ys = [xd + (a << cfg.wshift), xr + (a << cfg.wshift)]
    return i, ys


def clamp_bits_hdl(flags: dict):
    """Pack per-update clamp flags into the bit order of :data:`CLAMP_KINDS` (RTL)."""
    return Cat(*[flags[k] for k in CLAMP_KINDS])
