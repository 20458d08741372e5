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
from amaranth.hdl import Cat

from ..lib.datapath import const_like, false_like, lookup, select_by
from ..lib.fixed import (clamp_flagged, is_hdl, narrow, product, round_shift, round_shift_add,
                         select)
from .config import CLAMP_KINDS, IzhikevichConfig

__all__ = ["operands", "multiply1", "multiply2", "update_state", "stage_update", "clamp_bits",
           "Step", "STEPS", "CARRIED", "U_SUMS", "operand_step", "product1_step", "align_step",
           "product2_step", "sum_step", "select_step", "one_update", "step_flags"]


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
    out = {"q": product(wq, lookup([k.raw for k in cfg.KA], sel), "multiply1 q"),
           "bvp": product(vq, lookup([b.raw for b in cfg.beta], sel), "multiply1 bvp")}
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
    out["x"] = (_dt_x(cfg, x, u) if cfg.dt_shift is not None
                else product(x, cfg.KDT.raw, "multiply1 x"))
    return out


def _dt_x(cfg: IzhikevichConfig, i, u):
    """``dt I - dt u`` by shifts (dt a power of two), the rounding of ``dt u`` folded into the
    subtraction."""
    s, r = cfg.dt_shift, cfg.rounding
    dti = round_shift(i, cfg.I.frac_bits + s - cfg.V.frac_bits, r)
    su = cfg.U.frac_bits + s - cfg.V.frac_bits
    if su > 0 and r == "nearest":
        # dti - ((u >> su) + bit) == dti + ~(u >> su) + ~bit   (two's complement)
        bit_n = ~u[su - 1] if is_hdl(u) else 1 - ((u >> (su - 1)) & 1)
        return dti + ~(u >> su) + bit_n
    return dti - round_shift(u, su, r)


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
    return {"p": product(qq, wq, "multiply2 p"),
            "m": product(y, lookup([a.raw for a in cfg.alpha], sel), "multiply2 m"),
            "qq": qq, "y": y, "vb_sh": vb_sh, "vb_th": vb_th, "vb_lo": vb_lo, "u_sh": u_sh,
            "ud_sh": ud_sh, "y_flag": y_low | y_high}


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


def stage_update(cfg: IzhikevichConfig, v, u, I, sel, stages=None):
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


# ----------------------------------------------------------------------------------------------
# The same update as six pipelined steps (the core's and the twin's). Each multiplier sees a
# register (a floor: a slice of the state, no adder in front) and nothing follows it in its
# step: the rounding increments that :func:`operands` and :func:`multiply2` add before the
# products are added as ``increment * operand`` terms beside them, and the clamp tests of
# :func:`update_state` become signs of sums formed in parallel. The integers are the same
# (``round(x) * c == floor(x) * c + bit * c``); the ``steps`` property of
# :mod:`cuneate.hdl.izhikevich.formal` proves the two forms equal over the state box.
#
# Every step is ``f(cfg, x) -> dict`` over a mapping ``x`` of named values; :data:`STEPS` lists
# them with the names each reads, so that the RTL registers exactly the values still needed at
# each cut of the pipeline (``IzhikevichConfig.cuts``).

def _carry(x, t_low, shift: int):
    """``((x mod 2**shift) + t_low) >> shift``: the carry out of the dropped bits."""
    if is_hdl(x):
        return (x[:shift] + t_low)[shift]
    return ((np.asarray(x) & ((1 << shift) - 1)) + t_low) >> shift


def _floor_split(x, consts, sel, shift: int, rounding: str):
    """``round_shift(x + consts[sel], shift)`` as ``(x >> shift, K, carry)``: the floor of
    ``x`` (a slice), the constant part ``K`` (per set) and the 0/1 carry of the dropped bits
    (``carry`` is a Python 0 when it cannot be 1)."""
    h = (1 << (shift - 1)) if (rounding == "nearest" and shift > 0) else 0
    if shift <= 0:
        return x << -shift, [c << -shift for c in consts], 0
    t = [c + h for c in consts]
    lows = [tt & ((1 << shift) - 1) for tt in t]
    carry = 0 if not any(lows) else _carry(x, lookup(lows, sel), shift)
    return x >> shift, [tt >> shift for tt in t], carry


