"""The LIF datapath, written once: the stage functions run by the twin and the RTL.

One neuron update per clock; state (``v`` and the refractory counter) in block RAM; a host-written
current and a parameter-set index per neuron; weighted input spikes summed per tick from a weight
memory. Both forms of the brief (section 6), written as one subtraction of a product (see
:mod:`cuneate.hdl.lif.config`)::

    D   = clamp(I) + sum_i w_i x_i                    (total input of this tick)
    continuous:  v_pre = v - k (v - v_rest - D)       k = 1 - exp(-dt/tau_m)
    discrete:    v_pre = v - k v + D                  k = 1 - alpha
    refractory (r > 0):  v' = v_reset, r' = r - 1, no spike
    else if v_pre >= v_th (continuous) / v_pre > u_th (discrete):  spike, v' = v_reset, r' = n_ref
    else:  v' = v_pre (flagged clamp at the state floor when the format is narrower than proven)

Formats (from :class:`LifConfig`): state ``V`` (signed, ``v_frac_bits`` fraction bits, integer
bits from the proven range), host current ``I`` (default sQ8.8), weights ``W`` (``weight_bits``,
e.g. 8 or 4), accumulator ``acc_bits = weight_bits + ceil(log2 fan_in)`` (cannot overflow), the
leak operand ``X`` (``operand_width`` bits, multiply mode) and ``k`` (``operand_width`` bits,
one shared exponent) or a per-set shift ``s`` (shift mode, no multiplier). All arithmetic comes
from :mod:`cuneate.hdl.lib.fixed`; the three datapath steps below are used by the RTL (a pipeline
register after each stage) and by the twin (composed directly).

With ``synapses=True`` the weighted input spikes drive four per-neuron AMPA/GABA traces instead
(:mod:`cuneate.hdl.lib.synapses`): ``D = clamp(I) + I_syn``, the traces in their own block RAM,
their decays (one multiplier each) in stage 4 and their write-back in stage 5. With
``syn_alpha`` (discrete form) one signed current-based trace takes the whole input:
``D = y = x + clamp(I) + sum w x_in``, ``x' = y - (1 - syn_alpha) y`` (the host current is a
per-tick input of the synapse, as an Affine bias before NIR's CubaLIF).

Every clamp that can act is flagged and counted (:data:`CLAMP_KINDS`): ``current`` (host wrote
outside ``current_range``), ``input`` (the total input left ``input_limit``; only built with
``saturation="flag"``) and ``v_low`` (state below a format narrower than proven).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from amaranth import Const

from ..lib.datapath import false_like, lookup
from ..lib.fixed import (QFormat, clamp_flagged, is_hdl, narrow, product, round_shift,
                         round_shift_select, select, tree_sum)
from ..lib.synapses import cuba_input, trace_inputs
from .config import CLAMP_KINDS, LifConfig

__all__ = ["gather_input", "leak_operand", "leak_product", "update_state", "clamp_bits"]


# ----------------------------------------------------------------------------------------------
# The datapath: stage 3 (gather_input, leak_operand), stage 4 (leak_product), stage 5
# (update_state). NumPy int64 arrays (twin) and Amaranth values (RTL) alike.

def gather_input(cfg: LifConfig, I, x: Sequence, w: Sequence, traces=None):
    """Total input ``D = clamp(I) + sum_i (x_i ? w_i : 0)`` in state fraction bits, or, with
    synaptic traces, ``D = clamp(I) + I_syn`` (see :mod:`cuneate.hdl.lib.synapses`).

    ``x`` and ``w`` are per-source lists (spike bit and raw weight of the neuron for source
    ``i``). The sum cannot overflow its accumulator (width derived from the fan-in). Returns
    ``D``, the accumulator, the trace inputs ``ys`` and the ``current``/``input`` clamp flags."""
    fv = cfg.V.frac_bits
    if cfg.current_clamp:
        I, lo, hi = clamp_flagged(I, cfg.i_lo_raw, cfg.i_hi_raw, cfg.I)
        f_cur = lo | hi
    else:
        f_cur = false_like(I)
    ys = []
    if cfg.synapses:
        i_syn, ys, acc = trace_inputs(cfg, traces, x, w)
        D = (I << (fv - cfg.I.frac_bits)) + i_syn
    else:
        acc = tree_sum(select(xi, wi, 0) for xi, wi in zip(x, w))
        if not cfg.n_inputs:
            acc = Const(0, 1) if is_hdl(I) else np.zeros(np.shape(I), dtype=np.int64)
        if cfg.syn_alpha is not None:       # current-based synapse: D = y = x + I + a
            ys = [cuba_input(cfg, traces, I, acc)]
            D = ys[0]
        else:
            D = (I << (fv - cfg.I.frac_bits)) + (acc << (fv - cfg.W.frac_bits))
    if cfg.input_clamp:
        width = max(abs(cfg.d_lo_raw), abs(cfg.d_hi_raw)).bit_length() + 1
        D, lo, hi = clamp_flagged(D, cfg.d_lo_raw, cfg.d_hi_raw, QFormat(width, 0))
        f_in = lo | hi
    else:
        f_in = false_like(I)
    return {"d": D, "acc": acc, "ys": ys, "current": f_cur, "input": f_in}


def leak_operand(cfg: LifConfig, v, D, sel):
    """The operand of the leak: ``v - v_rest - D`` (continuous) or ``v`` (discrete), rounded
    to the multiplier's operand format ``X`` (proven to fit: no clamp) in multiply mode."""
    if cfg.form == "continuous":
        x = v - lookup([c.raw for c in cfg.REST], sel) - D
    else:
        x = v
    if cfg.X is None:
        return x
    return narrow(round_shift(x, cfg.V.frac_bits - cfg.X.frac_bits, cfg.rounding), cfg.X,
                  cfg.x_bounds_raw, "leak operand")


