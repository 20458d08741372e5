"""Pipelined, time-multiplexed, fixed-point Izhikevich core and its bit-exact NumPy twin.

The arithmetic is forward Euler (the golden model's ``scheme="euler"``), rewritten so that each
multiplier sees two operands of at most ``operand_width`` (18) bits and every constant keeps as
many significant bits as an operand can carry::

    w   = v + B/(2A)                            (B/(2A) = 62.5 mV, exact)
    v'  = v + (A dt) w^2 + dt (C - B^2/(4A)) + dt I - dt u
    u'  = u + (a dt) (b v - u)
    if v' >= 30:  v' <- c,  u' <- u' + d

Completing the square (``A v^2 + B v = A w^2 - B^2/(4A)``) makes the one squared operand small
near rest, where the neuron spends its time, so its rounding costs least there. When ``dt`` is a
power of two (16 kHz: dt = 1/16 ms) ``dt I`` and ``dt u`` are exact shifts and the core uses four
multipliers: ``(A dt) w``, ``((A dt) w) w``, ``b v`` and ``(a dt) (b v - u)``. Otherwise a fifth
multiplies ``I - u`` by ``dt``. ``a dt`` and ``b`` are stored per parameter set as normalized
mantissas with their own shifts. All formats, roundings and saturations come from
:mod:`cuneate.hdl.fixed`; the four datapath stages below are written once and used both by the
RTL (with a pipeline register after each) and by the twin (composed directly).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..golden import izhikevich as golden
from .fixed import (FixedConstant, FixedPointError, QFormat, check_int64, is_hdl,
                    round_shift, round_shift_add, saturate, select)

__all__ = ["ConfigError", "IzhikevichConfig", "IzhikevichTwin", "IzhikevichCore",
           "PIPELINE_DEPTH"]

PIPELINE_DEPTH = 5
W_OFFSET = golden.B / (2 * golden.A)                 # 62.5 mV
K0_MV_PER_MS = golden.C - golden.B ** 2 / (4 * golden.A)  # -16.25 mV/ms


class ConfigError(FixedPointError):
    """A core configuration that cannot hold; raised at construction (before elaboration)."""


def _lookup(table: Sequence[int], sel, width: int | None = None):
    """``table[sel]``: a mux of constants in RTL, fancy indexing in the twin."""
    if is_hdl(sel):
        out = Const(table[-1], range(min(table), max(table) + 1) if width is None else width)
        for i in range(len(table) - 2, -1, -1):
            out = Mux(sel == i, table[i], out)
        return out
    return np.asarray(table, dtype=np.int64)[np.asarray(sel)]


@dataclass
class IzhikevichConfig:
    """Everything that defines a core: size, rates, formats, constants, parameter sets.

    Parameters
    ----------
    n_neurons
        Neurons sharing the core (default 2500).
    clock_hz, update_hz
        Core clock and per-neuron update rate; ``dt = 1000 / update_hz`` ms and
        ``cycles_per_tick = clock_hz / update_hz`` (must be an integer >= ``n_neurons``).
    param_sets
        Table of parameter sets (preset names or (a, b, c, d)); per-neuron selection.
    neuron_sets
        Initial set index of each neuron (default all 0); writable by the host at run time.
    operand_width
        Multiplier operand width (18 for the 18x18 DSP blocks of Spartan-6 and ECP5).
    v_frac_bits, u_frac_bits, state_int_bits
        State formats ``sQ{state_int_bits}.{frac}``; state lives in block RAM, wider than the
        operands (adders only, no multiplier cost).
    current_format
        Format of the input current written by the host (default sQ10.8, +-512 mV/ms).
    rounding
        ``"nearest"`` (default) or ``"truncate"`` at every narrowing.
    tick_source
        ``"internal"`` (divider of ``clock_hz / update_hz``) or ``"external"`` (``tick`` input).
    spike_fifo_depth, sweep_number_width
        Spike stream buffering and the width of the (wrapping) sweep number.
    y_int_bits
        Integer bits of the ``b v - u`` operand. Default: the fewest that provably hold every
        state (no clamp needed); fewer bits buy precision but clamp in extreme states.
    """

    n_neurons: int = 2500
    clock_hz: float = 40e6
    update_hz: float = 16e3
    param_sets: tuple = ("RS",)
    neuron_sets: Sequence[int] | None = None
    operand_width: int = 18
    state_int_bits: int = 8
    v_frac_bits: int = 18
    u_frac_bits: int = 20
    current_format: QFormat = QFormat(10, 8)
    rounding: str = "nearest"
    tick_source: str = "internal"
    spike_fifo_depth: int = 64
    sweep_number_width: int = 16
    y_int_bits: int | None = None
    v0: float = golden.V0
    v_th: float = golden.V_TH

    # derived (filled by __post_init__)
    sets: list = field(init=False, repr=False)

    def __post_init__(self):
        self.param_sets = tuple(self.param_sets)
        try:
            self._derive()
        except FixedPointError as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(f"Izhikevich core configuration refused: {exc}") from None

    # ------------------------------------------------------------------------------------------
    def _derive(self):
        N = self.n_neurons
        if not isinstance(N, (int, np.integer)) or N < PIPELINE_DEPTH:
            raise ConfigError(f"n_neurons must be an integer >= {PIPELINE_DEPTH} (the pipeline "
                              f"depth; a neuron must leave the pipeline before it is read "
                              f"again), got {N!r}")
        if not (self.clock_hz > 0 and self.update_hz > 0 and math.isfinite(self.clock_hz)
                and math.isfinite(self.update_hz)):
            raise ConfigError("clock_hz and update_hz must be positive")
        ratio = self.clock_hz / self.update_hz
        if abs(ratio - round(ratio)) > 1e-9 * ratio:
            raise ConfigError(f"clock_hz / update_hz = {ratio:g} is not an integer number of "
                              f"cycles per update")
        self.cycles_per_tick = int(round(ratio))
        if N > self.cycles_per_tick:
            raise ConfigError(
                f"{N} neurons do not fit one sweep: at {self.clock_hz:g} Hz and "
                f"{self.update_hz:g} Hz per neuron the core has {self.cycles_per_tick} cycles "
                f"per update (at most {self.cycles_per_tick} neurons)")
        if self.rounding not in ("nearest", "truncate"):
            raise ConfigError(f"unknown rounding {self.rounding!r}")
        if self.tick_source not in ("internal", "external"):
            raise ConfigError("tick_source must be 'internal' or 'external'")
        if self.operand_width < 8:
            raise ConfigError("operand_width must be >= 8")
        if not self.param_sets:
            raise ConfigError("at least one parameter set is needed")
        self.dt_ms = 1000.0 / self.update_hz
        ow = self.operand_width
        self.V = QFormat(self.state_int_bits, self.v_frac_bits)
        self.U = QFormat(self.state_int_bits, self.u_frac_bits)
        self.I = self.current_format
        # w = v + 62.5 and v itself as multiplier operands (same format).
        w_lo, w_hi = self.V.min_value + W_OFFSET, self.V.max_value + W_OFFSET
        self.W = QFormat.for_range(w_lo, w_hi, ow)
        # constants
        sets = [golden.resolve_params(p, 1) for p in self.param_sets]
        self.sets = [tuple(float(x[0]) for x in s) for s in sets]
        dt = self.dt_ms
        self.KA = FixedConstant.normalized("A*dt", golden.A * dt, ow, max_rel_error=2.0 ** -12)
        q_max = self.KA.quantized * max(abs(self.W.min_value), abs(self.W.max_value))
        self.Q = QFormat.for_range(-q_max, q_max, ow)
        self.K0 = FixedConstant.in_format("dt*(C-B^2/4A)", dt * K0_MV_PER_MS, self.V)
        self.VTH = FixedConstant.in_format("v_th", self.v_th, self.V, exact=True)
        self.WOFF = FixedConstant.in_format("B/(2A)", W_OFFSET, self.V, exact=True)
        log2dt = math.log2(dt)
        self.dt_shift = -int(log2dt) if log2dt == int(log2dt) else None
        if self.dt_shift is None:
            self.KDT = FixedConstant.normalized("dt", dt, ow)
            x_max = max(abs(self.I.min_value), abs(self.I.max_value)) + \
                max(abs(self.U.min_value), abs(self.U.max_value))
            self.X = QFormat.for_range(-x_max, x_max, ow)
        else:
            self.KDT = None
            self.X = None
        if not self.sets:
            raise ConfigError("no parameter sets")
        # b shares one exponent across the table (so b v needs no per-set shift); its
        # mantissa is normalized to the largest |b|
        b_norm = FixedConstant.normalized("b", max((abs(st[1]) for st in self.sets)), ow)
        self.beta = [FixedConstant.scaled(f"b[{i}]", b, b_norm.frac_bits, ow,
                                          max_rel_error=2.0 ** -12)
                     for i, (a, b, c, d) in enumerate(self.sets)]
        self.alpha = [FixedConstant.normalized(f"a*dt[{i}]", a * dt, ow,
                                               max_rel_error=2.0 ** -12)
                      for i, (a, b, c, d) in enumerate(self.sets)]
        self.c = [FixedConstant.in_format(f"c[{i}]", c, self.V)
                  for i, (a, b, c, d) in enumerate(self.sets)]
        self.d = [FixedConstant.in_format(f"d[{i}]", d, self.U)
                  for i, (a, b, c, d) in enumerate(self.sets)]
        for i, (a, b, c, d) in enumerate(self.sets):
            if not (a > 0 and b != 0):
                raise ConfigError(f"parameter set {i}: a must be > 0 and b non-zero")
            if c >= self.v_th:
                raise ConfigError(f"parameter set {i}: reset c = {c:g} is not below threshold")
        # y = b v - u as an operand
        b_max = max(abs(b.quantized) for b in self.beta)
        y_max = b_max * max(abs(self.V.min_value), abs(self.V.max_value)) + \
            max(abs(self.U.min_value), abs(self.U.max_value))
        self.Y = QFormat.for_range(-y_max, y_max, ow) if self.y_int_bits is None else \
            QFormat(self.y_int_bits, ow - self.y_int_bits)
        # shifts aligning products to the state formats
        self.shift_p = self.Q.frac_bits + self.W.frac_bits - self.V.frac_bits
        self.shift_q = self.KA.frac_bits + self.W.frac_bits - self.Q.frac_bits
        self.shift_b = self.beta[0].frac_bits + self.W.frac_bits - self.U.frac_bits
        self.shift_y = self.shift_b + self.U.frac_bits - self.Y.frac_bits
        self.shift_a = [a.frac_bits + self.Y.frac_bits - self.U.frac_bits for a in self.alpha]
        for name, s in [("b*v", self.shift_y), ("(a dt) y", min(self.shift_a)),
                        ("q", self.shift_q), ("p", self.shift_p)]:
            if s < 1:
                raise ConfigError(f"product {name} has fewer fraction bits than its target "
                                  f"format; reduce the state fraction bits")
        self._derive_bounds()
        # worst-case overshoot of v above threshold must fit the state format
        u_min = self.U.min_value
        f_max = golden.A * self.v_th ** 2 + golden.B * self.v_th + golden.C - u_min + \
            self.I.max_value
        self.v_pre_max = self.v_th + dt * f_max
        if self.v_pre_max > self.V.max_value:
            raise ConfigError(
                f"worst-case v before reset {self.v_pre_max:.1f} mV (v just below "
                f"{self.v_th:g}, u = {u_min:g}, I = {self.I.max_value:g}, dt = {dt:g} ms) "
                f"overflows the state format {self.V} (max {self.V.max_value:g}); use more "
                f"state integer bits or a smaller dt")
        # initial state and per-neuron set selection
        ns = [0] * N if self.neuron_sets is None else [int(s) for s in self.neuron_sets]
        if len(ns) != N or any(not 0 <= s < len(self.sets) for s in ns):
            raise ConfigError(f"neuron_sets needs {N} indices in [0, {len(self.sets)})")
        self.neuron_sets = ns
        self.V0 = FixedConstant.in_format("v0", self.v0, self.V)
        self.u0 = [FixedConstant.in_format(f"u0[{i}]", b * self.v0, self.U)
                   for i, (a, b, c, d) in enumerate(self.sets)]
        self.sel_bits = max(1, (len(self.sets) - 1).bit_length())

    def _derive_bounds(self):
        """Proven raw bounds of the narrowed operands (every map below is monotone), used to
        leave out clamp logic that can never act."""
        r = self.rounding
        sv = self.V.frac_bits - self.W.frac_bits
        lo, hi = self.V.min_raw, self.V.max_raw
        self.bounds_vq = (round_shift(lo, sv, r), round_shift(hi, sv, r))
        self.bounds_wq = (round_shift(lo + self.WOFF.raw, sv, r),
                          round_shift(hi + self.WOFF.raw, sv, r))
        q_ends = [w * self.KA.raw for w in self.bounds_wq]
        sq = self.KA.frac_bits + self.W.frac_bits - self.Q.frac_bits
        self.bounds_qq = (round_shift(min(q_ends), sq, r), round_shift(max(q_ends), sq, r))
        bvp = [vq * b.raw for vq in self.bounds_vq for b in self.beta]
        ush = [self.U.min_raw << self.shift_b, self.U.max_raw << self.shift_b]
        self.bounds_y = (round_shift(min(bvp) - ush[1], self.shift_y, r),
                         round_shift(max(bvp) - ush[0], self.shift_y, r))

    # ------------------------------------------------------------------------------------------
    # Error bound of one update against float64 Euler from the same state.
    def one_step_bound(self, v, u, I):
        """Upper bounds (mV) on |v' - v'_golden| and |u' - u'_golden| for one update from the
        state ``(v, u)`` (floats, exactly representable) with input ``I``, before reset.

        Sum of every rounding and representation error of the datapath, each at its worst:
        operand roundings ``e_X`` (half an LSB, or one LSB when truncating), constant errors
        ``|k_q - k|``, and the alignments into the state formats.
        """
        v, u, I = (np.asarray(x, dtype=np.float64) for x in (v, u, I))
        half = 0.5 if self.rounding == "nearest" else 1.0
        eW, eQ, eV, eU, eY = (half * f.lsb for f in (self.W, self.Q, self.V, self.U, self.Y))
        w = v + W_OFFSET
        ka, dka = self.KA.quantized, abs(self.KA.abs_error)
        bound_v = (dka * w * w + ka * (2 * np.abs(w) * eW + eW * eW)
                   + eQ * (np.abs(w) + eW) + eV + abs(self.K0.abs_error))
        if self.dt_shift is not None:
            bound_v = bound_v + eV                           # dt*u alignment (dt*I is exact)
        else:
            eX = half * self.X.lsb
            kd, dkd = self.KDT.quantized, abs(self.KDT.abs_error)
            bound_v = bound_v + dkd * np.abs(I - u) + kd * (eX + eU) + eV
        beta_q = np.array([b.quantized for b in self.beta])
        dbeta = np.array([abs(b.abs_error) for b in self.beta])
        alpha_q = np.array([a.quantized for a in self.alpha])
        dalpha = np.array([abs(a.abs_error) for a in self.alpha])
        ey = beta_q.max() * eW + dbeta.max() * np.abs(v) + eU + eY
        bound_u = alpha_q.max() * ey + dalpha.max() * (np.abs(v) * beta_q.max() + np.abs(u)) \
            + eU
        return bound_v + 1e-9, bound_u + 1e-9

    def to_dict(self) -> dict:
        """Everything a user of the generated Verilog needs (written beside it as JSON)."""
        consts = [self.KA, self.K0, self.VTH, self.WOFF, self.V0] + \
            ([self.KDT] if self.KDT else []) + self.alpha + self.beta + self.c + self.d + self.u0
        bv, bu = self.one_step_bound(np.array([self.V.min_value / 2, -65.0, self.v_th]),
                                     np.array([0.0, -13.0, 0.0]), np.zeros(3))
        return {
            "block": "IzhikevichCore", "scheme": "euler", "n_neurons": self.n_neurons,
            "clock_hz": self.clock_hz, "update_hz": self.update_hz, "dt_ms": self.dt_ms,
            "cycles_per_tick": self.cycles_per_tick, "pipeline_depth": PIPELINE_DEPTH,
            "latency_cycles": PIPELINE_DEPTH, "throughput": "one neuron update per cycle",
            "rounding": self.rounding, "tick_source": self.tick_source,
            "dt_is_shift": self.dt_shift is not None,
            "multipliers": 4 if self.dt_shift is not None else 5,
            "formats": {k: getattr(self, k).to_dict() for k in ("V", "U", "I", "W", "Q", "Y")}
            | ({"X": self.X.to_dict()} if self.X else {}),
            "param_sets": [dict(zip("abcd", s)) for s in self.sets],
            "constants": {c.name: c.to_dict() for c in consts},
            "worst_case": {"v_pre_max_mV": self.v_pre_max, "v_range": [self.V.min_value,
                                                                      self.V.max_value],
                           "u_range": [self.U.min_value, self.U.max_value],
                           "one_step_bound_v_mV_at_rest": float(bv[1]),
                           "one_step_bound_u_at_rest": float(bu[1]),
                           "one_step_bound_v_mV_at_threshold": float(bv[2])},
            "state_word_bits": self.V.width + self.U.width,
        }


# ----------------------------------------------------------------------------------------------
# The datapath as four steps (operands and multiply1 share pipeline stage 3, multiply2 is
# stage 4, update_state stage 5). Each works on NumPy int64 arrays (twin) and on Amaranth
# values (RTL) alike.

def operands(cfg: IzhikevichConfig, v, u, I):
    """Operands: w = v + 62.5 and v rounded to multiplier width; the ``I - u`` operand when dt
    is not a power of two (else ``I`` passes through to stage 3)."""
    r = cfg.rounding
    wq = saturate(round_shift_add(v, cfg.WOFF.raw, cfg.V.frac_bits - cfg.W.frac_bits, r), cfg.W,
                  cfg.bounds_wq)
    vq = saturate(round_shift(v, cfg.V.frac_bits - cfg.W.frac_bits, r), cfg.W, cfg.bounds_vq)
    if cfg.dt_shift is not None:
        x = I
    else:
        x_full = round_shift(I, cfg.I.frac_bits - cfg.U.frac_bits, r) - u
        x = saturate(round_shift(x_full, cfg.U.frac_bits - cfg.X.frac_bits, r), cfg.X)
    return {"wq": wq, "vq": vq, "x": x}


def multiply1(cfg: IzhikevichConfig, wq, vq, x, u, sel):
    """Multipliers 1 and 3 (and 5, ``dt (I - u)``, when dt is not a power of two; when it is,
    ``dt I - dt u`` by shifts, the rounding of ``dt u`` folded into the subtraction)."""
    out = {"q": wq * cfg.KA.raw, "bvp": vq * _lookup([b.raw for b in cfg.beta], sel)}
    # y = round((b v - u) / 2**shift_y) is computed in stage 4 as (bvp - uy) >> shift_y with
    # uy = u << shift_b, minus half an LSB of y when rounding to nearest (exact, one adder)
    half_y = (1 << (cfg.shift_y - 1)) if cfg.rounding == "nearest" else 0
    out["uy"] = (u << cfg.shift_b) - half_y
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
    """Multipliers 2 and 4: (A dt w) w and (a dt)(b v - u). Meanwhile the addends of stage 5 are
    prepared, pre-shifted to the products' scale with the rounding half folded in, so that
    each sum of stage 5 is a single adder: ``v + dt (I - u) + dt (C - B^2/4A)`` for ``v'``,
    ``u`` and ``u + d`` for ``u'``."""
    r = cfg.rounding
    qq = saturate(round_shift(q, cfg.shift_q, r), cfg.Q, cfg.bounds_qq)
    y = saturate((bvp - uy) >> cfg.shift_y, cfg.Y, cfg.bounds_y)
    if cfg.dt_shift is not None:
        dx = x
    else:
        dx = round_shift(x, cfg.X.frac_bits + cfg.KDT.frac_bits - cfg.V.frac_bits, r)
    near = r == "nearest"
    vb = v + dx + cfg.K0.raw
    vb_sh = (vb << cfg.shift_p) + ((1 << (cfg.shift_p - 1)) if near else 0)
    # threshold and lower clamp of v' become sign tests of sums formed in stage 5:
    # v' >= v_th  <=>  vb_sh - (v_th << shift_p) + p >= 0   (likewise for V.min)
    vb_th = vb_sh - (cfg.VTH.raw << cfg.shift_p)
    vb_lo = vb_sh - (cfg.V.min_raw << cfg.shift_p)
    shifts = cfg.shift_a
    halves = [(1 << (sa - 1)) if near else 0 for sa in shifts]
    ud = u + _lookup([d.raw for d in cfg.d], sel)
    if len(set(shifts)) == 1:
        u_sh = (u << shifts[0]) + halves[0]
        ud_sh = (ud << shifts[0]) + halves[0]
    else:
        u_sh = _select_by(sel, [(u << sa) + h for sa, h in zip(shifts, halves)])
        ud_sh = _select_by(sel, [(ud << sa) + h for sa, h in zip(shifts, halves)])
    return {"p": qq * wq, "m": y * _lookup([a.raw for a in cfg.alpha], sel),
            "vb_sh": vb_sh, "vb_th": vb_th, "vb_lo": vb_lo, "u_sh": u_sh, "ud_sh": ud_sh}