def _pick(flag, if_set, if_clear, sel):
    """Per-set constant ``if_set[sel]`` where ``flag`` else ``if_clear[sel]`` (``flag`` may be
    the Python int 0)."""
    if isinstance(flag, int) and not is_hdl(flag):
        return lookup(if_set if flag else if_clear, sel)
    return select(flag, lookup(if_set, sel), lookup(if_clear, sel))


def operand_step(cfg: IzhikevichConfig, x):
    """Step 0: the current (clamped and flagged when the host wrote one outside the accepted
    range), the floors ``v >> s`` that the first multipliers take with their rounding carries,
    the ``w`` operand for the second, ``dt (I - u)`` (or the ``I - u`` operand) and the ``u``
    side of ``b v - u``, its rounding carry folded in."""
    v, u, sel, r = x["v"], x["u"], x["sel"], cfg.rounding
    s2 = operands(cfg, v, u, x["i"], sel)
    sw = cfg.V.frac_bits - cfg.W.frac_bits
    vs_w, kw, cw = _floor_split(v, [w.raw for w in cfg.woff], sel, sw, r)
    vs_q, kq, cq = _floor_split(v, [0] * len(cfg.params), sel, cfg.V.frac_bits -
                                cfg.VQ.frac_bits, r)
    betas = [b.raw for b in cfg.beta]
    half_y = (1 << (cfg.shift_y - 1)) if r == "nearest" else 0
    # b v - uy = vs_q b - (uy - (kq + cq) b): the increment's product joins the u side
    e0 = [(e.raw << cfg.shift_b) - half_y - k * b for e, k, b in zip(cfg.E, kq, betas)]
    e1 = [e - b for e, b in zip(e0, betas)]
    e_sel = _pick(cq, e1, e0, sel)
    if all(cfg.u_leak):
        uyp = (u << cfg.shift_b) + e_sel
    else:
        uyp = select_by(sel, [((u << cfg.shift_b) if lam else const_like(u, 0)) + e_sel
                              for lam in cfg.u_leak])
    kas = [k.raw for k in cfg.KA]
    x_dt = _dt_x(cfg, s2["x"], u) if cfg.dt_shift is not None else s2["x"]
    return {"ic": s2["i"], "i_flag": s2["i_flag"], "wq": s2["wq"],
            "vs_w": narrow(vs_w, cfg.VSW, cfg.bounds_vsw, "w floor"),
            "vs_q": narrow(vs_q, cfg.VSQ, cfg.bounds_vsq, "v floor"),
            "q_inc": _pick(cw, [(k + 1) * a for k, a in zip(kw, kas)],
                           [k * a for k, a in zip(kw, kas)], sel),
            "ka": lookup(kas, sel), "beta": lookup(betas, sel), "uyp": uyp, "x": x_dt}


def product1_step(cfg: IzhikevichConfig, x):
    """Step 1: the first multipliers, on registers: ``floor(w) (A dt)``, ``floor(v) b`` (and
    ``(I - u) dt`` when dt is not a power of two); beside them ``vx = v + dt (I - u)`` when dt
    is a power of two (the shifts' difference is ready), else ``vx = v``, so that each ``v`` sum
    of the next step adds one constant."""
    out = {"pq": product(x["vs_w"], x["ka"], "product1_step pq"),
           "pb": product(x["vs_q"], x["beta"], "product1_step pb")}
    if cfg.dt_shift is None:
        out["px"], out["vx"] = product(x["x"], cfg.KDT.raw, "product1_step px"), x["v"]
    else:
        out["px"], out["vx"] = x["x"], x["v"] + x["x"]
    return out


