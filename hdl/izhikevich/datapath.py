"""The Izhikevich datapath, written once: four stage functions run by the twin and the RTL.

The arithmetic is forward Euler (the golden model's ``scheme="euler"``), rewritten so that each
multiplier sees two operands of at most ``operand_width`` (18) bits and every constant keeps as
many significant bits as an operand can carry. Per parameter set ``s``::

    w   = v + B_s/(2 A_s)                       (62.5 mV for the standard equation)
    v'  = v + (A_s dt) w^2 + dt (C_s - A_s woff_s^2) + dt I - dt u
    u'  = u + (a_s dt) (b_s v - lambda_s u - b_s v_u,s)
    if v' >= v_th:  v' <- c_s,  u' <- u' + d_s

Completing the square (``A v^2 + B v = A w^2 - B^2/(4A)``) makes the one squared operand small
near rest, where the neuron spends its time, so its rounding costs least there. When ``dt`` is a
power of two (16 kHz: dt = 1/16 ms) ``dt I`` and ``dt u`` are exact shifts and the core uses four
multipliers: ``(A dt) w``, ``((A dt) w) w``, ``b v`` and ``(a dt) y``. Otherwise a fifth
multiplies ``I - u`` by ``dt``. ``a dt`` is stored per parameter set as a normalized mantissa
with its own shift; ``b`` and ``A dt`` share one exponent across the sets. Per-set offsets and
constants are multiplexed by the neuron's set index only when the sets differ.

Formats, clamp levels and constants come from :class:`~cuneate.hdl.izhikevich.config
.IzhikevichConfig`, sized to the state range proven for the accepted currents; every clamp that
can act is flagged (``v_low``, ``u_high``, ``u_low``, ``current``, ``y``: see
:data:`CLAMP_KINDS`). All arithmetic comes from :mod:`cuneate.hdl.lib.fixed`; the four datapath
steps below are written once and used both by the RTL (with a pipeline register after each
stage) and by the twin (composed directly).
"""

from __future__ import annotations

import numpy as np

from ..lib.datapath import const_like, false_like, lookup, select_by
from ..lib.fixed import clamp_flagged, is_hdl, narrow, round_shift, round_shift_add, select
from .config import CLAMP_KINDS, IzhikevichConfig

__all__ = ["operands", "multiply1", "multiply2", "update_state", "one_update", "clamp_bits"]


# ----------------------------------------------------------------------------------------------
# The datapath as four steps (operands and multiply1 share pipeline stage 3, multiply2 is
# stage 4, update_state stage 5). Each works on NumPy int64 arrays (twin) and on Amaranth
# values (RTL) alike.

def operands(cfg: IzhikevichConfig, v, u, I, sel):
    """Operands: the accepted current (clamped and flagged when the host wrote one outside
    ``current_range``), ``w = v + B/(2A)`` and ``v`` rounded to multiplier width, and the
    ``I - u`` operand when dt is not a power of two."""
    r = cfg.rounding
    if cfg.current_clamp:
        I, i_low, i_high = clamp_flagged(I, cfg.i_lo_raw, cfg.i_hi_raw, cfg.I)
        i_flag = i_low | i_high
    else:
        i_flag = false_like(v)
    sv = cfg.V.frac_bits - cfg.W.frac_bits
    woff = [w.raw for w in cfg.woff]
    if len(set(woff)) == 1:
        wq_full = round_shift_add(v, woff[0], sv, r)
    else:
        wq_full = round_shift(v + lookup(woff, sel), sv, r)
    wq = narrow(wq_full, cfg.W, cfg.bounds_wq, "w operand")
    vq = narrow(round_shift(v, cfg.V.frac_bits - cfg.VQ.frac_bits, r), cfg.VQ, cfg.bounds_vq,
                "v operand")
    if cfg.dt_shift is not None:
        x = I
    else:
        x_full = round_shift(I, cfg.I.frac_bits - cfg.U.frac_bits, r) - u
        x = narrow(round_shift(x_full, cfg.U.frac_bits - cfg.X.frac_bits, r), cfg.X,
                   cfg.bounds_x, "I - u operand")
    return {"wq": wq, "vq": vq, "x": x, "i": I, "i_flag": i_flag}