def _select_by(sel, options):
    """``options[sel]`` (a mux in RTL, per-element choice in the twin)."""
    if is_hdl(sel):
        out = options[-1]
        for i in range(len(options) - 2, -1, -1):
            out = Mux(sel == i, options[i], out)
        return out
    return np.choose(np.asarray(sel), [np.broadcast_to(o, np.shape(sel)) for o in options])


def update_state(cfg: IzhikevichConfig, vb_sh, vb_th, vb_lo, u_sh, ud_sh, p, m, sel):
    """Sum, threshold, reset and saturation into the state formats:
    ``v' = (vb_sh + p) >> shift_p`` and ``u' = (u_sh + m) >> shift_a`` (or ``ud_sh`` on a
    spike, i.e. ``u' = sat(u + d + (a dt)(b v - u))`` with one saturation). The threshold test
    and the lower clamp of ``v'`` are signs of ``vb_th + p`` and ``vb_lo + p``; ``v'`` needs no
    upper clamp: above threshold it is replaced by ``c``."""
    v_pre = (vb_sh + p) >> cfg.shift_p
    spike = (vb_th + p) >= 0
    under = (vb_lo + p) < 0
    shifts = cfg.shift_a
    if len(set(shifts)) == 1:
        u_new, u_spk = (u_sh + m) >> shifts[0], (ud_sh + m) >> shifts[0]
    else:
        u_new = _select_by(sel, [(u_sh + m) >> sa for sa in shifts])
        u_spk = _select_by(sel, [(ud_sh + m) >> sa for sa in shifts])
    u_new, u_spk = saturate(u_new, cfg.U), saturate(u_spk, cfg.U)
    v_keep = select(under, cfg.V.min_raw, saturate(v_pre, cfg.V, (cfg.V.min_raw,
                                                                  cfg.VTH.raw)))
    v_out = select(spike, _lookup([c.raw for c in cfg.c], sel), v_keep)
    u_out = select(spike, u_spk, u_new)
    return {"v": v_out, "u": u_out, "spike": spike, "v_pre": v_pre}