def align_step(cfg: IzhikevichConfig, x):
    """Step 2: ``q = (A dt) w`` completed and split into its floor and rounding bit for the
    second multiplier (with ``cfg.q_split`` the floor is the sum of the floors of the product
    and its increment, an operand-wide adder after the multiplier, and the rounding "bit" counts
    0..2 carries of the dropped bits; with ``cfg.y_borrow`` likewise for ``y``, its borrow
    joining the low bits), ``y = (b v - u) >> shift_y`` (clamped and flagged only where its format
    is narrowed) split into the operand ``y_hi`` and the low bits ``y_lo``, and the ``v`` sums
    ``v + dt (I - u) + K0`` pre-shifted (plain, less ``v_th``, less ``v_floor``)."""
    sel, r = x["sel"], cfg.rounding
    sq = cfg.shift_q
    if cfg.q_split:
        # round(q) = (pq >> sq) + (q_inc >> sq) + qbit, qbit in 0..2 the carries of the
        # dropped bits and the rounding half: the adder after the product is operand-wide
        pq, qi = x["pq"], x["q_inc"]
        h = (1 << (sq - 1)) if r == "nearest" else 0
        qq_f = (pq >> sq) + (qi >> sq)
        if is_hdl(pq):
            qi_low = qi[:sq] if is_hdl(qi) else (int(qi) & ((1 << sq) - 1))
            qbit = (pq[:sq] + qi_low + h)[sq:]
        else:
            qbit = ((pq & ((1 << sq) - 1)) + (qi & ((1 << sq) - 1)) + h) >> sq
    else:
        qq_f, _, qbit = _floor_split(x["pq"] + x["q_inc"], [0], 0, sq, r)
    k, sy = cfg.y_split, cfg.shift_y
    if cfg.y_borrow:
        # y = yd - borrow with yd the difference of the floors (an adder as wide as y after
        # the product) and borrow of the dropped bits; y (a dt) = yd_hi (a dt) 2**k +
        # (yd_lo - borrow) (a dt): the multiplier takes yd_hi, the u sums the rest
        pb, uyp = x["pb"], x["uyp"]
        yd = narrow((pb >> sy) - (uyp >> sy), cfg.Y, (cfg.bounds_y[0], cfg.bounds_y[1] + 1),
                    "y operand")
        if is_hdl(yd):
            borrow = pb[:sy] < uyp[:sy]
        else:
            borrow = ((pb & ((1 << sy) - 1)) < (uyp & ((1 << sy) - 1))).astype(np.int64)
        y, y_low, y_high = yd, false_like(yd), false_like(yd)
    else:
        y_full = (x["pb"] - x["uyp"]) >> sy
        y, y_low, y_high = clamp_flagged(y_full, cfg.Y.min_raw, cfg.Y.max_raw, cfg.Y,
                                         cfg.bounds_y)
        borrow = 0
    if cfg.dt_shift is not None:
        vx = x["vx"]                    # v + dt (I - u), formed beside the first products
    else:
        vx = x["vx"] + round_shift(x["px"], cfg.X.frac_bits + cfg.KDT.frac_bits -
                                   cfg.V.frac_bits, r)
    half = (1 << (cfg.shift_p - 1)) if r == "nearest" else 0
    k0 = [c.raw for c in cfg.K0]
    sums = {}
    for name, off in (("vb", 0), ("vb_th", cfg.VTH.raw), ("vb_lo", cfg.v_floor_raw)):
        sums[name] = ((vx + lookup([c - off for c in k0], sel)) << cfg.shift_p) + half
    y_lo = (y[:k] if is_hdl(y) else y & ((1 << k) - 1)) if k else 0
    if cfg.y_borrow:        # the index of (y_lo - borrow) in _y_low_terms
        y_lo = (Cat(y_lo, borrow) if k else borrow) if is_hdl(y) else y_lo + (borrow << k)
    return {"qq_f": narrow(qq_f, cfg.QQF, cfg.bounds_qqf, "q floor"), "qbit": qbit,
            "y_hi": y >> k if k else y, "y_lo": y_lo, "y_flag": y_low | y_high,
            "alpha": lookup([a.raw for a in cfg.alpha], sel), **sums}


def _u_constants(cfg: IzhikevichConfig, y_lo: int) -> dict:
    """Per sum of :data:`U_SUMS`, per set: the constant added to ``u << shift_a`` when the low
    bits of ``y`` are ``y_lo``: the rounding half, ``d << shift_a`` for the sums after a spike,
    the clamp levels for the sign tests and ``y_lo (a dt)``."""
    near = cfg.rounding == "nearest"
    out = {}
    for name in U_SUMS:
        row = []
        for sa, d, a in zip(cfg.shift_a, cfg.d, cfg.alpha):
            c = ((1 << (sa - 1)) if near else 0) + y_lo * a.raw
            if name.startswith("ub"):
                c += d.raw << sa
            if name.endswith("_hi"):
                c -= (cfg.u_hi_raw + 1) << sa
            elif name.endswith("_lo"):
                c -= cfg.u_lo_raw << sa
            row.append(c)
        out[name] = row
    return out


