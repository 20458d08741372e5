"""The learning layer's stage functions, written once for the twin (NumPy int64 arrays) and the
RTL (Amaranth values).

The synapse (the learning stage, :class:`~cuneate.hdl.plasticity.stage.SynapseStage`), per
operation on one synapse word ``(w, c_d, c_r, L)``:

* integrate (every tick): :func:`calcium_input` (``C = c_d - c_r`` as fetched; each trace's
  ``y = c + w s_late``), the calcium traces' products and updates
  (:func:`~cuneate.hdl.lib.synapses.trace_products` / ``trace_update``), :func:`drive_product`
  (``round(C Z)``) and :func:`integrate` (``L + round(C Z)``, clamped, flagged); the CN's input
  sum takes :func:`contribution` (``w`` if the afferent spiked);
* learn (a window's end): :func:`compensated` (``D = K L - total`` rounded to an operand),
  :func:`step_index` (the step table's entry for ``w``'s bin and ``D``'s sign),
  :func:`weight_delta` (``round(D step)``) and :func:`weight_update` (``w + dw`` clamped to
  ``[0, w_max]``, flagged); ``L <- 0``.

The tick (:class:`~cuneate.hdl.plasticity.core.LearningLayer`): :func:`interneuron`
(``g H`` as fetched, ``y = H + n``), :func:`net_drive` (``I = E - g H``, ``y = E + a``),
:func:`main_calcium` (``Z = clamp(I) - theta``) and the Izhikevich core's stages for the CN.
"""

from __future__ import annotations

from amaranth import Cat

from ..lib.fixed import clamp_flagged, narrow, product, round_shift, select
from ..lib.synapses import trace_products, trace_update
from .config import CLAMP_KINDS, OPS, PlasticityConfig

__all__ = ["calcium_input", "calcium_update", "drive_product", "integrate", "contribution",
           "compensated", "step_index", "weight_delta", "weight_update", "interneuron", "net_drive",
           "main_calcium", "clamp_bits_hdl", "synapse_step"]


def contribution(acc, spiked, w):
    """One synapse of a CN's input sum: ``acc + (w if spiked else 0)``."""
    return acc + select(spiked, w, 0)


def calcium_input(cfg: PlasticityConfig, cd, cr, w, late):
    """The local calcium ``C = c_d - c_r`` (as fetched) and each trace's ``y = c + w s_late``
    (``late``: the afferent's spike ``latency`` ticks ago)."""
    x = select(late, w << cfg.wshift, 0)
    return cd - cr, [cd + x, cr + x]


def calcium_update(cfg: PlasticityConfig, ys, ps=None):
    """The two calcium traces after the tick: ``y - round(k round(y))`` (``ps``: the products,
    computed here when not given)."""
    ps = trace_products(cfg.cview, ys) if ps is None else ps
    return trace_update(cfg.cview, ys, ps)


def drive_product(cfg: PlasticityConfig, C, Z):
    """``round(C Z)`` in the drive's fraction bits: ``C`` rounded to its operand, one
    multiplier."""
    cq = narrow(round_shift(C, cfg.c_shift, cfg.rounding), cfg.CQ, cfg.cq_bounds,
                "local calcium operand")
    return round_shift(product(cq, Z, "drive product"), cfg.q_shift, cfg.rounding)


def integrate(cfg: PlasticityConfig, L, q):
    """``L + q`` clamped to the drive's format: ``(L', low, high)``."""
    return clamp_flagged(L + q, cfg.L.min_raw, cfg.L.max_raw, cfg.L)


def compensated(cfg: PlasticityConfig, L, total):
    """``D = K L - total`` (``total``: the sum of the CN's drives) rounded to its operand."""
    d = L * cfg.n_synapses - total
    return narrow(round_shift(d, cfg.d_shift, cfg.rounding), cfg.DQ, cfg.dq_bounds,
                  "compensated drive")


def step_index(cfg: PlasticityConfig, w, dq):
    """The step table's entry for ``w``'s bin (its top ``sigmoid_bits``) and ``D``'s sign:
    ``bin + 2**sigmoid_bits`` when ``D > 0`` (potentiation), else ``bin``
    (:attr:`PlasticityConfig.step_table`: a ROM in RTL, indexed in the twin)."""
    return (w >> cfg.sig_shift) + select(dq > 0, 1 << cfg.sigmoid_bits, 0)


