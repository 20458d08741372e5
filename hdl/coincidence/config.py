"""Configuration of the coincidence detector (cuneate neurons): formats derived, bad input refused.

:class:`CoincidenceConfig` holds what :class:`cuneate.hdl.coincidence.CoincidenceDetector` is built
from: ``n_sources`` afferents, ``n_targets`` cuneate neurons, a conduction delay in ticks and a
weight for every (target, source) pair, the PSP time constants and the Izhikevich parameters of
the targets. It derives and proves:

* the spike history (a ring of ``max_delay_ticks`` words of ``n_sources`` bits in block RAM);
* the weight format (``weight_bits``, unsigned, the most fraction bits that hold ``J w``);
* the input accumulator (``a = sum_s J w_s x_s``: width from the fan-in, never overflows);
* the two PSP traces (decay and rise) as in :mod:`cuneate.hdl.lib.synapses`, sized from the
  largest per-tick input;
* the PSP current ``I = x_d - x_r`` and its proven range, which becomes the accepted current
  range of the Izhikevich arithmetic (an :class:`~cuneate.hdl.izhikevich.IzhikevichConfig`
  built for the targets: its proven state ranges hold, no unflagged clamp can act).

Refused at construction, one line each: delays outside ``0 .. max_delay_ticks - 1``, negative
or non-finite weights, weights that round to zero or do not fit their format, PSP decay
constants that round to 0 or 1 at this dt, a fan-in whose accumulator would not fit 62 bits, a
tick budget the clock cannot hold, a spike history larger than the block RAM of the largest
supported FPGA (:data:`MAX_HISTORY_BITS`), and anything the Izhikevich configuration refuses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...golden import coincidence as gcun
from ..izhikevich.config import CLAMP_KINDS
from ..izhikevich.targets import TargetOptions, target_arithmetic
from ..lib.config import (MAX_BLOCK_RAM_BITS, ConfigError, check_rounding, check_tick_source,
                          int_bits_for, refusing, whole_cycles_per_tick)
from ..lib.fixed import QFormat
from ..lib.synapses import TraceView, trace_spec

__all__ = ["CoincidenceConfig", "ConfigError", "CYCLES_PER_TARGET_EXTRA", "TRACE_NAMES",
           "CLAMP_KINDS", "MAX_HISTORY_BITS"]

#: trace order (state, ports, twin arrays): decay, rise
TRACE_NAMES = ("xd", "xr")
#: cycles per target beyond one per input: history/weight read latency and the update stages
CYCLES_PER_TARGET_EXTRA = 8


#: The most spike-history bits a detector may hold: the block RAM of the largest supported FPGA.
MAX_HISTORY_BITS = MAX_BLOCK_RAM_BITS


@dataclass
class CoincidenceConfig(TargetOptions):
    """A coincidence detector: ``n_targets`` Izhikevich neurons driven by delayed, weighted,
    bi-exponential PSPs of ``n_sources`` afferents.

    Parameters
    ----------
    n_sources, n_targets
        Afferents (input spike sources) and cuneate neurons.
    delays_ticks
        ``(n_targets, n_sources)`` conduction delays in ticks (integers in
        ``0 .. max_delay_ticks - 1``); see :meth:`from_ms`.
    weights
        ``(n_targets, n_sources)`` PSP amplitudes ``J w`` in mV/ms (>= 0; 0 disconnects).
        Default: ``J`` = 8 mV/ms for every pair (the brief).
    max_delay_ticks
        Depth of the spike history (default 513: delays up to 32 ms at 16 kHz).
    tau_rise_ms, tau_decay_ms
        PSP time constants (0.5 and 2 ms).
    param_sets, target_sets
        Izhikevich parameter sets of the targets and each target's set (default RS for all).
    clock_hz, update_hz
        Clock and tick rate; a tick needs ``n_targets * (n_sources + 8)`` cycles.
    tick_source
        ``"external"`` (``tick`` input, default) or ``"internal"`` (divider).
    weight_bits, trace_frac_bits, max_decay_error
        Weight width, fraction bits of the traces, largest accepted relative error of a trace
        decay constant.
    operand_width, rounding
        Multiplier operand width and rounding.
    """

    n_sources: int = 4
    n_targets: int = 3
    delays_ticks: object = None
    weights: object = None
    max_delay_ticks: int = 513
    tau_rise_ms: float = gcun.TAU_RISE_MS
    tau_decay_ms: float = gcun.TAU_DECAY_MS
    update_hz: float = 16e3
    weight_bits: int = 12
    trace_frac_bits: int = 16

    def __post_init__(self):
        with refusing("coincidence detector"):
            self._derive()

    # ------------------------------------------------------------------------------------------
    @classmethod
    def from_ms(cls, delays_ms, update_hz: float = 16e3, **kw) -> "CoincidenceConfig":
        """Build from delays in ms; each must be a whole number of ticks (to 1e-9)."""
        d = np.asarray(delays_ms, dtype=np.float64)
        if d.ndim != 2 or not np.all(np.isfinite(d)):
            raise ConfigError(f"delays_ms must be a finite (n_targets, n_sources) matrix, got "
                              f"shape {d.shape}")
        ticks = d * update_hz / 1000.0
        if not np.allclose(ticks, np.round(ticks), atol=1e-9):
            bad = d.ravel()[np.argmax(np.abs(ticks - np.round(ticks)).ravel())]
            raise ConfigError(f"delay {bad:g} ms is not a whole number of ticks at "
                              f"{update_hz:g} Hz (dt = {1000 / update_hz:g} ms)")
        return cls(n_targets=d.shape[0], n_sources=d.shape[1],
                   delays_ticks=np.round(ticks).astype(np.int64), update_hz=update_hz, **kw)

    def _derive(self):
        S, M = self.n_sources, self.n_targets
        for k, v in (("n_sources", S), ("n_targets", M)):
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise ConfigError(f"{k} must be an integer >= 1, got {v!r}")
        check_rounding(self.rounding)
        check_tick_source(self.tick_source)
        D = self.max_delay_ticks
        if not isinstance(D, (int, np.integer)) or D < 1:
            raise ConfigError(f"max_delay_ticks must be an integer >= 1, got {D!r}")
        if D * S > MAX_HISTORY_BITS:
            raise ConfigError(f"max_delay_ticks = {D}: a spike history of {D} x {S} bits "
                              f"({D * S / 2**20:.3g} Mibit) does not fit the block RAM of the "
                              f"largest supported FPGA ({MAX_HISTORY_BITS / 2**20:.3g} Mibit); at "
                              f"{S} source(s) at most {MAX_HISTORY_BITS // S} ticks")
        self.cycles_per_tick = whole_cycles_per_tick(self.clock_hz, self.update_hz)
        self.dt_ms = 1000.0 / self.update_hz
        # delays
        d = np.zeros((M, S), dtype=np.int64) if self.delays_ticks is None else \
            np.asarray(self.delays_ticks)
        if d.shape != (M, S):
            raise ConfigError(f"delays_ticks must have shape (n_targets, n_sources) = ({M}, {S}),"
                              f" got {d.shape}")
        if not np.issubdtype(d.dtype, np.integer):
            if not np.all(np.isfinite(d)) or not np.array_equal(d, np.round(d)):
                raise ConfigError("delays_ticks must be whole numbers of ticks")
        d = d.astype(np.int64)
        if d.min() < 0 or d.max() >= D:
            t, s = np.unravel_index(np.argmax((d < 0) | (d >= D)), d.shape)
            raise ConfigError(f"delay of target {t} from source {s} is {d[t, s]} ticks: outside "
                              f"0 .. {D - 1} (max_delay_ticks = {D}, "
                              f"{(D - 1) * self.dt_ms:g} ms)")
        self.delays = d
        self.history_addr_bits = max(1, (D - 1).bit_length())
        # weights
        w = np.full((M, S), gcun.J_MV_PER_MS) if self.weights is None else \
            np.asarray(self.weights, dtype=np.float64)
        if w.shape != (M, S):
            raise ConfigError(f"weights must have shape (n_targets, n_sources) = ({M}, {S}), got "
                              f"{w.shape}")
        if not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ConfigError("weights must be finite and >= 0 (PSP amplitudes J w in mV/ms; "
                              "the coincidence detector has excitatory inputs only)")
        self.weights_real = w
        wmax = float(w.max())
        if wmax == 0:
            raise ConfigError("every weight is 0: the detector would have no input")
        if not isinstance(self.weight_bits, (int, np.integer)) or self.weight_bits < 2:
            raise ConfigError("weight_bits must be an integer >= 2")
        self.W = QFormat.for_range(0.0, wmax, self.weight_bits, signed_=False)
        F = self.trace_frac_bits
        if self.W.frac_bits > F:
            self.W = QFormat(self.W.width - F, F, signed=False) if self.W.width > F else \
                QFormat(0, F, signed=False)
        self.weights_raw = self.W.to_raw(w)
        lost = (w > 0) & (self.weights_raw == 0)
        if lost.any():
            t, s = np.argwhere(lost)[0]
            raise ConfigError(f"weight of target {t} from source {s} ({w[t, s]:g}) rounds to 0 "
                              f"in {self.W}")
        # accumulator: the fan-in sum never overflows
        acc_max = int(self.weights_raw.sum(axis=1).max())
        self.acc_bits = max(1, acc_max.bit_length())
        if self.acc_bits + F - self.W.frac_bits > 60:
            raise ConfigError(f"fan-in of {S} inputs needs a {self.acc_bits}-bit accumulator: too "
                              f"wide")
        self.acc_max_raw = acc_max
        # traces
        self._derive_traces()
        # cycles
        self.cycles_needed = M * (S + CYCLES_PER_TARGET_EXTRA) + 2
        if self.cycles_needed > self.cycles_per_tick:
            raise ConfigError(f"{M} targets x {S} sources need {self.cycles_needed} cycles per "
                              f"tick; {self.clock_hz:g} Hz / {self.update_hz:g} Hz gives "
                              f"{self.cycles_per_tick}")
        # the Izhikevich arithmetic of the targets, proven for the PSP current range
        self.iz, self.target_sets_ = target_arithmetic(
            self, "coincidence detector: the targets",
            QFormat(int_bits_for(self.i_lo, self.i_hi), self.i_frac_bits), (self.i_lo, self.i_hi))
        if self.i_raw_bounds[0] < self.iz.I.min_raw or self.i_raw_bounds[1] > self.iz.I.max_raw:
            raise ConfigError(f"PSP current range [{self.i_lo:g}, {self.i_hi:g}] mV/ms does not "
                              f"fit the Izhikevich current format {self.iz.I}")

    def _derive_traces(self):
        F, ow, lsb = self.trace_frac_bits, self.operand_width, 2.0 ** -self.trace_frac_bits
        if not isinstance(F, (int, np.integer)) or F < 8:
            raise ConfigError("trace_frac_bits must be an integer >= 8")
        if not (math.isfinite(self.tau_rise_ms) and math.isfinite(self.tau_decay_ms)
                and 0 < self.tau_rise_ms < self.tau_decay_ms):
            raise ConfigError(f"PSP time constants need 0 < tau_rise < tau_decay, got "
                              f"{self.tau_rise_ms!r}, {self.tau_decay_ms!r}")
        self.T = QFormat(32, F)                   # nominal; the stored formats follow
        self.wshift = F - self.W.frac_bits
        a = self.acc_max_raw * self.W.lsb           # largest per-tick input, mV/ms
        specs = [trace_spec(name, tau, self.dt_ms, ow, F, a, self.max_decay_error, "PSP trace")
                 for name, tau in (("xd", self.tau_decay_ms), ("xr", self.tau_rise_ms))]
        self.traces = specs
        self.TV = QFormat(max(s.T.int_bits for s in specs), F)
        self.tview = TraceView(specs, QFormat(self.TV.int_bits, F), self.rounding, self.dt_ms)
        # I = xd - xr: at most the all-inputs-every-tick steady state, plus rounding margins
        kd, kr = specs[0].K.quantized, specs[1].K.quantized
        top = a * ((1 - kd) / kd - (1 - kr) / kr)
        marg = sum((s.Y.lsb + 2 * lsb) / s.K.quantized for s in specs) + 8 * lsb
        lo, hi = -marg, max(0.0, top) + marg
        self.isyn_bounds = (int(math.floor(lo / lsb)), int(math.ceil(hi / lsb)))
        # the Izhikevich current: I_syn rounded to the core's default current LSB (2^-8)
        self.i_frac_bits = 8
        self.i_shift = F - self.i_frac_bits
        half = 0.5 if self.rounding == "nearest" else 1.0
        i_lo = math.floor(lo * 2 ** self.i_frac_bits - half) - 1
        i_hi = math.ceil(hi * 2 ** self.i_frac_bits + half) + 1
        self.i_raw_bounds = (i_lo, i_hi)
        self.i_lo, self.i_hi = i_lo * 2.0 ** -self.i_frac_bits, i_hi * 2.0 ** -self.i_frac_bits

    # ------------------------------------------------------------------------------------------
    def to_kwargs(self) -> dict:
        """Constructor keywords (JSON-friendly) that rebuild this configuration."""
        return {"n_sources": int(self.n_sources), "n_targets": int(self.n_targets),
                "delays_ticks": self.delays.tolist(), "weights": self.weights_real.tolist(),
                "max_delay_ticks": int(self.max_delay_ticks), "tau_rise_ms": self.tau_rise_ms,
                "tau_decay_ms": self.tau_decay_ms,
                "param_sets": [p if isinstance(p, str) else dict(p) for p in self.param_sets],
                "target_sets": list(self.target_sets_), "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "weight_bits": int(self.weight_bits),
                "trace_frac_bits": int(self.trace_frac_bits),
                "operand_width": int(self.operand_width), "rounding": self.rounding,
                "tick_source": self.tick_source, "max_decay_error": self.max_decay_error}

    @property
    def latency_ticks(self) -> str:
        return ("an input spike stamped with tick T enters the input sum of target t at tick "
                "T + delay[t, s]; it first changes the PSP current at tick T + delay + 1 "
                "(the PSP kernel is 0 at lag 0, as in golden)")

    def to_dict(self) -> dict:
        """Everything a user of the generated Verilog needs (written beside it as JSON)."""
        return {
            "block": "CoincidenceDetector", "n_sources": self.n_sources,
            "n_targets": self.n_targets, "clock_hz": self.clock_hz,
            "update_hz": self.update_hz, "dt_ms": self.dt_ms,
            "cycles_per_tick": self.cycles_per_tick, "cycles_needed": self.cycles_needed,
            "throughput": f"one input per cycle, {CYCLES_PER_TARGET_EXTRA} cycles per target "
                          f"for history latency and the update stages",
            "tick_source": self.tick_source, "rounding": self.rounding,
            "max_delay_ticks": self.max_delay_ticks,
            "max_delay_ms": (self.max_delay_ticks - 1) * self.dt_ms,
            "delays_ticks": self.delays.tolist(),
            "weights_mV_per_ms": self.weights_real.tolist(),
            "weights_quantized": (self.weights_raw * self.W.lsb).tolist(),
            "weight_max_abs_error": float(np.max(np.abs(self.weights_raw * self.W.lsb
                                                         - self.weights_real))),
            "formats": {"weight": self.W.to_dict(), "accumulator_bits": self.acc_bits,
                        "traces": {s.name: s.to_dict() for s in self.traces},
                        "psp_current": {"raw_bounds": list(self.isyn_bounds),
                                        "frac_bits": self.trace_frac_bits},
                        "izhikevich_current": str(self.iz.I)},
            "psp": {"tau_rise_ms": self.tau_rise_ms, "tau_decay_ms": self.tau_decay_ms,
                    "kernel": "exp(-j dt/tau_d) - exp(-j dt/tau_r) at lag j ticks (unnormalized)"},
            "accepted_current_range": [self.i_lo, self.i_hi],
            "latency": self.latency_ticks,
            "izhikevich": {k: v for k, v in self.iz.to_dict().items()
                           if k in ("formats", "param_sets", "constants", "proven_range",
                                    "clamps", "multiplier_operands")},
            "multipliers": 2 + (4 if self.iz.dt_shift is not None else 5),
            "memories": {"history": f"{self.max_delay_ticks} x {self.n_sources} bits",
                         "delay_weight": f"{self.n_targets * self.n_sources} x "
                                         f"{self.history_addr_bits + self.W.width} bits",
                         "state": f"{self.n_targets} x "
                                  f"{self.iz.V.width + self.iz.U.width + 2 * self.TV.width} "
                                  f"bits"},
        }