#: The ``u`` sums: ``ua`` (no spike) and ``ub`` (spike, ``u + d``), each plain, less the ceiling
#: (``_hi``: ``u' > u_hi`` is its sign) and less the floor (``_lo``: ``u' < u_lo``).
U_SUMS = ("ua", "ua_hi", "ua_lo", "ub", "ub_hi", "ub_lo")


def _u_sum(cfg: IzhikevichConfig, u, sel, y_lo, tables: list, name: str):
    """``(u << shift_a[sel]) + constant[name][sel, y_lo]``: one adder when the sets share the
    shift, else one per set and a multiplexer."""
    shifts = cfg.shift_a
    n = len(shifts)
    if len(set(shifts)) == 1:
        per_lo = [lookup([t[name][s] for s in range(n)], sel) for t in tables]
        c = per_lo[0] if len(tables) == 1 else select_by(y_lo, per_lo)
        return (u << shifts[0]) + c
    opts = []
    for s, sa in enumerate(shifts):
        c = [t[name][s] for t in tables]
        opts.append((u << sa) + (c[0] if len(set(c)) == 1 else select_by(y_lo, c)))
    return select_by(sel, opts)


def _y_low_terms(cfg: IzhikevichConfig) -> list[int]:
    """The multiples of ``a dt`` added to the u sums beside ``y_hi (a dt) 2**k``, by the
    ``y_lo`` index of :func:`align_step`: the low bits of y, less the borrow with
    ``y_borrow``."""
    lows = list(range(1 << cfg.y_split))
    return lows + [j - 1 for j in lows] if cfg.y_borrow else lows


def product2_step(cfg: IzhikevichConfig, x):
    """Step 3: the second multipliers, on registers: ``floor(q) w`` and ``y_hi (a dt)``;
    beside them the ``v`` sums take the ``q`` rounding bit's ``w`` and the six ``u`` sums are
    formed with the ``y_lo (a dt)`` term."""
    u, sel, wq, qbit = x["u"], x["sel"], x["wq"], x["qbit"]
    out = {"p2": product(x["qq_f"], wq, "product2_step p2"),
           "m2": product(x["y_hi"], x["alpha"], "product2_step m2")}
    if not is_hdl(qbit) and isinstance(qbit, int):
        extra = 0           # no rounding bit (truncation, no dropped constant bits)
    elif is_hdl(qbit) and len(qbit) > 1:      # 0, 1 or 2 (q_split)
        extra = select(qbit[1], wq << 1, select(qbit[0], wq, 0))
    else:
        extra = qbit * wq if not is_hdl(qbit) else select(qbit, wq, 0)
    for name in ("vb", "vb_th", "vb_lo"):
        out[name] = x[name] + extra if not isinstance(extra, int) else x[name]
    tables = [_u_constants(cfg, j) for j in _y_low_terms(cfg)]
    for name in U_SUMS:
        out[name] = _u_sum(cfg, u, sel, x["y_lo"], tables, name)
    return out


def sum_step(cfg: IzhikevichConfig, x):
    """Step 4: every sum with the products: the three ``v`` sums with ``floor(q) w`` and the
    six ``u`` sums with ``y_hi (a dt) << k``."""
    p, m = x["p2"], x["m2"] << cfg.y_split if cfg.y_split else x["m2"]
    out = {f"t_{n}": x[n] + p for n in ("vb", "vb_th", "vb_lo")}
    out.update({f"t_{n}": x[n] + m for n in U_SUMS})
    return out


