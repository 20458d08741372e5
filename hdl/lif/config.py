"""Configuration of the fixed-point LIF core: formats, constants, proven ranges, refusals.

:class:`LifConfig` turns the user's parameters into everything the datapath needs, and refuses
(:class:`ConfigError`, at construction) what the formats cannot hold:

* decay constants that round to 0 or 1, or miss ``max_decay_error`` (also a shift's 2**-s);
* weights outside their format (given ``weight_frac_bits``), thresholds, resets, rests;
* a fan-in whose weight sum can leave ``input_limit`` (refused, or clamped and flagged with
  ``saturation="flag"``), an accumulator narrower than its fan-in needs;
* a state format narrower than the proven state range (refused, or flagged ``v_low`` clamp);
* a parameter set that is not one, a weight memory no supported FPGA holds, formats wider than
  the twin's int64 carries, a leak that never acts below threshold (:mod:`.checks`).

The leak is written for both forms as one subtraction of a product::

    continuous:  v' = v - k (v - v_rest - D),   k = 1 - exp(-dt/tau_m)   (exact integration)
    discrete:    u' = u - k u + D,              k = 1 - alpha

where ``D = I + sum_i w_i x_i`` is the neuron's total input of this tick (host current plus the
weighted input spikes). ``decay="multiply"`` multiplies by ``k`` (one multiplier, constants of
all parameter sets share one exponent); ``decay="shift"`` uses ``k = 2**-s`` (no multiplier),
accepted only when that power of two is within ``max_decay_error`` of the exact ``k``.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ...golden import lif as golden
from ..lib.config import MIN_NEURONS, SATURATION, ConfigError, CoreOptions, check_delays, \
    int_bits_for, whole_cycles_per_tick
from ..lib.fixed import FixedConstant, QFormat
from .checks import (MAX_OPERAND_WIDTH, MAX_V_FRAC_BITS, MAX_WEIGHT_BITS, LifSet, check_int64,
                     check_leak, check_weight_memory)

__all__ = ["ConfigError", "LifConfig", "LifSet", "PIPELINE_DEPTH", "CLAMP_KINDS", "FORMS",
           "DECAYS", "SATURATION", "MAX_INPUT_DELAY"]

PIPELINE_DEPTH = 5
CLAMP_KINDS = ("current", "input", "v_low")
FORMS = ("continuous", "discrete")
DECAYS = ("multiply", "shift")
_GRID_EPS = 1e-9
MAX_INPUT_DELAY = 64    #: the longest input delay the core's input history holds (ticks)


@dataclass
class LifConfig(CoreOptions):
    """A time-multiplexed LIF core (see :class:`cuneate.hdl.lif.LifCore`).

    Parameters
    ----------
    n_neurons, clock_hz, update_hz
        Neurons on the core (>= 8), clock, per-neuron update rate; ``clock_hz / update_hz``
        must be an integer number of cycles >= ``n_neurons``. ``dt_ms = 1000 / update_hz``.
    form
        ``"continuous"`` (mV, ms; exact exponential integration) or ``"discrete"``.
    param_sets, neuron_sets
        Parameter sets (dicts, see :class:`LifSet`; defaults from :mod:`cuneate.golden.lif`)
        and the set index of every neuron (default all 0; host-writable at run time).
    decay
        ``"multiply"`` or ``"shift"`` (see the module docstring).
    v_frac_bits, v_int_bits
        State format; integer bits derived from the proven range unless given.
    operand_width
        Multiplier operand width (the leak operand and ``k``).
    current_format, current_range
        Host current format (default sQ8.8) and the accepted range (default: the format's;
        a narrower one adds a flagged clamp).
    weights, weight_bits, weight_frac_bits, acc_bits
        ``(n_neurons, n_inputs)`` weights of the input spikes (real values; quantized to
        nearest), their width, fraction bits (default: the most that hold every weight) and
        the accumulator width (default: ``weight_bits + ceil(log2(n_inputs))``, never
        overflows).
    input_limit
        ``(lo, hi)`` the total input ``D`` may take; default: the proven range (no clamp).
    saturation, rounding, tick_source, spike_fifo_depth, sweep_number_width, v_init
        As for the Izhikevich core.
    max_decay_error
        Largest accepted relative error of ``k`` (and of ``1 - k``) as represented.
    syn_alpha, input_delays
        Discrete form: a current-based synapse (NIR's CubaLIF, :mod:`~cuneate.hdl.lib.synapses`);
        per source a delay in ticks (<= MAX_INPUT_DELAY; a spike before tick T acts at T + d).
    """

    n_neurons: int = 8
    clock_hz: float | None = None
    update_hz: float = 16e3
    form: str = "continuous"
    param_sets: Sequence = ()
    neuron_sets: Sequence[int] | None = None
    decay: str = "multiply"
    v_frac_bits: int = 16
    v_int_bits: int | None = None
    operand_width: int = 18
    current_format: QFormat = field(default_factory=lambda: QFormat(8, 8))
    current_range: tuple[float, float] | None = None
    weights: object = None
    weight_bits: int = 8
    weight_frac_bits: int | None = None
    acc_bits: int | None = None
    input_limit: tuple[float, float] | None = None
    v_init: Sequence[float] | None = None
    max_decay_error: float = 1e-2
    synapses: bool = False
    weights_writable: bool = False
    input_types: Sequence[str] | None = None
    ampa: tuple[float, float] = (golden.AMPA.tau_rise_ms, golden.AMPA.tau_decay_ms)
    gaba: tuple[float, float] = (golden.GABA.tau_rise_ms, golden.GABA.tau_decay_ms)
    syn_alpha: float | None = None
    input_delays: Sequence[int] | None = None

    def __post_init__(self):
        self._check_sizes()
        self._derive_sets()
        self._derive_inputs()
        self._derive_decay()
        self._derive_state()
        check_leak(self)
        check_int64(self)

    # ------------------------------------------------------------------------------------------
    def _check_sizes(self):
        N = self.n_neurons
        if not isinstance(N, (int, np.integer)) or N < MIN_NEURONS:
            raise ConfigError(f"n_neurons must be an integer >= {MIN_NEURONS} (the pipeline "
                              f"depth plus margin), got {N!r}")
        if self.form not in FORMS:
            raise ConfigError(f"form must be one of {FORMS}, got {self.form!r}")
        if self.decay not in DECAYS:
            raise ConfigError(f"decay must be one of {DECAYS}, got {self.decay!r}")
        self._check_options()
        if not (isinstance(self.update_hz, numbers.Real) and not isinstance(self.update_hz, bool)
                and math.isfinite(self.update_hz) and self.update_hz > 0):
            raise ConfigError("update_hz must be a positive finite number")
        if self.clock_hz is None:
            self.clock_hz = float(self.update_hz * N)
        self.cycles_per_tick = whole_cycles_per_tick(self.clock_hz, self.update_hz)
        if N > self.cycles_per_tick:
            raise ConfigError(f"{N} neurons do not fit one sweep of {self.cycles_per_tick} "
                              f"cycles (clock_hz / update_hz)")
        self.dt_ms = 1000.0 / self.update_hz
        for k, top in (("v_frac_bits", MAX_V_FRAC_BITS), ("operand_width", MAX_OPERAND_WIDTH),
                       ("weight_bits", MAX_WEIGHT_BITS)):
            v = getattr(self, k)
            if not isinstance(v, (int, np.integer)) or not 2 <= v <= top:
                raise ConfigError(f"{k} must be an integer in 2 .. {top} (the twin holds the "
                                  f"state, its sums and products in int64), got {v!r}")
        if not 0 < self.max_decay_error < 1:
            raise ConfigError("max_decay_error must lie in (0, 1)")

    def _derive_sets(self):
        specs = list(self.param_sets) or [{}]
        self.sets = [LifSet.make(s, self.form) for s in specs]
        self.param_sets = tuple(s.to_dict() for s in self.sets)
        n_sets = len(self.sets)
        self.sel_bits = max(1, (n_sets - 1).bit_length())
        ns = [0] * self.n_neurons if self.neuron_sets is None else [int(x) for x in
                                                                    self.neuron_sets]
        if len(ns) != self.n_neurons or any(not 0 <= x < n_sets for x in ns):
            raise ConfigError(f"neuron_sets needs {self.n_neurons} indices in [0, {n_sets})")
        self.neuron_sets = ns
        if self.form == "continuous":
            self.n_ref = [int(max(0, math.ceil(s.t_ref_ms / self.dt_ms - _GRID_EPS)))
                          for s in self.sets]
            self.k_exact = [-math.expm1(-self.dt_ms / s.tau_m_ms) for s in self.sets]
        else:
            self.n_ref = [int(s.refractory_steps) for s in self.sets]
            self.k_exact = [1.0 - s.alpha for s in self.sets]
        self.ref_bits = max(self.n_ref).bit_length()

    def _derive_inputs(self):
        I = self.current_format
        if isinstance(I, (list, tuple)):
            I = self.current_format = QFormat(*I)
        if I.frac_bits > self.v_frac_bits:
            raise ConfigError(f"current format {I} has more fraction bits than the state "
                              f"({self.v_frac_bits})")
        self.I = I
        lo, hi = self.current_range if self.current_range is not None else (I.min_value,
                                                                            I.max_value)
        if not (I.contains(lo) and I.contains(hi) and lo <= hi):
            raise ConfigError(f"current_range [{lo:g}, {hi:g}] must lie inside {I} "
                              f"[{I.min_value:g}, {I.max_value:g}]")
        self.i_lo_raw, self.i_hi_raw = I.to_raw(lo, rounding="nearest"), I.to_raw(hi)
        self.i_lo, self.i_hi = I.to_float(self.i_lo_raw), I.to_float(self.i_hi_raw)
        self.current_clamp = (self.i_lo_raw, self.i_hi_raw) != (I.min_raw, I.max_raw)
        # ---- weights and accumulator
        if self.weights is None:
            w = np.zeros((self.n_neurons, 0))
        else:
            w = np.asarray(self.weights, dtype=np.float64)
            if w.ndim != 2 or w.shape[0] != self.n_neurons:
                raise ConfigError(f"weights must have shape (n_neurons={self.n_neurons}, "
                                  f"n_inputs), got {w.shape}")
            if not np.all(np.isfinite(w)):
                raise ConfigError("weights must be finite")
        self.n_inputs = F = w.shape[1]
        check_weight_memory(self.n_neurons, F, self.weight_bits)
        self.weights = w
        self.input_delays = check_delays(self.input_delays, F, MAX_INPUT_DELAY, "input")
        self.max_input_delay = max(self.input_delays or [0])
        self.input_exc = np.ones(F, dtype=bool)
        if self.input_types is not None and not self.synapses:
            raise ConfigError("input_types (AMPA/GABA) only apply with synapses=True")
        if self.synapses:
            from ..lib.synapses import scale_weights
            w, self.input_exc = scale_weights(self, w)     # the memory holds w / N_type
        wb = self.weight_bits
        if self.weight_frac_bits is None:
            lo_w, hi_w = (float(w.min()), float(w.max())) if w.size else (0.0, 0.0)
            W = QFormat.for_range(min(lo_w, 0.0), max(hi_w, 0.0), wb) if (lo_w or hi_w) \
                else QFormat(1, wb - 1)
        else:
            W = QFormat(wb - self.weight_frac_bits, self.weight_frac_bits)
            if w.size and (w.min() < W.min_value - W.lsb / 2 or w.max() > W.max_value + W.lsb / 2):
                bad = w.flat[np.argmax(np.maximum(W.min_value - w, w - W.max_value))]
                raise ConfigError(f"weight {bad:g} is outside the weight format {W} "
                                  f"[{W.min_value:g}, {W.max_value:g}]")
        if W.frac_bits > self.v_frac_bits:
            W = QFormat(wb - self.v_frac_bits, self.v_frac_bits)
        self.W = W
        self.weights_raw = W.to_raw(w).astype(np.int64).reshape(self.n_neurons, F) if F else \
            np.zeros((self.n_neurons, 0), dtype=np.int64)
        need = wb + max(0, (F - 1).bit_length()) if F else 1
        if self.acc_bits is None:
            self.acc_bits = need
        elif self.acc_bits < need:
            raise ConfigError(f"an accumulator of {self.acc_bits} bits cannot hold the sum of "
                              f"{F} weights of {wb} bits (needs {need}): the fan-in sum would "
                              f"overflow")
        wr = self.weights_raw
        if self.weights_writable:
            if self.synapses:
                raise ConfigError("host-writable weights are not available with synaptic "
                                  "traces (their formats are proven from the given weights)")
            if not F:
                raise ConfigError("weights_writable needs weights (their shape fixes the "
                                  "fan-in)")
        self.syn_lo_raw = np.where(wr < 0, wr, 0).sum(axis=1) if F else np.zeros(self.n_neurons,
                                                                                 np.int64)
        self.syn_hi_raw = np.where(wr > 0, wr, 0).sum(axis=1) if F else np.zeros(self.n_neurons,
                                                                                 np.int64)
        if self.weights_writable:
            # the host may write any value of the format: bound the fan-in by its extremes
            self.syn_lo_raw = np.full(self.n_neurons, F * W.min_raw, dtype=np.int64)
            self.syn_hi_raw = np.full(self.n_neurons, F * W.max_raw, dtype=np.int64)
        # ---- total input D = I + sum w x (or + I_syn), in state fraction bits
        fv = self.v_frac_bits
        if self.synapses:
            from ..lib.synapses import derive_traces
            self.traces, (s_lo, s_hi) = derive_traces(self)
        elif self.syn_alpha is not None:
            from ..lib.synapses import derive_cuba_trace
            self.traces, (s_lo, s_hi) = derive_cuba_trace(self)
        else:
            self.traces = []
            s_lo = int(self.syn_lo_raw.min()) << (fv - W.frac_bits)
            s_hi = int(self.syn_hi_raw.max()) << (fv - W.frac_bits)
        cur = self.syn_alpha is None            # (the current-based synapse: D = y)
        d_lo = (self.i_lo_raw << (fv - I.frac_bits)) * cur + s_lo
        d_hi = (self.i_hi_raw << (fv - I.frac_bits)) * cur + s_hi
        self.d_proven_raw = (int(d_lo), int(d_hi))
        if self.input_limit is None:
            self.d_lo_raw, self.d_hi_raw = self.d_proven_raw
            self.input_clamp = False
        else:
            lo, hi = self.input_limit
            self.d_lo_raw = int(math.ceil(lo * 2.0 ** fv))
            self.d_hi_raw = int(math.floor(hi * 2.0 ** fv))
            if self.d_lo_raw > self.d_hi_raw:
                raise ConfigError(f"input_limit [{lo:g}, {hi:g}] is empty")
            over = d_lo < self.d_lo_raw or d_hi > self.d_hi_raw
            if over and self.saturation == "refuse":
                raise ConfigError(
                    f"host current plus the fan-in of {F} weighted inputs can reach "
                    f"[{d_lo / 2.0 ** fv:g}, {d_hi / 2.0 ** fv:g}], outside input_limit "
                    f"[{lo:g}, {hi:g}]; lower the weights or pass saturation='flag' for a "
                    f"flagged clamp")
            self.input_clamp = over
            if not over:
                self.d_lo_raw, self.d_hi_raw = d_lo, d_hi
        self.d_lo, self.d_hi = self.d_lo_raw / 2.0 ** fv, self.d_hi_raw / 2.0 ** fv

    def _derive_decay(self):
        ks, ow = self.k_exact, self.operand_width
        if self.decay == "multiply":
            big = max(ks)
            if big <= 0:
                raise ConfigError("every set's decay rounds to alpha = 1 (k = 1 - alpha = 0): the "
                                  "neurons would not leak")
            ref = FixedConstant.normalized("k", big, ow)
            self.K = [FixedConstant.scaled(f"k[{i}]", k, ref.frac_bits, ow)
                      for i, k in enumerate(ks)]
            self.k_shift = None
        else:
            self.K, self.k_shift = [], []
            for i, k in enumerate(ks):
                if not 0 < k < 1:
                    raise ConfigError(f"set {i}: decay k = {k:g} has no power-of-two form")
                s = max(1, int(round(-math.log2(k))))
                self.k_shift.append(s)
                self.K.append(FixedConstant(f"k[{i}]", k, 1, s, s + 2))
        self.k_q = [c.quantized for c in self.K]
        for i, (k, kq) in enumerate(zip(ks, self.k_q)):
            form = ("a multiplier constant" if self.k_shift is None
                    else f"2**-{self.k_shift[i]}")
            what = f"set {i}: decay alpha = {1 - k:.6g} (k = 1 - alpha = {k:.6g}) as {form}"
            if kq <= 0:
                raise ConfigError(f"{what} rounds to alpha = 1: the neuron would not leak")
            if kq >= 1:
                raise ConfigError(f"{what} rounds to alpha = 0: the neuron would keep no state")
            err = abs(kq - k)
            if err > self.max_decay_error * min(k, 1 - k):
                raise ConfigError(f"{what} is represented as k = {kq:.6g}, relative error "
                                  f"{err / min(k, 1 - k):.3g} > max_decay_error "
                                  f"{self.max_decay_error:g}"
                                  + ("; use decay='multiply'" if self.decay == "shift" else ""))

    def _derive_state(self):
        fv, lsb = self.v_frac_bits, 2.0 ** -self.v_frac_bits
        cont = self.form == "continuous"
        if self.v_init is None:
            v_init = [self.sets[s].v_rest if cont else self.sets[s].v_reset
                      for s in self.neuron_sets]
        else:
            v_init = [float(x) for x in self.v_init]
            if len(v_init) != self.n_neurons or not all(map(math.isfinite, v_init)):
                raise ConfigError(f"v_init needs {self.n_neurons} finite values")
        self._v_init = v_init
        lo_all, hi_all, pre_hi_all = [], [], []
        for i, s in enumerate(self.sets):
            kq = self.k_q[i]
            members = [v_init[n] for n in range(self.n_neurons) if self.neuron_sets[n] == i]
            H = max([s.v_th, s.v_reset, s.v_rest] + members)
            if cont:
                L = min([s.v_reset, s.v_rest + self.d_lo, s.v_rest] + members)
                pre = ((1 - kq) * H + kq * (s.v_rest + self.d_hi))
            else:
                L = min([s.v_reset, 0.0, self.d_lo / kq] + members)
                pre = (1 - kq) * H + self.d_hi
            # rounding of each step (<= 1 LSB) accumulates at most 1/k LSB on a steady state
            margin = (4.0 / kq + 4.0) * lsb
            lo_all.append(L - margin)
            hi_all.append(max(H, pre) + margin)
            pre_hi_all.append(pre + margin)
        self.v_lo_proven, self.v_hi_proven = min(lo_all), max(hi_all)
        need = int_bits_for(self.v_lo_proven, self.v_hi_proven)
        if need + fv > 60:
            raise ConfigError(f"the state range [{self.v_lo_proven:.4g}, "
                              f"{self.v_hi_proven:.4g}] needs {need} integer bits; with {fv} "
                              f"fraction bits the state exceeds the 60 bits the twin's int64 "
                              f"holds with its sums (thresholds, resets and inputs of that size "
                              f"are not a neuron's)")
        self.v_int_bits_derived = need
        if self.v_int_bits is None:
            self.v_int_bits = need
        elif self.v_int_bits < need:
            V_try = QFormat(self.v_int_bits, fv)
            fits_th = all(V_try.contains(x) for s in self.sets
                          for x in (s.v_th, s.v_reset, s.v_rest)) and \
                all(V_try.contains(x) for x in v_init)
            if not fits_th:
                raise ConfigError(f"state format {V_try} cannot hold the thresholds, resets, "
                                  f"rests and initial values of the parameter sets")
            if self.saturation == "refuse" or V_try.max_value < max(s.v_th for s in self.sets):
                raise ConfigError(f"state format {V_try} is narrower than the proven state "
                                  f"range [{self.v_lo_proven:g}, {self.v_hi_proven:g}] (needs "
                                  f"{need} integer bits); pass saturation='flag' for a flagged "
                                  f"clamp")
        self.V = V = QFormat(self.v_int_bits, fv)
        self.v_floor_raw = max(V.min_raw, int(math.floor(self.v_lo_proven * 2.0 ** fv)))
        self.v_clamp = self.v_int_bits < need
        self.v_init_raw = np.asarray(V.to_raw(np.asarray(v_init)), dtype=np.int64)
        strict = self.form == "discrete"
        self.TH = [FixedConstant.in_format(f"v_th[{i}]", s.v_th, V) for i, s in enumerate(self.sets)]
        self.RESET = [FixedConstant.in_format(f"v_reset[{i}]", s.v_reset, V)
                      for i, s in enumerate(self.sets)]
        self.REST = [FixedConstant.in_format(f"v_rest[{i}]", s.v_rest, V)
                     for i, s in enumerate(self.sets)]
        # spike when v' >= v_th (continuous) or v' > u_th (discrete): one >= comparison
        self.th_cmp_raw = [c.raw + (1 if strict and c.quantized >= c.value else 0)
                           for c in self.TH]
        # ---- state after the clamp, and the leak operand
        v_lo = max(self.v_lo_proven, V.min_value)
        v_hi = self.v_hi_proven
        if cont:
            x_lo = v_lo - max(s.v_rest for s in self.sets) - self.d_hi
            x_hi = v_hi - min(s.v_rest for s in self.sets) - self.d_lo
        else:
            x_lo, x_hi = v_lo, v_hi
        self.x_range = (x_lo, x_hi)
        if self.decay == "multiply":
            X = QFormat.for_range(x_lo - 2 * lsb, x_hi + 2 * lsb, self.operand_width)
            if X.frac_bits > fv:
                X = QFormat(X.int_bits, fv)

            def bounds(fmt):
                return (int(np.floor(x_lo * 2.0 ** fmt.frac_bits)) - 1,
                        int(np.ceil(x_hi * 2.0 ** fmt.frac_bits)) + 1)
            while not X.min_raw <= bounds(X)[0] <= bounds(X)[1] <= X.max_raw:
                X = QFormat(X.int_bits + 1, X.frac_bits - 1)   # rounding reached the edge
            self.X = X
            self.x_bounds_raw = bounds(X)
            self.product_shift = X.frac_bits + self.K[0].frac_bits - fv
        else:
            self.X = None
            self.product_shift = None
        self.sweep_number_width = int(self.sweep_number_width)

    # ------------------------------------------------------------------------------------------
    @property
    def clamp_can_act(self) -> dict:
        return {"current": self.current_clamp, "input": self.input_clamp, "v_low": self.v_clamp}

    def golden_step(self, v, D, ref, sel):
        """Float64 golden update from state ``v`` (real), refractory counter ``ref``, total
        input ``D`` (real) with the set's exact (unquantized) parameters. Returns
        ``(v', spike, v_pre)``."""
        sel = np.asarray(sel)
        th = np.array([s.v_th for s in self.sets])[sel]
        reset = np.array([s.v_reset for s in self.sets])[sel]
        if self.form == "continuous":
            tau = np.array([s.tau_m_ms for s in self.sets])[sel]
            rest = np.array([s.v_rest for s in self.sets])[sel]
            v_pre = golden.lif_step(v, D, self.dt_ms, tau, rest, "exact")
            spk = v_pre >= th
        else:
            alpha = np.array([s.alpha for s in self.sets])[sel]
            v_pre = alpha * v + D
            spk = v_pre > th
        frozen = np.asarray(ref) > 0
        spk = spk & ~frozen
        return np.where(frozen | spk, reset, v_pre), spk, v_pre

    def one_step_bound(self, v, D, sel=None):
        """Largest |fixed - golden| of one update from the same state and input (mV or u),
        derived from the formats: the represented ``k`` (and ``v_rest``) against the exact
        ones, the rounding of the leak operand and of the product, the quantized reset."""
        sel = np.zeros(np.shape(v), dtype=np.int64) if sel is None else np.asarray(sel)
        v, D = np.asarray(v, dtype=np.float64), np.asarray(D, dtype=np.float64)
        half = 0.5 if self.rounding == "nearest" else 1.0
        lsb = self.V.lsb
        kq = np.array(self.k_q)[sel]
        dk = np.abs(kq - np.array(self.k_exact)[sel])
        if self.form == "continuous":
            rest = np.array([s.v_rest for s in self.sets])[sel]
            drest = np.array([abs(c.abs_error) for c in self.REST])[sel]
            x = np.abs(v - rest - D)
        else:
            drest = 0.0
            x = np.abs(v)
        ex = half * self.X.lsb if self.X is not None else 0.0
        step = dk * (x + drest) + kq * (ex + drest) + half * lsb
        reset_err = np.array([abs(c.abs_error) for c in self.RESET])[sel]
        return np.maximum(step, reset_err) + 1e-12 * (1 + np.abs(v) + np.abs(D))

    # ------------------------------------------------------------------------------------------
    def to_kwargs(self, **override) -> dict:
        """JSON-friendly constructor keywords that rebuild this configuration."""
        kw = {"n_neurons": int(self.n_neurons), "clock_hz": float(self.clock_hz),
              "update_hz": float(self.update_hz), "form": self.form,
              "param_sets": [dict(p) for p in self.param_sets],
              "neuron_sets": list(self.neuron_sets), "decay": self.decay,
              "v_frac_bits": int(self.v_frac_bits), "v_int_bits": int(self.V.int_bits),
              "operand_width": int(self.operand_width),
              "current_format": [self.I.int_bits, self.I.frac_bits],
              "current_range": [self.i_lo, self.i_hi],
              "weights": self.weights.tolist() if self.n_inputs else None,
              "weight_bits": int(self.weight_bits), "weight_frac_bits": int(self.W.frac_bits),
              "acc_bits": int(self.acc_bits),
              "input_limit": list(self.input_limit) if self.input_limit is not None else None,
              "saturation": self.saturation, "rounding": self.rounding,
              "tick_source": self.tick_source, "spike_fifo_depth": int(self.spike_fifo_depth),
              "sweep_number_width": int(self.sweep_number_width),
              "v_init": list(self._v_init), "max_decay_error": float(self.max_decay_error),
              "synapses": bool(self.synapses), "weights_writable": bool(self.weights_writable),
              "input_types": (["exc" if e else "inh" for e in self.input_exc]
                              if self.synapses else None),
              "ampa": list(self.ampa), "gaba": list(self.gaba), "syn_alpha": self.syn_alpha,
              "input_delays": self.input_delays}
        kw.update(override)
        return kw

    @classmethod
    def from_kwargs(cls, kw: dict) -> "LifConfig":
        kw = dict(kw)
        for k in ("current_range", "input_limit", "ampa", "gaba"):
            if kw.get(k) is not None:
                kw[k] = tuple(kw[k])
        if isinstance(kw.get("current_format"), (list, tuple)):
            kw["current_format"] = QFormat(*kw["current_format"])
        return cls(**kw)

    def to_dict(self) -> dict:
        """Everything a user of the generated Verilog needs (written beside it as JSON)."""
        consts = self.K + self.TH + self.RESET + self.REST
        mid = np.array([0.5 * (s.v_th + s.v_reset) for s in self.sets])
        bound = self.one_step_bound(mid, np.zeros(len(self.sets)),
                                    np.arange(len(self.sets)))
        return {
            "block": "LifCore", "form": self.form,
            "scheme": "exact exponential integration" if self.form == "continuous" else
                      "u[t] = alpha u[t-1] + sum w x",
            "decay": {"mode": self.decay,
                      "implementation": ("multiply by k = 1 - alpha (one multiplier)"
                                         if self.decay == "multiply" else
                                         "shift-and-subtract by 2**-s (no multiplier)"),
                      "shifts": self.k_shift,
                      "k": [c.to_dict() for c in self.K], "k_exact": self.k_exact},
            "n_neurons": self.n_neurons, "clock_hz": self.clock_hz,
            "update_hz": self.update_hz, "dt_ms": self.dt_ms,
            "cycles_per_tick": self.cycles_per_tick, "pipeline_depth": PIPELINE_DEPTH,
            "latency_cycles": PIPELINE_DEPTH, "throughput": "one neuron update per cycle",
            "rounding": self.rounding, "tick_source": self.tick_source,
            "saturation": self.saturation,
            "multipliers": (1 if self.decay == "multiply" else 0) + len(self.traces),
            "formats": {"V": self.V.to_dict(), "I": self.I.to_dict(), "W": self.W.to_dict()}
            | ({"X": self.X.to_dict()} if self.X else {}),
            "n_inputs": self.n_inputs, "accumulator_bits": self.acc_bits,
            "accepted_current_range": [self.i_lo, self.i_hi],
            "input_range": [self.d_lo, self.d_hi],
            "param_sets": [dict(p) for p in self.param_sets],
            "refractory_ticks": self.n_ref,
            "constants": {c.name: c.to_dict() for c in consts},
            "proven_state_range": [self.v_lo_proven, self.v_hi_proven],
            "v_int_bits_needed": self.v_int_bits_derived,
            "clamps": {k: {"built": v} for k, v in self.clamp_can_act.items()},
            "one_step_bound_mid_range": [float(b) for b in bound],
            "state_word_bits": self.V.width + self.ref_bits,
            "synapses": ({"input_types": ["exc" if e else "inh" for e in self.input_exc],
                          "weights_stored_as": "w / N (peak-normalized kernel)",
                          "traces": {t.name: t.to_dict() for t in self.traces},
                          "multipliers": len(self.traces)} if self.synapses else None),
            "current_synapse": (self.traces[0].to_dict() | {"syn_alpha": self.syn_alpha}
                                if self.syn_alpha is not None else None),
            "input_delays_ticks": self.input_delays,
            "resources_hint": {"multipliers": (1 if self.decay == "multiply" else 0)
                               + len(self.traces),
                               "trace_ram_bits": self.n_neurons * sum(t.T.width
                                                                      for t in self.traces),
                               "state_ram_bits": self.n_neurons * (self.V.width + self.ref_bits),
                               "current_ram_bits": self.n_neurons * self.I.width,
                               "weight_ram_bits": self.n_neurons * self.n_inputs
                               * self.W.width},
        }
