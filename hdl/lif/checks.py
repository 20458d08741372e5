"""What a LIF configuration refuses beyond its formats: a parameter set that is not one
(:class:`LifSet`), a weight memory no supported FPGA holds, formats wider than the twin's int64
carries, and a leak that never acts below threshold (:class:`~cuneate.hdl.lif.config.LifConfig`
calls these at construction)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...golden import lif as golden
from ..lib.config import MAX_BLOCK_RAM_BITS, ConfigError

__all__ = ["LifSet", "MAX_V_FRAC_BITS", "MAX_OPERAND_WIDTH", "MAX_WEIGHT_BITS",
           "check_weight_memory", "check_leak", "check_int64"]

#: the widest formats offered: the state's fraction, the leak multiplier's operands and a weight
#: (with the state's integer bits and a fan-in, the twin's int64 holds every intermediate;
#: :func:`check_int64` checks a configuration's own widest value)
MAX_V_FRAC_BITS, MAX_OPERAND_WIDTH, MAX_WEIGHT_BITS = 40, 36, 32


@dataclass(frozen=True)
class LifSet:
    """One parameter set, in the units of its form.

    Continuous: ``tau_m_ms``, ``v_th``, ``v_reset``, ``v_rest`` (mV) and ``t_ref_ms``.
    Discrete: ``alpha`` (decay per step), ``v_th`` (= ``u_th``, strict threshold), ``v_reset``
    (= ``u_rest``), ``refractory_steps``; the leak target is 0.
    """

    v_th: float
    v_reset: float
    v_rest: float = 0.0
    tau_m_ms: float | None = None
    t_ref_ms: float = 0.0
    alpha: float | None = None
    refractory_steps: int = 0

    def to_dict(self) -> dict:
        return dict(self.__dict__)

    @classmethod
    def make(cls, spec, form: str) -> "LifSet":
        if isinstance(spec, LifSet):
            return spec
        if not isinstance(spec, dict):
            raise ConfigError(f"a parameter set is a dict of its values, got {spec!r}")
        d = dict(spec)
        if form == "discrete":
            d.setdefault("alpha", golden.DISCRETE_ALPHA)
            d["v_th"] = d.pop("u_th", d.get("v_th", golden.DISCRETE_U_TH))
            d["v_reset"] = d.pop("u_rest", d.get("v_reset", 0.0))
            d.setdefault("v_rest", 0.0)
        else:
            d.setdefault("tau_m_ms", golden.TAU_M_EXC_MS)
            d.setdefault("v_th", golden.V_TH)
            d.setdefault("v_reset", golden.V_RESET)
            d.setdefault("v_rest", golden.V_REST)
            d.setdefault("t_ref_ms", golden.T_REF_EXC_MS)
        try:
            s = cls(**d)
        except TypeError as exc:
            raise ConfigError(f"parameter set {spec!r}: {exc}") from None
        for k, v in s.__dict__.items():
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ConfigError(f"parameter set: {k} = {v!r} is not a finite number")
        if not s.v_reset < s.v_th:
            raise ConfigError(f"parameter set: reset {s.v_reset:g} must lie below the "
                              f"threshold {s.v_th:g}")
        if form == "continuous":
            if s.tau_m_ms is None or s.tau_m_ms <= 0:
                raise ConfigError(f"parameter set: tau_m_ms must be > 0, got {s.tau_m_ms!r}")
            if s.t_ref_ms < 0:
                raise ConfigError(f"parameter set: t_ref_ms must be >= 0, got {s.t_ref_ms!r}")
        else:
            if s.alpha is None or not 0.0 <= s.alpha <= 1.0:
                raise ConfigError(f"parameter set: alpha must lie in [0, 1], got {s.alpha!r}")
            if int(s.refractory_steps) != s.refractory_steps or s.refractory_steps < 0:
                raise ConfigError("parameter set: refractory_steps must be an integer >= 0")
        return s


def check_weight_memory(n_neurons: int, n_inputs: int, weight_bits: int) -> None:
    """Refuse a weight memory (``n_neurons`` words of ``n_inputs`` weights) larger than the
    block RAM of the largest supported FPGA, before any weight is quantized."""
    bits = float(n_neurons) * n_inputs * weight_bits
    if bits > MAX_BLOCK_RAM_BITS:
        raise ConfigError(f"the weight memory of {n_neurons} neurons x {n_inputs} inputs x "
                          f"{weight_bits} bits needs {bits:.4g} bits; the largest supported "
                          f"FPGA holds {MAX_BLOCK_RAM_BITS} bits of block RAM")


def check_leak(cfg) -> None:
    """Refuse a leak that never acts below threshold: ``k x`` under the rounding's reach for
    every state between reset, rest and threshold (the neuron would integrate and fire as
    an IF neuron, which the core does not build)."""
    lsb = cfg.V.lsb
    reach = 0.5 * lsb if cfg.rounding == "nearest" else lsb
    cont = cfg.form == "continuous"
    for i, (s, kq) in enumerate(zip(cfg.sets, cfg.k_q)):
        ref = s.v_rest if cont else 0.0
        x = max(abs(s.v_th - ref), abs(s.v_reset - ref))
        if 0 < kq * x < reach:
            need = math.ceil(-math.log2(kq * x)) + (1 if cfg.rounding == "nearest" else 0)
            raise ConfigError(
                f"set {i}: decay alpha = 1 - {kq:.3g}: below threshold the leak k x stays "
                f"under {kq * x:.3g}, less than the state's rounding ({reach:.3g} at "
                f"{cfg.v_frac_bits} fraction bits), so it never acts: the neuron would be "
                f"an IF neuron (no leak); give the state {need} fraction bits or a faster "
                f"decay")


def check_int64(cfg) -> None:
    """The widest intermediate of the twin (the leak product, the state sums, the total
    input), bounded once from the formats: it must stay below 2**62 (int64)."""
    fv = cfg.v_frac_bits
    big = [abs(cfg.V.min_raw), cfg.V.max_raw, abs(cfg.d_lo_raw), abs(cfg.d_hi_raw),
           abs(cfg.d_proven_raw[0]), abs(cfg.d_proven_raw[1])]
    if cfg.X is not None:
        big.append(max(abs(b) for b in cfg.x_bounds_raw) * max(abs(c.raw) for c in cfg.K))
    bits = max(int(b).bit_length() for b in big) + 2
    if bits >= 62:
        raise ConfigError(f"the datapath's widest value needs {bits} bits (state "
                          f"{cfg.V}, {fv} fraction bits); reduce the state fraction bits, "
                          f"the weights or the operand width")