def multiply1(cfg: IzhikevichConfig, wq, vq, x, u, sel):
    """Multipliers 1 and 3 (and 5, ``dt (I - u)``, when dt is not a power of two; when it is,
    ``dt I - dt u`` by shifts, the rounding of ``dt u`` folded into the subtraction)."""
    out = {"q": wq * lookup([k.raw for k in cfg.KA], sel),
           "bvp": vq * lookup([b.raw for b in cfg.beta], sel)}
    # y = round((b v - lambda u - b v_u) / 2**shift_y) is computed in stage 4 as
    # (bvp - uy) >> shift_y with uy = (lambda u + E) << shift_b, minus half an LSB of y when
    # rounding to nearest (exact, one adder)
    half_y = (1 << (cfg.shift_y - 1)) if cfg.rounding == "nearest" else 0
    e_sh = [(e.raw << cfg.shift_b) - half_y for e in cfg.E]
    if all(cfg.u_leak):
        uy = (u << cfg.shift_b) + lookup(e_sh, sel)
    else:
        uy = select_by(sel, [((u << cfg.shift_b) + es) if lam else const_like(u, es)
                              for lam, es in zip(cfg.u_leak, e_sh)])
    out["uy"] = uy
    if cfg.dt_shift is not None:
        s, r = cfg.dt_shift, cfg.rounding
        dti = round_shift(x, cfg.I.frac_bits + s - cfg.V.frac_bits, r)
        su = cfg.U.frac_bits + s - cfg.V.frac_bits
        if su > 0 and r == "nearest":
            # dti - ((u >> su) + bit) == dti + ~(u >> su) + ~bit   (two's complement)
            bit_n = ~u[su - 1] if is_hdl(u) else 1 - ((u >> (su - 1)) & 1)
            out["x"] = dti + ~(u >> su) + bit_n
        else:
            out["x"] = dti - round_shift(u, su, r)
    else:
        out["x"] = x * cfg.KDT.raw
    return out


def multiply2(cfg: IzhikevichConfig, q, bvp, uy, wq, v, u, x, sel):
    """Multipliers 2 and 4: (A dt w) w and (a dt) y. Meanwhile the addends of stage 5 are
    prepared, pre-shifted to the products' scale with the rounding half folded in, so that
    each sum of stage 5 is a single adder: ``v + dt (I - u) + K0`` for ``v'``, ``u`` and
    ``u + d`` for ``u'``."""
    r = cfg.rounding
    qq = narrow(round_shift(q, cfg.shift_q, r), cfg.Q, cfg.bounds_qq, "q operand")
    y_full = (bvp - uy) >> cfg.shift_y
    y, y_low, y_high = clamp_flagged(y_full, cfg.Y.min_raw, cfg.Y.max_raw, cfg.Y,
                                     cfg.bounds_y)
    if cfg.dt_shift is not None:
        dx = x
    else:
        dx = round_shift(x, cfg.X.frac_bits + cfg.KDT.frac_bits - cfg.V.frac_bits, r)
    near = r == "nearest"
    vb = v + dx + lookup([k.raw for k in cfg.K0], sel)
    vb_sh = (vb << cfg.shift_p) + ((1 << (cfg.shift_p - 1)) if near else 0)
    # threshold and lower clamp of v' become sign tests of sums formed in stage 5:
    # v' >= v_th  <=>  vb_sh - (v_th << shift_p) + p >= 0   (likewise for v_floor)
    vb_th = vb_sh - (cfg.VTH.raw << cfg.shift_p)
    vb_lo = vb_sh - (cfg.v_floor_raw << cfg.shift_p)
    shifts = cfg.shift_a
    halves = [(1 << (sa - 1)) if near else 0 for sa in shifts]
    ud = u + lookup([d.raw for d in cfg.d], sel)
    if len(set(shifts)) == 1:
        u_sh = (u << shifts[0]) + halves[0]
        ud_sh = (ud << shifts[0]) + halves[0]
    else:
        u_sh = select_by(sel, [(u << sa) + h for sa, h in zip(shifts, halves)])
        ud_sh = select_by(sel, [(ud << sa) + h for sa, h in zip(shifts, halves)])
    return {"p": qq * wq, "m": y * lookup([a.raw for a in cfg.alpha], sel),
            "vb_sh": vb_sh, "vb_th": vb_th, "vb_lo": vb_lo, "u_sh": u_sh, "ud_sh": ud_sh,
            "y_flag": y_low | y_high}