# ----------------------------------------------------------------------------------------------
class IzhikevichTwin:
    """Bit-exact NumPy (int64) model of :class:`IzhikevichCore`, vectorized over neurons.

    State is held as raw integers in the core's formats; :meth:`sweep` performs one update of
    every neuron exactly as the RTL does. :meth:`update` computes updates from any given state
    (used by benches to check the DUT from its own previous state).
    """

    def __init__(self, config: IzhikevichConfig | None = None, **kwargs):
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        self.sel = np.asarray(cfg.neuron_sets, dtype=np.int64)
        self.v = np.full(cfg.n_neurons, cfg.V0.raw, dtype=np.int64)
        self.u = np.asarray([cfg.u0[s].raw for s in self.sel], dtype=np.int64)
        self.I = np.zeros(cfg.n_neurons, dtype=np.int64)
        self.sweeps = 0

    def set_currents(self, values_mv_per_ms, index=None) -> np.ndarray:
        """Quantize currents (mV/ms) like the host driver does and store them; returns raw."""
        raw = self.cfg.I.to_raw(values_mv_per_ms)
        if index is None:
            self.I[:] = raw
        else:
            self.I[index] = raw
        return raw

    def update(self, v, u, I, sel):
        """One update of the given neurons (raw int64 arrays); returns the stage-5 dict."""
        cfg = self.cfg
        v, u, I, sel = (np.asarray(x, dtype=np.int64) for x in (v, u, I, sel))
        s2 = operands(cfg, v, u, I)
        s3 = multiply1(cfg, s2["wq"], s2["vq"], s2["x"], u, sel)
        s4 = multiply2(cfg, s3["q"], s3["bvp"], s3["uy"], s2["wq"], v, u, s3["x"], sel)
        for k in ("q", "bvp", "x", "uy"):
            check_int64(k, s3[k])
        for k in ("p", "m", "vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh"):
            check_int64(k, s4[k])
        return update_state(cfg, *(s4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh",
                                                   "p", "m")), sel)

    def sweep(self):
        """Update every neuron once (one tick); returns the boolean spike vector."""
        out = self.update(self.v, self.u, self.I, self.sel)
        self.v, self.u = out["v"].astype(np.int64), out["u"].astype(np.int64)
        self.sweeps += 1
        return np.asarray(out["spike"], dtype=bool)

    def run(self, currents, n_sweeps: int) -> list[np.ndarray]:
        """Run ``n_sweeps`` ticks with currents given as a number, a (n_neurons,) array, or a
        callable ``f(t_ms) -> array``, read at the start of each update. Returns spike times (ms)
        per neuron with the golden convention (update k -> (k+1) dt)."""
        hits_k, hits_n = [], []
        for k in range(n_sweeps):
            cur = currents(k * self.cfg.dt_ms) if callable(currents) else currents
            self.set_currents(np.broadcast_to(cur, (self.cfg.n_neurons,)))
            spk = self.sweep()
            if spk.any():
                idx = np.flatnonzero(spk)
                hits_n.append(idx)
                hits_k.append(np.full(idx.size, k, dtype=np.int64))
        steps = golden.group_spikes(hits_k, hits_n, self.cfg.n_neurons)
        return [(s + 1) * self.cfg.dt_ms for s in steps]

    def v_mv(self):
        return self.cfg.V.to_float(self.v)

    def u_mv(self):
        return self.cfg.U.to_float(self.u)