def select_step(cfg: IzhikevichConfig, x):
    """Step 5: threshold, reset, floor of ``v``, ``u`` clamped into ``[u_lo, u_hi]``, all from
    the signs of the sums; returns the new state, the spike and this update's clamp flags
    (keys of :func:`update_state`, plus ``under``)."""
    sel = x["sel"]
    spike = x["t_vb_th"] >= 0
    under = x["t_vb_lo"] < 0
    v_pre = x["t_vb"] >> cfg.shift_p
    u_sum = select(spike, x["t_ub"], x["t_ua"])
    high = select(spike, x["t_ub_hi"] >= 0, x["t_ua_hi"] >= 0)
    low = select(spike, x["t_ub_lo"] < 0, x["t_ua_lo"] < 0)
    shifts = cfg.shift_a
    u_pre = u_sum >> shifts[0] if len(set(shifts)) == 1 else \
        select_by(sel, [u_sum >> sa for sa in shifts])
    U = cfg.U
    u_out = select(high, cfg.u_hi_raw, select(low, cfg.u_lo_raw, u_pre))
    if is_hdl(u_out):
        u_out = u_out[:U.width].as_signed()
    v_keep = select(under, cfg.v_floor_raw,
                    narrow(v_pre, cfg.V, (cfg.v_floor_raw, cfg.VTH.raw), "v below threshold"))
    v_out = select(spike, lookup([c.raw for c in cfg.c], sel), v_keep)
    if is_hdl(v_out):
        v_out = v_out[:cfg.V.width].as_signed()
    return {"v_next": v_out, "u_next": u_out, "spike": spike, "v_pre": v_pre,
            "v_low": under & ~spike, "u_high": high, "u_low": low, "under": under}


class Step:
    """One step of the pipelined datapath: its name, the values it reads and its function,
    looked up in this module by name when used (``fn`` a name; so that a fault injected into
    the module's function reaches the RTL built afterwards; the formal reference binds them
    at import) or given (``fn`` a function: :meth:`with_fn`)."""

    def __init__(self, name: str, fn, reads: tuple):
        self.name, self._fn, self.reads = name, fn, reads

    @property
    def fn(self):
        return globals()[self._fn] if isinstance(self._fn, str) else self._fn

    def with_fn(self, fn) -> "Step":
        """This step computed by ``fn`` (a core with a fault of its own: its ``STEPS``)."""
        return Step(self.name, fn, self.reads)


#: The pipelined datapath: step ``k`` of the update; the core registers the live values at
#: the cuts ``IzhikevichConfig.cuts`` (after step ``k``).
STEPS = (
    Step("operands", "operand_step", ("v", "u", "i", "sel")),
    Step("multiply1", "product1_step", ("vs_w", "ka", "vs_q", "beta", "x", "v")),
    Step("align", "align_step", ("vx", "sel", "pq", "q_inc", "pb", "uyp", "px")),
    Step("multiply2", "product2_step", ("u", "sel", "wq", "qq_f", "qbit", "y_hi", "y_lo",
                                      "alpha", "vb", "vb_th", "vb_lo")),
    Step("sums", "sum_step", ("p2", "m2", "vb", "vb_th", "vb_lo") + U_SUMS),
    Step("select", "select_step", ("sel", "t_vb", "t_vb_th", "t_vb_lo")
         + tuple(f"t_{n}" for n in U_SUMS)),
)
#: Sums kept as wires of their own in the RTL, so that synthesis does not merge them into the
#: adder after a multiplier (``b v - u``: the product then meets a two-input subtraction).
KEPT = ("uyp",)
#: Values the pipeline delivers beside the new state: the current as written, the set, and the
#: flags of the clamps that act before the last step.
CARRIED = ("i", "sel", "i_flag", "y_flag")


def one_update(cfg: IzhikevichConfig, v, u, I, sel, steps=None) -> dict:
    """The update as one composition of :data:`STEPS` (the twin's and the formal references';
    ``steps``: ``(function, reads)`` pairs to compose instead, bound by a proof at import);
    returns every value formed, the results under the keys of :func:`update_state` (``v``,
    ``u``, ``spike``, ``v_pre``, ``v_low``, ``u_high``, ``u_low``, ``under``) and the flags
    ``current`` and ``y``."""
    vals = {"v": v, "u": u, "i": I, "sel": sel}
    for fn, reads in steps or ((s.fn, s.reads) for s in STEPS):
        vals.update(fn(cfg, {k: vals[k] for k in reads}))
    vals.update(v=vals["v_next"], u=vals["u_next"], current=vals["i_flag"], y=vals["y_flag"])
    return vals


def step_flags(vals: dict) -> dict:
    """The clamp flags of a :func:`one_update` result by kind (:data:`CLAMP_KINDS`)."""
    return {k: vals[k] for k in CLAMP_KINDS}