def weight_delta(cfg: PlasticityConfig, dq, factor):
    """The step ``round(D factor)`` in weight LSBs (one multiplier)."""
    return round_shift(product(dq, factor, "weight step"), cfg.T_frac, cfg.rounding)


def weight_update(cfg: PlasticityConfig, w, dw):
    """``w + dw`` clamped to ``[0, w_max]``: ``(w', low, high)``."""
    return clamp_flagged(w + dw, 0, cfg.w_max_raw, cfg.W)


def interneuron(cfg: PlasticityConfig, H, n):
    """The inhibition ``round(g round(H))`` (current LSBs, ``H`` as fetched) and the trace's
    ``y = H + n`` (``n``: the tick's afferent spikes)."""
    hq = narrow(round_shift(H, cfg.trace_frac_bits - cfg.HQ.frac_bits, cfg.rounding), cfg.HQ,
                (cfg.inh.t_bounds[0] >> (cfg.trace_frac_bits - cfg.HQ.frac_bits),
                 (cfg.inh.t_bounds[1] >> (cfg.trace_frac_bits - cfg.HQ.frac_bits)) + 1),
                "interneuron operand")
    inh = round_shift(product(hq, cfg.G.raw, "inhibition"), cfg.g_shift, cfg.rounding)
    return inh, H + (n << cfg.trace_frac_bits)


def net_drive(cfg: PlasticityConfig, E, inh, a):
    """The CN's net drive ``I = round(E) - g H`` (current LSBs, ``E`` as fetched) and the
    excitation's ``y = E + a`` (``a``: the tick's input sum, weight LSBs)."""
    i = narrow(round_shift(E, cfg.e_shift, cfg.rounding) - inh, cfg.I_full, cfg.i_raw_bounds,
               "net drive")
    return i, E + (a << cfg.wshift)


def main_calcium(cfg: PlasticityConfig, i):
    """The zero-offset main calcium ``Z = clamp(I, -limit, limit) - theta`` (the clamp is the
    CNs' ``current`` clamp, flagged by their update)."""
    ic, _, _ = clamp_flagged(i, cfg.i_lim_raw[0], cfg.i_lim_raw[1], cfg.I_full)
    return narrow(ic - cfg.theta_raw, cfg.Z, cfg.z_bounds, "main calcium")


def clamp_bits_hdl(flags: dict):
    """Pack per-update clamp flags into the bit order of :data:`CLAMP_KINDS` (RTL)."""
    return Cat(*[flags[k] for k in CLAMP_KINDS])


def synapse_step(cfg: PlasticityConfig, op, w, cd, cr, L, spike, late, z, total, apply,
                 weight, table):
    """One operation on one synapse, composed from the stage functions (the learning stage's
    one-step specification; the twin runs it on arrays, the proofs on Amaranth values):
    ``op`` one of :data:`~cuneate.hdl.plasticity.config.OPS` and the operation's operands,
    ``table(index)`` the step table. Returns the new word (``w``, ``cd``, ``cr``, ``L``), the
    clamps that acted (``drive_low``, ``drive_high``, ``weight_low``, ``weight_high``) and
    the term of the CN's input sum (``contrib``); a ``read`` leaves the word as it was."""
    is_int, is_learn = op == OPS["integrate"], op == OPS["learn"]
    is_write, is_read = op == OPS["write"], op == OPS["read"]
    C, ys = calcium_input(cfg, cd, cr, w, late)
    cds, crs = calcium_update(cfg, ys)
    L_int, d_low, d_high = integrate(cfg, L, drive_product(cfg, C, z))
    dq = compensated(cfg, L, total)
    w_st, w_low, w_high = weight_update(cfg, w, weight_delta(cfg, dq, table(
        step_index(cfg, w, dq))))
    stepped = is_learn & apply
    return {"w": select(is_write, weight, select(stepped, w_st, w)),
            "cd": select(is_int, cds, select(is_write, 0, cd)),
            "cr": select(is_int, crs, select(is_write, 0, cr)),
            "L": select(is_int, L_int, select(is_read, L, 0)),
            "drive_low": is_int & d_low, "drive_high": is_int & d_high,
            "weight_low": stepped & w_low, "weight_high": stepped & w_high,
            "contrib": contribution(0, spike & is_int, w)}
