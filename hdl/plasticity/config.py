"""Configuration of the learning cuneate layer: every format and constant derived, what cannot be
held refused.

:class:`PlasticityConfig` holds what :class:`~cuneate.hdl.plasticity.LearningLayer` is built
from: ``n_sources`` afferents, ``n_targets`` cuneate neurons (CNs) of ``K`` synapses each (the
afferent of every synapse, ``sources``), the initial weights, the lumped inhibitory
interneuron, the AIDP rule (:class:`~cuneate.golden.aidp.AidpParams`) and the CNs' Izhikevich
parameters. It derives and proves, in the fixed point of :mod:`cuneate.hdl.lib.fixed`:

* the weight format ``W`` (unsigned, ``weight_bits``, the most fraction bits that hold
  ``w_max``);
* the synapse's two calcium traces (``c_d``, ``c_r``: :func:`~cuneate.hdl.lib.synapses
  .trace_spec`, each jumping by ``w`` per delayed spike), the CN's excitation ``E`` (jumping by
  the tick's weighted input sum) and the interneuron ``H`` (jumping by the tick's afferent
  spike count), all in ``trace_frac_bits`` fraction bits;
* the net drive ``I = E - g H`` in the Izhikevich current format (8 fraction bits), whose
  proven range is the Izhikevich configuration's current format; the CNs take it clamped to
  ``[-current_limit, current_limit]`` (the Izhikevich ``current`` clamp: flagged, counted);
* the zero-offset main calcium ``Z = I - theta`` and the local calcium ``C = c_d - c_r`` as
  multiplier operands, the learning drive ``L`` (signed, ``drive_int_bits`` +
  ``drive_frac_bits``) integrating ``C Z`` per tick (``alpha dt`` of the golden rule folded into
  the step), saturating flagged and counted (``drive_low`` / ``drive_high``);
* the compensated drive ``D = K L - sum_m L_m`` (exact) rounded to an operand, and the step
  table: ``eta alpha dt sigma(w, sign D) / K`` per weight bin (the top ``sigmoid_bits`` of
  ``w``) and sign, so ``dw = D sigma_table``; the new weight clamped to ``[0, w_max]``
  (``weight_low`` / ``weight_high``, flagged, counted).

Refused at construction (one line each): sources outside ``0 .. n_sources - 1`` or repeated in a
row, initial weights outside ``[0, w_max]``, a calcium latency of more than
:data:`MAX_LATENCY_TICKS` ticks or not a whole number of ticks, decay constants that round to
0 or 1, a step table that rounds to 0 for a rule that learns, a tick budget the clock cannot
hold, and anything the Izhikevich configuration refuses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...golden.aidp import AidpParams, sigmoid
from ..izhikevich.config import CLAMP_KINDS as IZ_CLAMP_KINDS
from ..izhikevich.targets import TargetOptions, target_arithmetic
from ..lib.config import (ConfigError, check_rounding, check_tick_source, int_bits_for, refusing,
                          whole_cycles_per_tick)
from ..lib.fixed import FixedConstant, QFormat
from ..lib.synapses import TraceView, trace_spec

__all__ = ["PlasticityConfig", "ConfigError", "CLAMP_KINDS", "SYNAPSE_CLAMP_KINDS",
           "CN_CLAMP_KINDS", "MAX_LATENCY_TICKS", "CYCLES_PER_TARGET_EXTRA", "TICK_PROLOGUE",
           "STAGE_LATENCY", "OPS"]

#: the CNs' clamp kinds (the Izhikevich core's) and the synapses' (drive and weight), in the
#: order of the clamp flag bits and counters
CN_CLAMP_KINDS = IZ_CLAMP_KINDS
SYNAPSE_CLAMP_KINDS = ("drive_low", "drive_high", "weight_low", "weight_high")
CLAMP_KINDS = CN_CLAMP_KINDS + SYNAPSE_CLAMP_KINDS
#: the longest calcium latency (ticks): the delayed spike words are registers
MAX_LATENCY_TICKS = 16
#: cycles of a CN beyond one per synapse: its state fetch (with the source table's first
#: read), the last synapse's fetch (its term enters the input sum) and four update cycles
CYCLES_PER_TARGET_EXTRA = 6
#: cycles of a tick besides its CNs: the stamp (the idle cycle that takes the tick) and the
#: interneuron's two
TICK_PROLOGUE = 3
#: cycles from a synapse operation's issue to its write-back (the stage's pipeline); two
#: operations on one synapse must be issued at least this far apart
STAGE_LATENCY = 4
#: the synapse stage's operations (op codes)
OPS = {"integrate": 0, "read": 1, "learn": 2, "write": 3}


@dataclass
class PlasticityConfig(TargetOptions):
    """A learning cuneate layer (see the module docstring).

    Parameters
    ----------
    n_sources
        Afferents (input spike sources).
    sources
        ``(n_targets, K)`` afferent of each synapse (distinct in a row); default: 2 CNs
        reaching every afferent.
    weights
        ``(n_targets, K)`` initial weights in mV/ms (``0 .. w_max``); default ``w_max / 4``.
    rule
        The AIDP rule (:class:`~cuneate.golden.aidp.AidpParams`: its calcium time constants,
        latency, threshold, step and sigmoids, ``w_max``).
    tau_syn_ms, g_inh
        The synaptic currents' decay (excitation and the interneuron's inhibition) and the
        inhibition per unit of the interneuron's trace (mV/ms).
    current_limit
        The CNs' input current range ``[-limit, limit]`` (mV/ms; beyond it clamped, flagged).
    param_sets, target_sets
        Izhikevich parameter sets of the CNs and each CN's set (default RS for all).
    clock_hz, update_hz, tick_source
        Clock, tick rate (2 kHz: dt = 0.5 ms) and tick source (``"external"``: the ``tick``
        input; ``"internal"``: a divider).
    weight_bits, trace_frac_bits, drive_int_bits, drive_frac_bits, sigmoid_bits
        Weight width; fraction bits of every trace; the learning drive's integer and fraction
        bits; the weight bits indexing the sigmoid table.
    operand_width, rounding, max_decay_error
        Multiplier operand width, rounding, largest relative error of a decay constant.
    plastic
        ``False``: a layer whose synapses do not learn (each word the weight alone; window
        ends change nothing): the baseline the cost of learning is measured against.
    """

    n_sources: int = 8
    sources: object = None
    weights: object = None
    rule: AidpParams = field(default_factory=AidpParams)
    tau_syn_ms: float = 6.4
    g_inh: float = 0.3
    current_limit: float = 64.0
    update_hz: float = 2000.0
    weight_bits: int = 16
    trace_frac_bits: int = 13
    drive_int_bits: int = 20
    drive_frac_bits: int = 8
    sigmoid_bits: int = 7
    plastic: bool = True

    def __post_init__(self):
        with refusing("learning layer", ValueError):
            self._derive()

    # ------------------------------------------------------------------------------------------
    def _derive(self):
        S = self.n_sources
        if not isinstance(S, (int, np.integer)) or S < 1:
            raise ConfigError(f"n_sources must be an integer >= 1, got {S!r}")
        check_rounding(self.rounding)
        check_tick_source(self.tick_source)
        if not isinstance(self.rule, AidpParams):
            raise ConfigError("rule must be AidpParams (cuneate.golden.aidp)")
        src = np.tile(np.arange(S), (2, 1)) if self.sources is None else \
            np.asarray(self.sources)
        if src.ndim != 2 or src.size == 0 or not np.issubdtype(src.dtype, np.integer):
            raise ConfigError(f"sources must be an integer (n_targets, synapses per CN) matrix, "
                              f"got shape {np.shape(self.sources)}")
        if src.min() < 0 or src.max() >= S:
            raise ConfigError(f"a synapse's source is outside 0 .. {S - 1}")
        for j, row in enumerate(src):
            if len(np.unique(row)) != len(row):
                raise ConfigError(f"CN {j} takes an afferent twice")
        self.src = src.astype(np.int64)
        M, K = src.shape
        self.n_targets, self.n_synapses = int(M), int(K)
        self.cycles_per_tick = whole_cycles_per_tick(self.clock_hz, self.update_hz)
        self.dt_ms = 1000.0 / self.update_hz
        p = self.rule
        try:
            self.latency_ticks = p.latency_ticks(self.dt_ms)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        if self.latency_ticks > MAX_LATENCY_TICKS:
            raise ConfigError(f"a calcium latency of {self.latency_ticks} ticks is more than "
                              f"the {MAX_LATENCY_TICKS} delayed spike words the layer keeps")
        # weights
        wb = self.weight_bits
        if not isinstance(wb, (int, np.integer)) or not 4 <= wb <= self.operand_width:
            raise ConfigError(f"weight_bits must be an integer in 4 .. {self.operand_width}")
        self.W = QFormat.for_range(0.0, p.w_max, wb, signed_=False)
        F = self.trace_frac_bits
        if not isinstance(F, (int, np.integer)) or F < self.W.frac_bits:
            raise ConfigError(f"trace_frac_bits ({F}) must hold the weights' {self.W.frac_bits} "
                              f"fraction bits")
        self.wshift = F - self.W.frac_bits
        self.w_max_raw = self.W.to_raw(p.w_max, rounding="truncate")
        w = np.full((M, K), p.w_max / 4) if self.weights is None else \
            np.asarray(self.weights, dtype=np.float64)
        if w.shape != (M, K):
            raise ConfigError(f"weights must have shape (n_targets, K) = ({M}, {K}), got "
                              f"{w.shape}")
        if not np.all(np.isfinite(w)) or w.min() < 0 or w.max() > p.w_max:
            raise ConfigError(f"initial weights must lie in [0, w_max = {p.w_max:g}] mV/ms")
        self.weights_real = w
        self.weights_raw = np.minimum(self.W.to_raw(w), self.w_max_raw)
        self._derive_traces()
        self._derive_learning()
        self._derive_izhikevich()
        # cycles
        self.cycles_needed = TICK_PROLOGUE + M * (K + CYCLES_PER_TARGET_EXTRA)
        if self.cycles_needed > self.cycles_per_tick:
            raise ConfigError(f"{M} CNs x {K} synapses need {self.cycles_needed} cycles per "
                              f"tick; {self.clock_hz:g} Hz / {self.update_hz:g} Hz gives "
                              f"{self.cycles_per_tick}")
        self.learn_cycles = M * (2 * K + 1) + 1

    def _derive_traces(self):
        F, ow, dt, p = self.trace_frac_bits, self.operand_width, self.dt_ms, self.rule
        M, K, S = self.n_targets, self.n_synapses, self.n_sources
        wmax = self.w_max_raw * self.W.lsb
        mk = (lambda name, tau, top, what: trace_spec(name, tau, dt, ow, F, top,
                                                      self.max_decay_error, what))
        try:
            self.calcium = [mk("c_d", p.tau_decay_ms, wmax, "local calcium"),
                            mk("c_r", p.tau_rise_ms, wmax, "local calcium")]
            self.exc = mk("E", self.tau_syn_ms, K * wmax, "excitation")
            self.inh = mk("H", self.tau_syn_ms, float(S), "interneuron")
        except ConfigError:
            raise
        tv = (lambda specs: TraceView(specs, QFormat(max(s.T.int_bits for s in specs), F),
                                      self.rounding, dt))
        self.cview, self.eview, self.hview = tv(self.calcium), tv([self.exc]), tv([self.inh])
        # the interneuron's inhibition g H: H rounded to an operand, g normalized
        h_hi = self.inh.t_bounds[1] * 2.0 ** -F
        self.HQ = QFormat.for_range(-1.0, h_hi, ow)
        if self.HQ.frac_bits > F:
            self.HQ = QFormat(self.HQ.width - F, F)
        self.G = FixedConstant.normalized("g_inh", self.g_inh, ow, signed=False) \
            if self.g_inh > 0 else FixedConstant("g_inh", 0.0, 0, 0, ow, False)
        self.i_frac_bits = 8
        self.g_shift = self.HQ.frac_bits + self.G.frac_bits - self.i_frac_bits
        half = 1
        self.inh_raw_bounds = (-half - 1,
                               int(math.ceil((self.HQ.max_raw * self.G.raw) *
                                             2.0 ** -self.g_shift)) + half + 1)
        self.e_shift = F - self.i_frac_bits
        e_lo, e_hi = self.exc.t_bounds
        self.i_raw_bounds = ((e_lo >> self.e_shift) - 1 - self.inh_raw_bounds[1],
                             (e_hi >> self.e_shift) + 2 - self.inh_raw_bounds[0])
        lsb_i = 2.0 ** -self.i_frac_bits
        self.I_full = QFormat(int_bits_for(self.i_raw_bounds[0] * lsb_i,
                                           self.i_raw_bounds[1] * lsb_i), self.i_frac_bits)

    def _derive_learning(self):
        p, F, ow, K = self.rule, self.trace_frac_bits, self.operand_width, self.n_synapses
        lim = float(self.current_limit)
        if not math.isfinite(lim) or lim <= 0:
            raise ConfigError(f"current_limit must be > 0 mV/ms, got {self.current_limit!r}")
        Ii = QFormat(self.I_full.int_bits, self.i_frac_bits)
        self.i_lim_raw = (Ii.to_raw(-lim), Ii.to_raw(lim))
        if not self.I_full.min_raw <= self.i_lim_raw[0] < self.i_lim_raw[1] <= \
                self.I_full.max_raw:
            raise ConfigError(f"current_limit {lim:g} is outside the drive's format")
        # zero-offset main calcium: the clamped drive minus the threshold
        self.theta_raw = Ii.to_raw(p.theta)
        z_lo, z_hi = self.i_lim_raw[0] - self.theta_raw, self.i_lim_raw[1] - self.theta_raw
        self.z_bounds = (z_lo, z_hi)
        self.Z = QFormat.for_raw(z_lo, z_hi, self.i_frac_bits)
        if self.Z.width > ow:
            raise ConfigError(f"the zero-offset main calcium needs {self.Z.width} bits, more "
                              f"than the {ow}-bit multiplier operand (lower current_limit or "
                              f"theta)")
        # local calcium C = c_d - c_r as fetched, and its operand
        (dlo, dhi), (rlo, rhi) = self.calcium[0].t_bounds, self.calcium[1].t_bounds
        self.c_bounds = (dlo - rhi, dhi - rlo)
        cq = QFormat.for_range(self.c_bounds[0] * 2.0 ** -F - 2.0 ** -F,
                               self.c_bounds[1] * 2.0 ** -F + 2.0 ** -F, ow)
        self.CQ = cq if cq.frac_bits <= F else QFormat(cq.width - F, F)
        self.c_shift = F - self.CQ.frac_bits
        self.cq_bounds = ((self.c_bounds[0] >> self.c_shift) - 1,
                          (self.c_bounds[1] >> self.c_shift) + 1)
        # the drive L, integrating round(C Z) per tick
        di, df = self.drive_int_bits, self.drive_frac_bits
        if not (isinstance(di, (int, np.integer)) and isinstance(df, (int, np.integer))
                and di >= 2 and df >= 0 and di + df <= 48):
            raise ConfigError("drive_int_bits >= 2, drive_frac_bits >= 0 and at most 48 bits "
                              "in all")
        self.L = QFormat(di, df)
        self.q_shift = self.CQ.frac_bits + self.i_frac_bits - df
        if self.q_shift < 0:
            raise ConfigError(f"drive_frac_bits ({df}) exceeds the product's "
                              f"{self.CQ.frac_bits + self.i_frac_bits}")
        # compensation: D = K L - total (exact), rounded to an operand
        self.total_bits = self.L.width + max(1, (K - 1).bit_length()) + 1
        d_span = K * (self.L.max_raw - self.L.min_raw)
        self.d_bounds = (-d_span, d_span)
        self.d_shift = 0
        while True:
            lo = self.d_bounds[0] >> self.d_shift
            hi = (self.d_bounds[1] >> self.d_shift) + (1 if self.d_shift else 0)
            self.DQ = QFormat.for_raw(lo, hi, 0)
            if self.DQ.width <= ow:
                break
            self.d_shift += 1
        self.dq_bounds = (lo, hi)
        # the step table: eta alpha dt sigma(w, sign) / K, in weight LSBs per D_q LSB
        nb = self.sigmoid_bits
        if not isinstance(nb, (int, np.integer)) or not 1 <= nb <= self.W.width:
            raise ConfigError(f"sigmoid_bits must be in 1 .. {self.W.width}")
        self.sig_shift = self.W.width - nb
        centres = (np.arange(1 << nb) + 0.5) * 2.0 ** self.sig_shift * self.W.lsb
        unit = p.eta * p.alpha * self.dt_ms / K * 2.0 ** (self.d_shift - df) / self.W.lsb
        self.step_unit = unit
        tables = [unit * sigmoid(centres, True, p), unit * sigmoid(centres, False, p)]
        top = max(float(np.max(t)) for t in tables)
        if top == 0:
            self.T_frac = 0
            self.step_tables = [np.zeros(1 << nb, np.int64) for _ in tables]
        else:
            ref = FixedConstant.normalized("step", top, ow, signed=False)
            self.T_frac = ref.frac_bits
            self.step_tables = [np.floor(t * 2.0 ** ref.frac_bits + 0.5).astype(np.int64)
                                for t in tables]
            if any(int(t.max()) == 0 for t in self.step_tables):
                raise ConfigError(f"the step eta = {p.eta:g} rounds to 0 in a sigmoid table")
        self.step_bits = max(1, int(max(int(t.max()) for t in self.step_tables)).bit_length())
        biggest = max(abs(x) for x in self.dq_bounds) * max(int(t.max()) for t in
                                                            self.step_tables)
        if p.eta > 0 and biggest * 2.0 ** -self.T_frac < 0.5:
            raise ConfigError(f"the step eta = {p.eta:g} rounds to 0: the largest drive moves a "
                              f"weight by {biggest * 2.0 ** -self.T_frac:.3g} of its LSB "
                              f"({self.W})")
        self.table_errors = [float(np.max(np.abs(t * 2.0 ** -self.T_frac - e) / np.maximum(e,
                             1e-300))) if top else 0.0 for t, e in zip(self.step_tables, tables)]

    def _derive_izhikevich(self):
        lsb = 2.0 ** -self.i_frac_bits
        self.iz, self.target_sets_ = target_arithmetic(
            self, "learning layer: the CNs", self.I_full,
            (self.i_lim_raw[0] * lsb, self.i_lim_raw[1] * lsb))

    # ------------------------------------------------------------------------------------------
    @property
    def step_table(self) -> list[int]:
        """The step table as the ROM holds it: depression's bins, then potentiation's."""
        return [int(x) for x in np.concatenate(self.step_tables[::-1])]

    @property
    def synapse_fields(self) -> list[tuple[str, QFormat]]:
        """The synapse word's fields (first at the LSB): weight, the two calcium traces, the
        drive (the weight alone when not ``plastic``)."""
        if not self.plastic:
            return [("w", self.W)]
        return [("w", self.W), ("c_d", self.calcium[0].T), ("c_r", self.calcium[1].T),
                ("L", self.L)]

    @property
    def target_fields(self) -> list[tuple[str, QFormat]]:
        """The CN word's fields: ``v``, ``u``, the excitation ``E``."""
        return [("v", self.iz.V), ("u", self.iz.U), ("E", self.exc.T)]

    def to_kwargs(self) -> dict:
        """Constructor keywords (JSON-friendly) that rebuild this configuration (the rule as
        a dict: :meth:`from_kwargs`)."""
        return {"n_sources": int(self.n_sources), "sources": self.src.tolist(),
                "weights": self.weights_real.tolist(),
                "rule": {k: v for k, v in self.rule.to_dict().items() if k != "alpha"},
                "tau_syn_ms": self.tau_syn_ms, "g_inh": self.g_inh,
                "current_limit": self.current_limit,
                "param_sets": [p if isinstance(p, str) else dict(p) for p in self.param_sets],
                "target_sets": list(self.target_sets_), "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "tick_source": self.tick_source,
                "weight_bits": int(self.weight_bits),
                "trace_frac_bits": int(self.trace_frac_bits),
                "drive_int_bits": int(self.drive_int_bits),
                "drive_frac_bits": int(self.drive_frac_bits),
                "sigmoid_bits": int(self.sigmoid_bits),
                "operand_width": int(self.operand_width), "rounding": self.rounding,
                "max_decay_error": self.max_decay_error, "plastic": bool(self.plastic)}

    @classmethod
    def from_kwargs(cls, kw: dict) -> "PlasticityConfig":
        kw = dict(kw)
        if isinstance(kw.get("rule"), dict):
            kw["rule"] = AidpParams(**kw["rule"])
        return cls(**kw)

    def to_dict(self) -> dict:
        """Everything a user of the generated Verilog needs (written beside it as JSON)."""
        M, K = self.n_targets, self.n_synapses
        sw = sum(f.width for _, f in self.synapse_fields)
        cw = sum(f.width for _, f in self.target_fields)
        return {
            "block": "LearningLayer", "n_sources": self.n_sources, "n_targets": M,
            "synapses_per_target": K, "clock_hz": self.clock_hz, "update_hz": self.update_hz,
            "dt_ms": self.dt_ms, "cycles_per_tick": self.cycles_per_tick,
            "cycles_needed": self.cycles_needed, "learn_cycles": self.learn_cycles,
            "throughput": f"one synapse per cycle; {CYCLES_PER_TARGET_EXTRA} cycles per CN "
                          f"and {TICK_PROLOGUE} per tick beyond",
            "rule": self.rule.to_dict(), "tau_syn_ms": self.tau_syn_ms, "g_inh": self.g_inh,
            "latency_ticks": self.latency_ticks, "current_limit": self.current_limit,
            "formats": {"weight": self.W.to_dict(),
                        "calcium": {s.name: s.to_dict() for s in self.calcium},
                        "excitation": self.exc.to_dict(), "interneuron": self.inh.to_dict(),
                        "drive_current": str(self.I_full), "main_calcium_operand": str(self.Z),
                        "local_calcium_operand": str(self.CQ), "learning_drive": str(self.L),
                        "compensated_drive_operand": str(self.DQ),
                        "compensated_drive_shift": self.d_shift},
            "step_table": {"bins": 1 << self.sigmoid_bits, "frac_bits": self.T_frac,
                           "unit_weight_lsb_per_operand_lsb": self.step_unit,
                           "max_rel_error": self.table_errors},
            "g_inh_constant": self.G.to_dict(),
            "clamps": list(CLAMP_KINDS),
            "izhikevich": {k: v for k, v in self.iz.to_dict().items()
                           if k in ("formats", "param_sets", "constants", "proven_range",
                                    "clamps", "multiplier_operands")},
            "memories": {"synapses": f"{M * K} x {sw} bits", "targets": f"{M} x {cw} bits",
                         "sources": f"{M * K} x {max(1, (self.n_sources - 1).bit_length())} "
                                    f"bits"},
            "latency": f"a synapse operation writes back {STAGE_LATENCY} cycles after its "
                       f"issue; an input spike stamped with tick T drives the CNs from tick "
                       f"T + 1 and their synapses' calcium from tick T + latency + 1",
        }