def update_state(cfg: IzhikevichConfig, vb_sh, vb_th, vb_lo, u_sh, ud_sh, p, m, sel):
    """Sum, threshold, reset and the flagged state clamps:
    ``v' = (vb_sh + p) >> shift_p`` and ``u' = (u_sh + m) >> shift_a`` (or ``ud_sh`` on a
    spike, i.e. ``u' = u + d + (a dt) y``) clamped once into ``[u_lo, u_hi]``. The threshold
    test and the floor of ``v'`` are signs of ``vb_th + p`` and ``vb_lo + p``; ``v'`` needs no
    upper clamp: above threshold it is replaced by ``c``. Returns the new state, the spike and
    the clamp flags of this update (``v_low``, ``u_high``, ``u_low``)."""
    v_pre = (vb_sh + p) >> cfg.shift_p
    spike = (vb_th + p) >= 0
    under = (vb_lo + p) < 0
    shifts = cfg.shift_a
    u_sum = select(spike, ud_sh, u_sh) + m
    if len(set(shifts)) == 1:
        u_pre = u_sum >> shifts[0]
    else:
        u_pre = select_by(sel, [u_sum >> sa for sa in shifts])
    u_out, u_low, u_high = clamp_flagged(u_pre, cfg.u_lo_raw, cfg.u_hi_raw, cfg.U)
    v_keep = select(under, cfg.v_floor_raw,
                    narrow(v_pre, cfg.V, (cfg.v_floor_raw, cfg.VTH.raw), "v below threshold"))
    v_out = select(spike, lookup([c.raw for c in cfg.c], sel), v_keep)
    v_low = under & ~spike
    return {"v": v_out, "u": u_out, "spike": spike, "v_pre": v_pre, "v_low": v_low,
            "u_high": u_high, "u_low": u_low}


def one_update(cfg: IzhikevichConfig, v, u, I, sel, stages=None):
    """One whole update from ``(v, u, I, sel)``: the four stage functions composed (``stages``:
    the four functions to compose, in order; default this module's, looked up at the call).
    Returns the :func:`update_state` result and the clamp flags by kind (``CLAMP_KINDS``)."""
    op, m1, m2, up = stages or (operands, multiply1, multiply2, update_state)
    s2 = op(cfg, v, u, I, sel)
    s3 = m1(cfg, s2["wq"], s2["vq"], s2["x"], u, sel)
    s4 = m2(cfg, s3["q"], s3["bvp"], s3["uy"], s2["wq"], v, u, s3["x"], sel)
    o = up(cfg, *(s4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh", "p", "m")), sel)
    flags = {"v_low": o["v_low"], "u_high": o["u_high"], "u_low": o["u_low"],
             "current": s2["i_flag"], "y": s4["y_flag"]}
    return o, flags


def clamp_bits(flags: dict):
    """Pack the per-update clamp flags into the bit order of :data:`CLAMP_KINDS`
    (twin: an int64 array)."""
    return sum((np.asarray(flags[k], dtype=np.int64) << i) for i, k in enumerate(CLAMP_KINDS))
