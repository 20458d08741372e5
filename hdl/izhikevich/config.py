"""Configuration of the Izhikevich core: sizes, rates, parameter sets, and every format and
constant derived from them, with the refusals of what cannot be held.

The arithmetic is forward Euler, per parameter set ``s`` (see
:mod:`cuneate.hdl.izhikevich.datapath`)::

    w   = v + B_s/(2 A_s)                                  (rounded once into the v format)
    v'  = v + (A_s dt) w^2 + dt (C_s - A_s woff_s^2) + dt I - dt u
    u'  = u + (a_s dt) (b_s v - lambda_s u - b_s v_u,s)
    if v' >= v_th:  v' <- c_s,  u' <- u' + d_s

**The accepted input range is the proven range.** The configuration accepts currents in
``current_range`` (default: the whole current format) and derives, for every parameter set, the
range of ``v`` and ``u`` reachable for those currents (:mod:`cuneate.hdl.izhikevich.range`:
a documented worst-case search for ``u``, a proof for ``v`` from ``u``'s bound). The state
formats are sized to hold it (``v_int_bits``/``u_int_bits`` = None, the default) and the clamp
levels of the datapath sit just outside it: ``v`` never below ``v_floor``, ``u`` within
``[u_lo, u_hi]``. Every operand format follows by interval arithmetic, so the multiplier
operands need no clamp. A configuration whose formats are given narrower than the proven range
is refused, unless ``saturation="flag"`` accepts that clamps may act - they are then flagged on
every update, counted per sweep and listed in the JSON. A parameter set whose state diverges
within the accepted range is refused, naming it, the stimulus and the time.

Clamps (kinds, in the order of the ``upd_clamp``/``clamp_flags`` bits):

``v_low``  ``v'`` below ``v_floor`` (held at ``v_floor``);
``u_high`` / ``u_low``  ``u'`` above ``u_hi`` / below ``u_lo``;
``current``  a host current outside ``current_range`` (clamped to it before use);
``y``  the ``b v - u`` operand outside its format (only when ``y_int_bits`` narrows it).

Every configuration states the rounding its state registers take per update
(``state_rounding_per_step``: half an LSB of ``v`` and ``u`` when rounding to nearest, one LSB
when truncating) and warns when that is :data:`NARROW_STATE_RATIO` times the default formats'
or more: such formats can change spike counts many-fold against the golden model.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ...golden import izhikevich as golden
from ..lib.banked import DP16KD_SHAPES, block_shapes
from ..lib.config import (SATURATION, ConfigError, CoreOptions, int_bits_for, refusing,
                          shared_exponent, whole_cycles_per_tick)
from ..lib.fixed import FixedConstant, QFormat, round_shift
from .range import RangeSearchError, one_step_bound, reachable_ranges

__all__ = ["ConfigError", "IzhikevichConfig", "PIPELINE_DEPTH", "PIPELINE_STAGES", "PIPELINE_CUTS",
           "PIPELINE_READ", "min_neurons", "CLAMP_KINDS", "SATURATION", "NARROW_STATE_RATIO"]

#: How many times the default formats' per-update state rounding a configuration may take
#: before it warns (2**8: eight fraction bits fewer than the default's).
NARROW_STATE_RATIO = 2.0 ** 8

PIPELINE_DEPTH = 5      # the default (the reference core's): fetch, read, 3 datapath stages
#: Registered cuts of the datapath (after step ``k`` of :data:`~cuneate.hdl.izhikevich.datapath
#: .STEPS`: 0 operands, 1 multiply 1, 2 align, 3 multiply 2, 4 sums; step 5, select, ends in
#: the write-back) for each ``pipeline_stages`` (see :mod:`cuneate.hdl.izhikevich.core`; fmax
#: per depth in docs/architecture.md).
PIPELINE_CUTS = {5: (2, 3), 6: (2, 3, 4), 7: (1, 2, 3, 4), 8: (0, 1, 2, 3, 4),
                 9: (0, 1, 2, 3, 4)}
#: Stages from a fetch to its memories' words: 1 read a cycle ahead (the next address), 2 read
#: from the fetch's register, the host's writes registered too (:mod:`cuneate.hdl.lib.banked`).
PIPELINE_READ = {5: 1, 6: 1, 7: 1, 8: 1, 9: 2}
#: The pipeline depths offered (``pipeline_stages``).
PIPELINE_STAGES = tuple(PIPELINE_CUTS)


def min_neurons(pipeline_stages: int = PIPELINE_DEPTH) -> int:
    """The fewest neurons a core of this depth holds: a neuron's write-back lands ``depth``
    cycles after its fetch and must be in its memory by its next fetch (read a cycle ahead,
    it lands as the word is sampled and is bypassed into it)."""
    return pipeline_stages + 1
CLAMP_KINDS = ("v_low", "u_high", "u_low", "current", "y")
_REL = 2.0 ** -12          # largest relative representation error accepted for a constant
_INT64_GUARD = 1 << 62


def _shared_exponent(name: str, values: Sequence[float], width: int, nominal: float = 1.0):
    """Constants sharing one exponent (see :func:`~cuneate.hdl.lib.config.shared_exponent`),
    each within the relative error every constant of the core is held to."""
    return shared_exponent(name, values, width, nominal, max_rel_error=_REL)


@dataclass
class IzhikevichConfig(CoreOptions):
    """Everything that defines a core: size, rates, formats, constants, parameter sets.

    Parameters
    ----------
    n_neurons
        Neurons sharing the core (default 2500).
    clock_hz, update_hz
        Core clock and per-neuron update rate; ``dt = 1000 / update_hz`` ms and
        ``cycles_per_tick = clock_hz / update_hz`` (an integer >= ``n_neurons``).
    param_sets
        Table of parameter sets: preset names, :class:`~cuneate.golden.izhikevich
        .IzhikevichParams` (any ``a, b, c, d``, per-set ``A, B, C`` and u-equation form), 4-tuples
        ``(a, b, c, d)`` or mappings; per-neuron selection.
    neuron_sets
        Initial set index of each neuron (default all 0); writable by the host at run time.
    v_init, u_init
        Initial state of each neuron (default ``v0`` and ``b v0`` of the neuron's set).
    current_range
        Accepted input currents ``(lo, hi)`` in mV/ms (default: the whole current format). The
        state formats are sized for it; currents outside it are clamped and flagged.
    saturation
        ``"refuse"`` (default): refuse formats narrower than the proven state range;
        ``"flag"``: accept them, the clamps that can then act being flagged and counted.
    operand_width
        Multiplier operand width (18 for the 18x18 DSP blocks of Spartan-6 and ECP5).
    v_int_bits, u_int_bits
        Integer bits of the state formats (None: the fewest that hold the proven range).
        ``state_int_bits`` sets both (kept for older callers).
    v_frac_bits, u_frac_bits
        Fraction bits of the state formats (state lives in block RAM; adders only).
    current_format
        Format of the input current written by the host (default sQ10.8, +-512 mV/ms).
    rounding
        ``"nearest"`` (default) or ``"truncate"`` at every narrowing.
    tick_source
        ``"internal"`` (divider of ``clock_hz / update_hz``) or ``"external"`` (``tick`` input).
    spike_fifo_depth, sweep_number_width
        Spike stream buffering and the width of the (wrapping) sweep number.
    pipeline_stages
        Pipeline depth, one of :data:`PIPELINE_STAGES` (default 5, the reference core's):
        cycles from a neuron's fetch to its result on ``upd_*``. Deeper pipelines register more
        cuts of the same datapath (the arithmetic does not change); a neuron's state is read
        again at the earliest ``n_neurons`` cycles after its fetch, its memories are read a
        cycle ahead of the fetch (a write landing then is bypassed) and its write-back is
        registered before the RAM, so ``n_neurons`` must be at least the depth + 1 (depth 9
        reads them at the fetch instead, a stage later: :data:`PIPELINE_READ`).
    bram_shapes
        ``(depth, width)`` modes of the target's block RAM (default the ECP5 DP16KD's): the
        memories are built in banks of the best shape, each bank's word registered beside its
        RAM (:mod:`cuneate.hdl.lib.banked`).
    y_int_bits
        Integer bits of the ``b v - u`` operand. Default: the fewest that provably hold every
        state (no clamp); fewer bits add a flagged clamp.
    y_frac_bits
        Fewest fraction bits of the ``b v - u`` operand (default ``operand_width - 9``). ``u``
        integrates the rounding error of this operand, so its LSB is kept and a wider state
        range widens the operand (the ``(a dt) y`` multiplier) rather than coarsening it.
    """

    n_neurons: int = 2500
    clock_hz: float = 40e6
    update_hz: float = 16e3
    param_sets: tuple = ("RS",)
    neuron_sets: Sequence[int] | None = None
    operand_width: int = 18
    state_int_bits: int | None = None
    v_int_bits: int | None = None
    u_int_bits: int | None = None
    v_frac_bits: int = 18
    u_frac_bits: int = 20
    current_format: QFormat = QFormat(10, 8)
    current_range: tuple[float, float] | None = None
    y_int_bits: int | None = None
    y_frac_bits: int | None = None
    v0: float = golden.V0
    v_th: float = golden.V_TH
    v_init: Sequence[float] | None = None
    u_init: Sequence[float] | None = None
    pipeline_stages: int = PIPELINE_DEPTH
    bram_shapes: tuple = DP16KD_SHAPES

    # derived (filled by __post_init__)
    sets: list = field(init=False, repr=False)

    def __post_init__(self):
        self.param_sets = tuple(self.param_sets)
        # parameter-set errors from the golden model are ValueErrors
        with refusing("Izhikevich core configuration", RangeSearchError, ValueError):
            self._derive()

    # ------------------------------------------------------------------------------------------
    def _derive(self):
        self._check_sizes()
        self.params = [golden.to_params(p) for p in self.param_sets]
        self.sets = [p.as_tuple() for p in self.params]
        for i, p in enumerate(self.params):
            if not p.c < self.v_th:
                raise ConfigError(f"parameter set {i} {p.label()}: reset c = {p.c:g} is not "
                                  f"below threshold {self.v_th:g}")
        self.dt_ms = 1000.0 / self.update_hz
        self._derive_inputs()
        self._derive_state()
        self._derive_constants()
        self._derive_operands()
        self._derive_bounds()
        self._check_int64()

    def _check_sizes(self):
        N = self.n_neurons
        D = self.pipeline_stages
        if isinstance(D, bool) or D not in PIPELINE_STAGES:
            raise ConfigError(f"pipeline_stages must be one of "
                              f"{', '.join(map(str, PIPELINE_STAGES))}, got {D!r}")
        self.pipeline_stages = D = int(D)
        self.cuts = PIPELINE_CUTS[D]
        self.read_stages = PIPELINE_READ[D]
        if not isinstance(N, (int, np.integer)) or N < min_neurons(D):
            raise ConfigError(f"n_neurons must be an integer >= {min_neurons(D)} at pipeline "
                              f"depth {D} (a neuron's registered write-back must land by the "
                              f"time its memories are read again), got {N!r}")
        shapes = block_shapes(self.bram_shapes)
        if shapes is None:
            raise ConfigError(f"bram_shapes must be (depth, width) pairs of positive integers, "
                              f"each depth a power of two, got {self.bram_shapes!r}")
        self.bram_shapes = shapes
        self.cycles_per_tick = whole_cycles_per_tick(self.clock_hz, self.update_hz)
        if N > self.cycles_per_tick:
            raise ConfigError(
                f"{N} neurons do not fit one sweep: at {self.clock_hz:g} Hz and "
                f"{self.update_hz:g} Hz per neuron the core has {self.cycles_per_tick} cycles "
                f"per update (at most {self.cycles_per_tick} neurons)")
        self._check_options()
        if not isinstance(self.operand_width, (int, np.integer)) or self.operand_width < 8:
            raise ConfigError("operand_width must be an integer >= 8")
        for k in ("v_frac_bits", "u_frac_bits"):
            v = getattr(self, k)
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise ConfigError(f"{k} must be an integer >= 1, got {v!r}")
        if not self.param_sets:
            raise ConfigError("at least one parameter set is needed")
        if self.state_int_bits is not None:
            self.v_int_bits = self.v_int_bits if self.v_int_bits is not None else \
                self.state_int_bits
            self.u_int_bits = self.u_int_bits if self.u_int_bits is not None else \
                self.state_int_bits
        for k in ("v_int_bits", "u_int_bits", "y_int_bits"):
            v = getattr(self, k)
            if v is not None and (not isinstance(v, (int, np.integer)) or v < 2):
                raise ConfigError(f"{k} must be an integer >= 2, got {v!r}")

    def _derive_inputs(self):
        """Accepted currents, per-neuron set selection and initial states."""
        N = self.n_neurons
        self.I = I = self.current_format
        lo, hi = (I.min_value, I.max_value) if self.current_range is None else \
            tuple(float(x) for x in self.current_range)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ConfigError(f"current_range must be two finite numbers lo < hi, got "
                              f"{self.current_range!r}")
        if not (I.contains(lo) and I.contains(hi)):
            raise ConfigError(f"current_range [{lo:g}, {hi:g}] is outside the current format "
                              f"{I} [{I.min_value:g}, {I.max_value:g}]")
        # endpoints quantized as the host quantizes currents (to nearest); the range search
        # runs over these quantized values
        self.i_lo_raw, self.i_hi_raw = int(I.to_raw(lo)), int(I.to_raw(hi))
        self.i_lo, self.i_hi = I.to_float(self.i_lo_raw), I.to_float(self.i_hi_raw)
        self.current_clamp = (self.i_lo_raw, self.i_hi_raw) != (I.min_raw, I.max_raw)
        ns = [0] * N if self.neuron_sets is None else [int(s) for s in self.neuron_sets]
        if len(ns) != N or any(not 0 <= s < len(self.params) for s in ns):
            raise ConfigError(f"neuron_sets needs {N} indices in [0, {len(self.params)})")
        self.neuron_sets = ns
        v_init = np.full(N, float(self.v0)) if self.v_init is None else \
            np.asarray(self.v_init, dtype=np.float64)
        if v_init.shape != (N,) or not np.all(np.isfinite(v_init)):
            raise ConfigError(f"v_init needs {N} finite values")
        b_of = np.array([self.params[s].b for s in ns])
        u_init = b_of * v_init if self.u_init is None else \
            np.asarray(self.u_init, dtype=np.float64)
        if u_init.shape != (N,) or not np.all(np.isfinite(u_init)):
            raise ConfigError(f"u_init needs {N} finite values")
        if np.any(v_init >= self.v_th):
            raise ConfigError(f"an initial v is not below threshold {self.v_th:g}")
        self._v_init, self._u_init = v_init, u_init
        # initial states the search starts from: each set's (v0, b v0) and every distinct
        # per-neuron initial state of that set
        self._inits = []
        for i, p in enumerate(self.params):
            pairs = {(float(self.v0), float(p.b * self.v0))}
            pairs |= {(float(v), float(u)) for v, u, s in zip(v_init, u_init, ns) if s == i}
            self._inits.append(tuple(sorted(pairs)))

    def _derive_state(self):
        """State formats and clamp levels from the proven reachable range."""
        self.ranges = reachable_ranges(self.params, self.dt_ms, self.i_lo, self.i_hi,
                                       self._inits, self.v_th)
        v_floor = min(r.v_floor for r in self.ranges)
        u_lo = min(r.u_lo for r in self.ranges)
        u_hi = max(r.u_hi for r in self.ranges)
        # the state must also hold the resets, the initial states and u + d after a reset
        v_need_lo = min([v_floor] + [p.c for p in self.params] + list(self._v_init))
        u_need = [u_lo, u_hi] + list(self._u_init)
        self.proven = {"v": (v_need_lo, self.v_th), "u": (min(u_need), max(u_need))}
        ib_v = int_bits_for(v_need_lo, self.v_th)
        ib_u = int_bits_for(min(u_need), max(u_need))
        self.v_int_bits_derived, self.u_int_bits_derived = ib_v, ib_u
        narrow = []
        if self.v_int_bits is None:
            self.v_int_bits = ib_v
        elif self.v_int_bits < ib_v:
            narrow.append(("v", self.v_int_bits, ib_v, f"[{v_need_lo:.1f}, {self.v_th:g}]"))
        if self.u_int_bits is None:
            self.u_int_bits = ib_u
        elif self.u_int_bits < ib_u:
            narrow.append(("u", self.u_int_bits, ib_u, f"[{min(u_need):.1f}, "
                                                      f"{max(u_need):.1f}]"))
        if narrow and self.saturation == "refuse":
            what = "; ".join(f"{n} needs {need} integer bits for its proven range {rng}, "
                             f"{have} given" for n, have, need, rng in narrow)
            raise ConfigError(
                f"state formats too narrow for the accepted currents [{self.i_lo:g}, "
                f"{self.i_hi:g}] mV/ms: {what}; widen them, narrow current_range, or accept "
                f"flagged clamps with saturation='flag'")
        self.V = V = QFormat(self.v_int_bits, self.v_frac_bits)
        self.U = U = QFormat(self.u_int_bits, self.u_frac_bits)
        if not V.contains(self.v_th) or V.to_raw(self.v_th) * V.lsb != self.v_th:
            raise ConfigError(f"v_th = {self.v_th:g} is not exactly representable in {V}")
        self._state_rounding(V, U)
        # clamp levels: just outside the proven range, never outside the formats
        self.v_floor_raw = max(V.min_raw, int(math.floor(v_floor * 2 ** V.frac_bits)))
        self.u_lo_raw = max(U.min_raw, int(math.floor(u_lo * 2 ** U.frac_bits)))
        self.u_hi_raw = min(U.max_raw, int(math.ceil(u_hi * 2 ** U.frac_bits)))
        self.v_floor = V.to_float(self.v_floor_raw)
        self.u_lo, self.u_hi = U.to_float(self.u_lo_raw), U.to_float(self.u_hi_raw)
        for i, p in enumerate(self.params):
            if p.c < self.v_floor:
                raise ConfigError(f"parameter set {i} {p.label()}: reset c = {p.c:g} is below "
                                  f"the v clamp level {self.v_floor:g} of {V}")
        if np.any(self._v_init < self.v_floor) or np.any(self._u_init < self.u_lo) or \
                np.any(self._u_init > self.u_hi):
            raise ConfigError(f"an initial state lies outside the state clamps (v >= "
                              f"{self.v_floor:g}, u in [{self.u_lo:g}, {self.u_hi:g}])")
        # which clamps can act for accepted inputs from reachable states
        self.clamp_can_act = {
            "v_low": bool(self.v_floor > min(r.v_floor_proven for r in self.ranges)),
            "u_high": bool(self.u_hi < max(r.u_max_search for r in self.ranges)),
            "u_low": bool(self.u_lo > min(r.u_min_search for r in self.ranges)),
            "current": False,       # currents outside the accepted range are not accepted
            "y": False,             # set in _derive_operands
        }

    def _derive_constants(self):
        ow, dt, V, U = self.operand_width, self.dt_ms, self.V, self.U
        P = self.params
        # completing the square per set: w = v + B/(2A), rounded once into the v format
        self.woff = [FixedConstant.in_format(f"B/(2A)[{i}]", p.B / (2 * p.A), V)
                     for i, p in enumerate(P)]
        self.KA = _shared_exponent("A*dt", [p.A * dt for p in P], ow)
        self.K0 = [FixedConstant.in_format(f"dt*(C-A*woff^2)[{i}]",
                                           dt * (p.C - p.A * w.quantized ** 2), V)
                   for i, (p, w) in enumerate(zip(P, self.woff))]
        self.VTH = FixedConstant.in_format("v_th", self.v_th, V, exact=True)
        log2dt = math.log2(dt)
        self.dt_shift = -int(log2dt) if log2dt == int(log2dt) else None
        self.KDT = None if self.dt_shift is not None else FixedConstant.normalized("dt", dt, ow)
        self.beta = _shared_exponent("b", [p.b for p in P], ow)
        alpha_ref = [p.a * dt for p in P]
        self.alpha = []
        nz = [x for x in alpha_ref if x]
        for i, x in enumerate(alpha_ref):
            if x:
                self.alpha.append(FixedConstant.normalized(f"a*dt[{i}]", x, ow,
                                                           max_rel_error=_REL))
            else:   # a = 0: no recovery dynamics; share a nonzero set's shift if there is one
                ref = FixedConstant.normalized("a*dt", nz[0] if nz else dt * 0.02, ow)
                self.alpha.append(FixedConstant(f"a*dt[{i}]", 0.0, 0, ref.frac_bits, ow))
        self.c = [FixedConstant.in_format(f"c[{i}]", p.c, V) for i, p in enumerate(P)]
        self.d = [FixedConstant.in_format(f"d[{i}]", p.d, U) for i, p in enumerate(P)]
        # u-equation form: y = b v - (lambda u + b v_u)
        self.E = [FixedConstant.in_format(f"b*v_u[{i}]", b.quantized * p.v_u, U)
                  for i, (p, b) in enumerate(zip(P, self.beta))]
        self.u_leak = [int(p.u_leak) for p in P]
        self.V0 = FixedConstant.in_format("v0", self.v0, V)
        self.u0 = [FixedConstant.in_format(f"u0[{i}]", p.b * self.v0, U)
                   for i, p in enumerate(P)]
        self.v_init_raw = V.to_raw(self._v_init)
        self.u_init_raw = U.to_raw(self._u_init)
        self.sel_bits = max(1, (len(P) - 1).bit_length())

    def _derive_operands(self):
        ow, V, U = self.operand_width, self.V, self.U
        vf, vt = self.v_floor, self.v_th
        wo = [w.quantized for w in self.woff]
        v_lo = min(vf, min(c.quantized for c in self.c))
        self.W = QFormat.for_range(v_lo + min(wo), vt + max(wo), ow)   # w = v + B/(2A)
        self.VQ = QFormat.for_range(v_lo, vt, ow)                      # v as the b v operand
        ka_max = max(abs(k.quantized) for k in self.KA)
        q_max = ka_max * max(abs(self.W.min_value), abs(self.W.max_value))
        self.Q = QFormat.for_range(-q_max, q_max, ow)
        if self.KDT is not None:
            self.x_range = (self.i_lo - self.u_hi, self.i_hi - self.u_lo)   # I - u
            x_max = max(abs(x) for x in self.x_range) + 1.0
            self.X = QFormat.for_range(-x_max, x_max, ow)
        else:
            self.X = None
        # y = b v - lambda u - b v_u over the state box, per set
        ylo, yhi = [], []
        for b, lam, E in zip(self.beta, self.u_leak, self.E):
            bv = [b.quantized * vf, b.quantized * vt]
            lu = [lam * self.u_lo, lam * self.u_hi]
            ylo.append(min(bv) - max(lu) - E.quantized)
            yhi.append(max(bv) - min(lu) - E.quantized)
        self.y_range = (min(ylo), max(yhi))
        # y keeps at least y_frac_bits fraction bits (default operand_width - 9: the LSB an
        # operand has for |y| < 256); a wider y range widens the operand instead of coarsening
        # it, because u integrates y's rounding error
        yf = ow - 9 if self.y_frac_bits is None else self.y_frac_bits
        if yf < 1:
            raise ConfigError(f"y_frac_bits must be >= 1, got {yf}")
        y_ib = int_bits_for(*self.y_range)
        yfit = QFormat.for_range(*self.y_range, max(ow, y_ib + yf))
        if self.y_int_bits is None:
            self.Y = yfit
        else:
            self.Y = QFormat(self.y_int_bits, max(ow - self.y_int_bits, yf))
            self.clamp_can_act["y"] = bool(self.y_int_bits < yfit.int_bits)
        # shifts aligning products to the state formats
        self.shift_p = self.Q.frac_bits + self.W.frac_bits - V.frac_bits
        self.shift_q = self.KA[0].frac_bits + self.W.frac_bits - self.Q.frac_bits
        self.shift_b = self.beta[0].frac_bits + self.VQ.frac_bits - U.frac_bits
        self.shift_y = self.shift_b + U.frac_bits - self.Y.frac_bits
        self.shift_a = [a.frac_bits + self.Y.frac_bits - U.frac_bits for a in self.alpha]
        for name, s in [("b*v", self.shift_y), ("(a dt) y", min(self.shift_a)),
                        ("q", self.shift_q), ("p", self.shift_p)]:
            if s < 1:
                raise ConfigError(f"product {name} has fewer fraction bits than its target "
                                  f"format; reduce the state fraction bits")
        if self.shift_b < 0:
            raise ConfigError("b v has fewer fraction bits than u; reduce u_frac_bits")
        # worst-case v before the reset (reported; the sum is computed at full width)
        f_max = max(p.A * self.v_th ** 2 + p.B * self.v_th + p.C for p in self.params) \
            - self.u_lo + self.i_hi
        self.v_pre_max = self.v_th + self.dt_ms * max(f_max, 0.0)

    def _derive_bounds(self):
        """Proven raw bounds of the narrowed operands (every map below is monotone), used to
        leave out clamp logic that can never act."""
        r = self.rounding
        sv = self.V.frac_bits - self.W.frac_bits
        lo = min(self.v_floor_raw, min(c.raw for c in self.c))
        hi = self.VTH.raw
        svq = self.V.frac_bits - self.VQ.frac_bits
        self.bounds_vq = (round_shift(lo, svq, r), round_shift(hi, svq, r))
        wr = [w.raw for w in self.woff]
        self.bounds_wq = (round_shift(lo + min(wr), sv, r), round_shift(hi + max(wr), sv, r))
        q_ends = [w * k.raw for w in self.bounds_wq for k in self.KA]
        self.bounds_qq = (round_shift(min(q_ends), self.shift_q, r),
                          round_shift(max(q_ends), self.shift_q, r))
        half_y = (1 << (self.shift_y - 1)) if r == "nearest" else 0
        ylo, yhi = [], []
        for b, lam, E in zip(self.beta, self.u_leak, self.E):
            bvp = [vq * b.raw for vq in self.bounds_vq]
            uy = [(lam * u + E.raw) << self.shift_b for u in (self.u_lo_raw, self.u_hi_raw)]
            ylo.append(min(bvp) - max(uy) + half_y)
            yhi.append(max(bvp) - min(uy) + half_y)
        self.bounds_y = (min(ylo) >> self.shift_y, max(yhi) >> self.shift_y)
        if self.X is not None:
            sx = self.U.frac_bits - self.X.frac_bits
            xi = [round_shift(i, self.I.frac_bits - self.U.frac_bits, r)
                  for i in (self.i_lo_raw, self.i_hi_raw)]
            self.bounds_x = (round_shift(xi[0] - self.u_hi_raw, sx, r),
                             round_shift(xi[1] - self.u_lo_raw, sx, r))
        # the pipelined datapath multiplies floors (slices of registers) and adds the rounding
        # increments separately: their proven bounds and the formats that hold them
        sh = (lambda x, k: x >> k if k >= 0 else x << -k)
        self.bounds_vsq = (sh(lo, svq), sh(hi, svq))
        self.bounds_vsw = (sh(lo, sv), sh(hi, sv))
        self.bounds_qqf = (min(q_ends) >> self.shift_q, max(q_ends) >> self.shift_q)
        qd = (self.bounds_qqf[0] - 1, self.bounds_qqf[1])    # floors' sum (datapath: q_split)
        self.q_split = QFormat.for_raw(*qd, self.Q.frac_bits).width <= self.operand_width
        if self.q_split:
            self.bounds_qqf = qd
        self.VSQ = QFormat.for_raw(*self.bounds_vsq, self.VQ.frac_bits)
        self.VSW = QFormat.for_raw(*self.bounds_vsw, self.W.frac_bits)
        self.QQF = QFormat.for_raw(*self.bounds_qqf, self.Q.frac_bits)
        # y wider than a multiplier operand: y = y_hi 2**k + y_lo, the y_lo (a dt) term added
        # beside the product (k <= 3: a choice of 2**k constants)
        k = self.Y.width - self.operand_width
        self.y_split = k if 0 < k <= 3 else 0
        # y + borrow fits Y and no y clamp can act (datapath: y_borrow)
        self.y_borrow = self.Y.min_raw <= self.bounds_y[0] and self.bounds_y[1] < self.Y.max_raw
        # every unflagged narrowing must be proven: refuse here rather than build a silent clamp
        for name, b, fmt in (("v operand", self.bounds_vq, self.VQ),
                             ("w operand", self.bounds_wq, self.W),
                             ("q operand", self.bounds_qq, self.Q)) + \
                (("I - u operand", self.bounds_x, self.X),) if self.X is not None else ():
            if not fmt.min_raw <= b[0] <= b[1] <= fmt.max_raw:
                raise ConfigError(f"{name}: proven range {b} does not fit {fmt}")

    def _check_int64(self):
        """The twin's widest intermediates, bounded once from the formats (no per-sweep check
        is needed for a configuration that passes this): the u sum ``(u + d) << shift_a +
        (a dt) y`` and the v sum ``(v + dx + K0) << shift_p + q w``."""
        a_w = max(a.width for a in self.alpha)
        u_bits = max(self.U.width + 1 + max(self.shift_a), self.Y.width + a_w) + 1
        v_bits = max(self.V.width + 2 + self.shift_p, self.Q.width + self.W.width) + 1
        self.widest_sum_bits = max(u_bits, v_bits)
        if self.widest_sum_bits >= 62:
            raise ConfigError(f"the datapath's widest sum needs {self.widest_sum_bits} bits; "
                              f"reduce the state fraction bits or the operand widths")

    def _state_rounding(self, V: QFormat, U: QFormat) -> None:
        """``state_rounding_per_step`` (mV for v, u's unit for u), and a warning when it is
        :data:`NARROW_STATE_RATIO` times the default formats' or more."""
        k = 0.5 if self.rounding == "nearest" else 1.0
        self.state_rounding_per_step = {"v_mV": k * V.lsb, "u": k * U.lsb}
        fields = type(self).__dataclass_fields__
        ratio = max(V.lsb * 2.0 ** fields["v_frac_bits"].default,
                    U.lsb * 2.0 ** fields["u_frac_bits"].default)
        if ratio >= NARROW_STATE_RATIO:
            warnings.warn(f"state formats {V} (v) and {U} (u) round v by up to {k * V.lsb:.3g} mV "
                          f"and u by up to {k * U.lsb:.3g} per update, {ratio:g} times the "
                          f"default formats' (v_frac_bits {fields['v_frac_bits'].default}, "
                          f"u_frac_bits {fields['u_frac_bits'].default}): spike counts may "
                          f"differ from the golden model's many-fold", stacklevel=3)

    # ------------------------------------------------------------------------------------------
    def to_kwargs(self, **override) -> dict:
        """JSON-friendly constructor keywords that rebuild this exact configuration (derived
        integer bits included), with ``override`` applied; see :meth:`from_kwargs`."""
        kw = {
            "n_neurons": int(self.n_neurons), "clock_hz": float(self.clock_hz),
            "update_hz": float(self.update_hz),
            "param_sets": [p.to_dict() | {"A": p.A, "B": p.B, "C": p.C, "u_leak": p.u_leak,
                                          "v_u": p.v_u} for p in self.params],
            "neuron_sets": [int(s) for s in self.neuron_sets],
            "operand_width": int(self.operand_width), "v_int_bits": int(self.V.int_bits),
            "u_int_bits": int(self.U.int_bits), "v_frac_bits": int(self.V.frac_bits),
            "u_frac_bits": int(self.U.frac_bits),
            "current_format": [self.I.int_bits, self.I.frac_bits],
            "current_range": [self.i_lo, self.i_hi], "saturation": self.saturation,
            "rounding": self.rounding, "tick_source": self.tick_source,
            "spike_fifo_depth": int(self.spike_fifo_depth),
            "sweep_number_width": int(self.sweep_number_width),
            "y_int_bits": self.y_int_bits, "y_frac_bits": self.y_frac_bits,
            "v0": float(self.v0), "v_th": float(self.v_th),
            "v_init": [float(x) for x in self._v_init], "u_init": [float(x) for x in self._u_init],
            "pipeline_stages": int(self.pipeline_stages),
            "bram_shapes": [list(s) for s in self.bram_shapes],
        }
        kw.update(override)
        return kw

    @classmethod
    def from_kwargs(cls, kw: dict) -> "IzhikevichConfig":
        """The configuration from :meth:`to_kwargs` output (or any JSON with the same keys)."""
        kw = dict(kw)
        if "param_sets" in kw:
            kw["param_sets"] = tuple(tuple(p) if isinstance(p, list) else p
                                     for p in kw["param_sets"])
        if isinstance(kw.get("current_format"), (list, tuple)):
            kw["current_format"] = QFormat(*kw["current_format"])
        if kw.get("current_range") is not None:
            kw["current_range"] = tuple(kw["current_range"])
        return cls(**kw)

    # ------------------------------------------------------------------------------------------
    # per-neuron views
    def neuron_params(self, sel) -> golden.NeuronParams:
        """Golden-model parameter arrays for the set indices ``sel``."""
        return golden.NeuronParams.from_sets([self.params[int(s)] for s in np.ravel(sel)])

    def golden_step(self, v, u, I, sel, dtype=np.float64):
        """float64 forward Euler one step from the given float state with each neuron's set."""
        p = self.neuron_params(sel)
        v, u, I = (np.asarray(x, dtype=dtype) for x in (v, u, I))
        return golden.step(v, u, I, p.a, p.b, p.c, p.d, self.dt_ms, "euler", **p.extras())

    def one_step_bound(self, v, u, I, sel=None):
        """Upper bounds (mV) on |v' - v'_golden| and |u' - u'_golden| for one update from the
        state ``(v, u)`` (see :func:`cuneate.hdl.izhikevich.range.one_step_bound`)."""
        return one_step_bound(self, v, u, I, sel)

    # ------------------------------------------------------------------------------------------
    def clamps_dict(self) -> dict:
        """The clamps, their levels and whether each can act (see :mod:`.describe`)."""
        from .describe import clamps_dict
        return clamps_dict(self, CLAMP_KINDS)

    def to_dict(self) -> dict:
        """Everything a user of the generated Verilog needs (written beside it as JSON; see
        :mod:`.describe`)."""
        from .describe import describe
        return describe(self, CLAMP_KINDS)