def leak_product(cfg: LifConfig, x, sel):
    """``k x`` rounded to state fraction bits: one multiply by the set's ``k`` (shared
    exponent) or a shift by the set's ``s``."""
    if cfg.k_shift is not None:
        return round_shift_select(x, cfg.k_shift, sel, cfg.rounding) if len(
            set(cfg.k_shift)) > 1 else round_shift(x, cfg.k_shift[0], cfg.rounding)
    return round_shift(product(x, lookup([c.raw for c in cfg.K], sel), "leak_product"),
                       cfg.product_shift, cfg.rounding)


def update_state(cfg: LifConfig, v, d, D, ref, sel):
    """``v_pre = v - d (+ D)``, refractory hold, threshold, reset, state floor clamp (flagged).
    Returns the new ``v`` and ``ref``, the spike, ``v_pre`` and the ``v_low`` flag."""
    v_pre = v - d + D if cfg.form == "discrete" else v - d
    frozen = (ref != 0) if cfg.ref_bits else false_like(v)
    spike = (v_pre >= lookup(cfg.th_cmp_raw, sel)) & ~frozen
    reset = lookup([c.raw for c in cfg.RESET], sel)
    fv = cfg.V.frac_bits
    pb = (int(np.floor(cfg.v_lo_proven * 2.0 ** fv)), int(np.ceil(cfg.v_hi_proven * 2.0 ** fv)))
    if cfg.v_clamp:
        # above the format's top v_pre is above threshold (the format holds v_th): it spikes
        kept, below, _ = clamp_flagged(v_pre, cfg.V.min_raw, cfg.V.max_raw, cfg.V)
        v_low = below & ~spike & ~frozen
    else:
        kept = narrow(v_pre, cfg.V, pb, "v")
        v_low = false_like(v)
    v_out = select(frozen | spike, reset, kept)
    if cfg.ref_bits:
        n_ref = lookup(cfg.n_ref, sel)
        ref_out = select(frozen, ref - 1, select(spike, n_ref, 0))
    else:
        ref_out = ref
    return {"v": v_out, "ref": ref_out, "spike": spike, "v_pre": v_pre, "v_low": v_low}


def clamp_bits(flags: dict):
    """Pack per-update clamp flags in the bit order of :data:`CLAMP_KINDS` (twin)."""
    return sum((np.asarray(flags[k], dtype=np.int64) << i) for i, k in enumerate(CLAMP_KINDS))