# ----------------------------------------------------------------------------------------------
class IzhikevichCore(wiring.Component):
    """Time-multiplexed Izhikevich core: one neuron update per clock, 5-stage pipeline.

    Pipeline (a neuron's index enters at cycle t; its result is on ``upd_*`` at t+5):

    1. **Fetch** - the sweep counter addresses the state (v, u), current and set-select RAMs
       (synchronous read).
    2. **Read** - the RAM outputs are registered (no logic after the block RAM).
    3. **Operands, multiply 1** - ``w = v + 62.5`` and ``v`` rounded to multiplier width, then
       ``(A dt) w`` and ``b v``; ``dt I - dt u`` by shifts (or ``I - u`` rounded and
       multiplied by ``dt`` when dt is not a power of two).
    4. **Multiply 2** - ``((A dt) w) w`` and ``(a dt)(b v - u)``; meanwhile
       ``v + dt (I - u) + dt (C - B^2/4A)`` is summed.
    5. **Update** - add the products into ``v'`` and ``u'`` (rounding as a carry-in),
       threshold, reset, saturate; write back to the state RAM and register the outputs.

    Sweeps start on a tick (internal divider of ``clock_hz / update_hz`` cycles, or the ``tick``
    input with ``tick_source="external"``). A tick that arrives while a sweep is still being
    issued is ignored and sets the sticky ``overrun`` flag.

    Ports
    -----
    ``i_wr_en/i_wr_addr/i_wr_data``
        Host write of a neuron's input current (format ``config.I``). It lands in the current RAM
        only, which the pipeline never writes, so it cannot corrupt an update in flight; a write
        in the same cycle as that neuron's fetch is seen from the next sweep on.
    ``sel_wr_en/sel_wr_addr/sel_wr_data``
        Host write of a neuron's parameter-set index (same rules).
    ``spike_valid/spike_ready/spike_index/spike_sweep``
        Spike stream (FIFO of ``spike_fifo_depth``); when full, further spikes are dropped and
        the sticky ``spike_overflow`` flag is set - nothing is lost silently.
    ``upd_valid/upd_index/upd_v/upd_u/upd_current/upd_spike``
        Every update as it leaves the pipeline (for scoreboards and probes).
    ``sweep_done/sweep_count/sweep_number``
        Pulse in the cycle after the last update of a sweep is on ``upd_*``, with the number of
        spikes in that sweep and its number.
    """

    def __init__(self, config: IzhikevichConfig | None = None, **kwargs):
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        N = cfg.n_neurons
        sig = {
            "i_wr_en": In(1), "i_wr_addr": In(range(N)), "i_wr_data": In(cfg.I.shape()),
            "sel_wr_en": In(1), "sel_wr_addr": In(range(N)), "sel_wr_data": In(cfg.sel_bits),
            "spike_valid": Out(1), "spike_ready": In(1), "spike_index": Out(range(N)),
            "spike_sweep": Out(cfg.sweep_number_width), "spike_overflow": Out(1),
            "upd_valid": Out(1), "upd_index": Out(range(N)), "upd_v": Out(cfg.V.shape()),
            "upd_u": Out(cfg.U.shape()), "upd_current": Out(cfg.I.shape()),
            "upd_spike": Out(1),
            "sweep_done": Out(1), "sweep_count": Out(range(N + 1)),
            "sweep_number": Out(cfg.sweep_number_width), "overrun": Out(1), "busy": Out(1),
        }
        if cfg.tick_source == "external":
            sig["tick"] = In(1)
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        N = cfg.n_neurons
        m = Module()
        V, U = cfg.V, cfg.U

        def pack(v, u):
            return (v & ((1 << V.width) - 1)) | ((u & ((1 << U.width) - 1)) << V.width)

        init_state = [pack(cfg.V0.raw, cfg.u0[s].raw) for s in cfg.neuron_sets]
        m.submodules.state_mem = state_mem = Memory(shape=V.width + U.width, depth=N,
                                                    init=init_state)
        m.submodules.cur_mem = cur_mem = Memory(shape=cfg.I.shape(), depth=N, init=[])
        m.submodules.sel_mem = sel_mem = Memory(shape=cfg.sel_bits, depth=N,
                                                init=cfg.neuron_sets)
        st_rd, st_wr = state_mem.read_port(), state_mem.write_port()
        cur_rd, cur_wr = cur_mem.read_port(), cur_mem.write_port()
        sel_rd, sel_wr = sel_mem.read_port(), sel_mem.write_port()
        m.d.comb += [
            cur_wr.addr.eq(self.i_wr_addr), cur_wr.data.eq(self.i_wr_data),
            cur_wr.en.eq(self.i_wr_en),
            sel_wr.addr.eq(self.sel_wr_addr), sel_wr.data.eq(self.sel_wr_data),
            sel_wr.en.eq(self.sel_wr_en),
        ]

        # --- sweep control ------------------------------------------------------------------
        tick = Signal()
        if cfg.tick_source == "internal":
            div = Signal(range(cfg.cycles_per_tick))
            m.d.comb += tick.eq(div == 0)
            m.d.sync += div.eq(Mux(div == cfg.cycles_per_tick - 1, 0, div + 1))
        else:
            m.d.comb += tick.eq(self.tick)
        issuing = Signal()
        addr = Signal(range(N))
        sweep_no = Signal(cfg.sweep_number_width)
        started = Signal()
        last_issue = issuing & (addr == N - 1)
        start = tick & (~issuing | last_issue)   # a tick in the last issuing cycle is on time
        with m.If(tick & ~start):
            m.d.sync += self.overrun.eq(1)
        with m.If(start):
            m.d.sync += [issuing.eq(1), addr.eq(0), started.eq(1),
                         sweep_no.eq(Mux(started, sweep_no + 1, 0))]
        with m.Elif(issuing):
            m.d.sync += addr.eq(addr + 1)
            with m.If(last_issue):
                m.d.sync += issuing.eq(0)
        m.d.comb += self.busy.eq(issuing)

        for port in (st_rd, cur_rd, sel_rd):
            m.d.comb += [port.addr.eq(addr), port.en.eq(1)]

        # --- pipeline valid/index/sweep tags -----------------------------------------------
        def tag(n):
            return (Signal(name=f"valid{n}"), Signal(range(N), name=f"idx{n}"),
                    Signal(cfg.sweep_number_width, name=f"swp{n}"))
        t2, t3, t4, t5 = tag(2), tag(3), tag(4), tag(5)
        m.d.sync += [t2[0].eq(issuing), t2[1].eq(addr), t2[2].eq(sweep_no)]
        for a, b in ((t2, t3), (t3, t4), (t4, t5)):
            m.d.sync += [b[0].eq(a[0]), b[1].eq(a[1]), b[2].eq(a[2])]

        # --- stage 2: the RAM outputs go straight into registers -------------------------
        def reg(name, value, stage):
            sig_ = Signal(value.shape(), name=f"{name}{stage}")
            m.d.sync += sig_.eq(value)
            return sig_

        v3 = reg("v", st_rd.data[:V.width].as_signed(), 3)
        u3 = reg("u", st_rd.data[V.width:].as_signed(), 3)
        i3, sel3 = reg("i", cur_rd.data, 3), reg("sel", sel_rd.data, 3)
        # --- stage 3: operands and the first multipliers ----------------------------------
        s2 = operands(cfg, v3, u3, i3)
        wq3, vq3, x3 = s2["wq"], s2["vq"], s2["x"]
        s3 = multiply1(cfg, wq3, vq3, x3, u3, sel3)
        v4, u4, i4, sel4, wq4 = (reg(n, x, 4) for n, x in
                                 (("v", v3), ("u", u3), ("i", i3), ("sel", sel3), ("wq", wq3)))
        q4, bvp4, x4 = reg("q", s3["q"], 4), reg("bvp", s3["bvp"], 4), reg("x", s3["x"], 4)
        uy4 = reg("uy", s3["uy"], 4)
        # --- stage 4 ----------------------------------------------------------------------
        s4 = multiply2(cfg, q4, bvp4, uy4, wq4, v4, u4, x4, sel4)
        i5, sel5 = reg("i", i4, 5), reg("sel", sel4, 5)
        p5, m5 = reg("p", s4["p"], 5), reg("m", s4["m"], 5)
        sums5 = [reg(n, s4[n], 5) for n in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh")]
        # --- stage 5 ----------------------------------------------------------------------
        s5 = update_state(cfg, *sums5, p5, m5, sel5)
        v_out = Signal(V.shape())
        u_out = Signal(U.shape())
        spike = Signal()
        m.d.comb += [v_out.eq(s5["v"]), u_out.eq(s5["u"]), spike.eq(s5["spike"] & t5[0])]
        m.d.comb += [st_wr.addr.eq(t5[1]), st_wr.data.eq(Cat(v_out, u_out)),
                     st_wr.en.eq(t5[0])]
        m.d.sync += [self.upd_valid.eq(t5[0]), self.upd_index.eq(t5[1]), self.upd_v.eq(v_out),
                     self.upd_u.eq(u_out), self.upd_current.eq(i5), self.upd_spike.eq(spike)]

        # --- bookkeeping from the registered outputs (off the datapath's critical path) -----
        upd_sweep = Signal(cfg.sweep_number_width)
        m.d.sync += upd_sweep.eq(t5[2])
        count = Signal(range(N + 1))
        last = self.upd_valid & (self.upd_index == N - 1)
        m.d.sync += self.sweep_done.eq(last)
        with m.If(last):
            m.d.sync += [self.sweep_count.eq(count + self.upd_spike),
                         self.sweep_number.eq(upd_sweep), count.eq(0)]
        with m.Elif(self.upd_valid):
            m.d.sync += count.eq(count + self.upd_spike)

        # --- spike stream -----------------------------------------------------------------
        iw = (N - 1).bit_length() or 1
        m.submodules.spike_fifo = fifo = SyncFIFOBuffered(
            width=iw + cfg.sweep_number_width, depth=cfg.spike_fifo_depth)
        push = self.upd_valid & self.upd_spike
        m.d.comb += [fifo.w_data.eq(Cat(self.upd_index[:iw], upd_sweep)), fifo.w_en.eq(push),
                     self.spike_valid.eq(fifo.r_rdy), fifo.r_en.eq(self.spike_ready),
                     self.spike_index.eq(fifo.r_data[:iw]),
                     self.spike_sweep.eq(fifo.r_data[iw:])]
        with m.If(push & ~fifo.w_rdy):
            m.d.sync += self.spike_overflow.eq(1)
        return m
