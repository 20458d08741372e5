"""Synaptic traces: two-exponential currents as pairs of decaying per-neuron traces, shared by
the LIF core (AMPA / GABA, four traces) and the coincidence detector (one PSP, two traces).

:func:`trace_spec` sizes one trace (its decay constant, operand and stored formats) from its
time constant and the largest input it can receive per tick; the stage functions
(:func:`trace_inputs`, :func:`trace_products`, :func:`trace_update`) run in the twins and the RTL.

The LIF core's use:

With ``LifConfig(synapses=True)`` every input source is excitatory (AMPA) or inhibitory (GABA)
(``input_types``), weights are non-negative peak currents in mV (the sign comes from the type,
as in :func:`cuneate.golden.lif.simulate_lif_network`), and each neuron carries four traces, a
decay and a rise trace per type. Per tick, with ``a_T = sum_{i of type T} (w_i / N_T) x_i``::

    I_syn = (xd_A - xr_A) - (xd_G - xr_G)            (traces as fetched)
    D     = clamp(I) + I_syn
    x'    = y - k y,   y = x + a_T                   for each of the four traces,
                       k = 1 - exp(-dt / tau)        (its rise or decay time constant)

so an input spike of tick k contributes ``w K(j dt)`` to the current of tick ``k + j`` - the
golden difference-of-exponentials kernel (peak-normalized by ``N_T``, the weight memory holds
``w / N_T``) sampled on the grid, 0 at ``j = 0``; any conduction latency is the sender's. Each
trace decay is one multiplier (18-bit operand of ``y`` rounded, 18-bit ``k``); the traces use
the state's fraction bits and integer bits proven from the largest per-tick input of each type.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...golden import synapses as gsyn
from .config import ConfigError, int_bits_for
from .fixed import FixedConstant, QFormat, narrow, product, round_shift, select, tree_sum

__all__ = ["TRACE_NAMES", "TraceSpec", "TraceView", "trace_spec", "scale_weights",
           "derive_traces", "derive_cuba_trace", "cuba_input", "CUBA_TRACE", "trace_inputs",
           "trace_products", "trace_update",
           "trace_golden_check"]

#: trace order everywhere (state word, probe ports, twin arrays)
TRACE_NAMES = ("xd_ampa", "xr_ampa", "xd_gaba", "xr_gaba")


@dataclass
class TraceSpec:
    name: str
    tau_ms: float
    k_exact: float
    K: FixedConstant
    Y: QFormat                 # multiplier operand (y rounded)
    y_bounds: tuple[int, int]  # raw, in Y
    T: QFormat                 # stored trace
    t_bounds: tuple[int, int]  # raw, in T
    product_shift: int
    y_max: float

    def to_dict(self) -> dict:
        return {"tau_ms": self.tau_ms, "k_exact": self.k_exact, "k": self.K.to_dict(),
                "operand": str(self.Y), "trace": str(self.T), "y_max": self.y_max}


@dataclass
class TraceView:
    """What the trace stage functions read of a configuration: the trace specs, the state
    format (its fraction bits are the traces'), the rounding and dt."""

    traces: list
    V: QFormat
    rounding: str
    dt_ms: float


def trace_spec(name: str, tau_ms: float, dt_ms: float, operand_width: int, frac_bits: int,
               input_max: float, max_decay_error: float, what: str = "trace",
               input_min: float = 0.0) -> TraceSpec:
    """One trace's formats: ``x' = y - round(k round(y))``, ``y = x + a`` with ``a`` in
    ``[input_min, input_max]`` per tick (``input_min < 0``: a signed trace, as the LIF core's
    current-based synapse), ``k = 1 - exp(-dt/tau)`` in ``operand_width`` bits (refused when its
    representation error exceeds ``max_decay_error``), the stored trace in ``frac_bits``
    fraction bits and integer bits proven from the steady states of the extreme inputs."""
    lsb = 2.0 ** -frac_bits
    k = -math.expm1(-dt_ms / tau_ms)
    K = FixedConstant.normalized(f"k_{name}", k, operand_width)
    if K.quantized >= 1 or K.quantized <= 0 or abs(K.rel_error) > max_decay_error:
        raise ConfigError(f"{what} {name}: decay k = 1 - exp(-dt/tau) = {k:.6g} (tau "
                          f"{tau_ms:g} ms at dt {dt_ms:g} ms) is represented as "
                          f"{K.quantized:.6g} in {operand_width} bits")
    y_max = input_max / K.quantized + 8 * lsb
    y_min = min(0.0, input_min) / K.quantized - (8 * lsb if input_min < 0 else 0.0)
    Y = QFormat.for_range(y_min - 4 * lsb, y_max, operand_width)
    if Y.frac_bits > frac_bits:
        Y = QFormat(Y.int_bits, frac_bits)
    # the stored trace: y - round(k round(y)) can pass 0 (or y_min) by the operand rounding
    t_lo = y_min - (Y.lsb + 2 * lsb) / K.quantized - 4 * lsb
    t_hi = y_max + (Y.lsb + 2 * lsb) / K.quantized
    T = QFormat(int_bits_for(t_lo, t_hi), frac_bits)
    t_bounds = (int(math.floor(t_lo / lsb)), int(math.ceil(t_hi / lsb)))

    def y_bounds(Y):
        return (int(math.floor((t_lo + min(0.0, input_min)) / Y.lsb)) - 1,
                int(math.ceil((t_hi + input_max) / Y.lsb)) + 1)
    lo_r, hi_r = y_bounds(Y)
    while not (Y.min_raw <= lo_r and hi_r <= Y.max_raw):
        Y = QFormat(Y.int_bits + 1, Y.frac_bits - 1)
        lo_r, hi_r = y_bounds(Y)
    return TraceSpec(name, float(tau_ms), k, K, Y, (lo_r, hi_r), T, t_bounds,
                     Y.frac_bits + K.frac_bits - frac_bits, y_max)


def scale_weights(cfg, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate the typed weights; returns ``(w / N_type, is_exc mask)``."""
    if cfg.form != "continuous":
        raise ConfigError("synaptic traces belong to the continuous form")
    F = w.shape[1]
    if F == 0:
        raise ConfigError("synapses=True needs weights (n_neurons x n_inputs)")
    if np.any(w < 0):
        raise ConfigError("with synapses the weights must be >= 0 (the sign comes from the "
                          "synapse type: AMPA adds, GABA subtracts)")
    types = ["exc"] * F if cfg.input_types is None else list(cfg.input_types)
    if len(types) != F or any(t not in ("exc", "inh") for t in types):
        raise ConfigError(f"input_types needs {F} entries of 'exc' or 'inh'")
    exc = np.array([t == "exc" for t in types])
    try:
        na = gsyn.norm_factor(*gsyn.check_taus(*cfg.ampa), "peak")
        ng = gsyn.norm_factor(*gsyn.check_taus(*cfg.gaba), "peak")
    except ValueError as exc_:
        raise ConfigError(f"synapse time constants: {exc_}") from None
    return w / np.where(exc, na, ng)[None, :], exc


def derive_traces(cfg) -> tuple[list[TraceSpec], tuple[int, int]]:
    """Trace formats and constants; returns the specs and the raw bounds of ``I_syn`` (in
    state fraction bits)."""
    fv, ow, lsb = cfg.v_frac_bits, cfg.operand_width, 2.0 ** -cfg.v_frac_bits
    wr = cfg.weights_raw
    wsh = fv - cfg.W.frac_bits
    acc_max = {"ampa": float((wr[:, cfg.input_exc].sum(axis=1).max() << wsh) * lsb)
               if cfg.input_exc.any() else 0.0,
               "gaba": float((wr[:, ~cfg.input_exc].sum(axis=1).max() << wsh) * lsb)
               if (~cfg.input_exc).any() else 0.0}
    taus = {"xd_ampa": cfg.ampa[1], "xr_ampa": cfg.ampa[0], "xd_gaba": cfg.gaba[1],
            "xr_gaba": cfg.gaba[0]}
    specs = [trace_spec(name, float(taus[name]), cfg.dt_ms, ow, fv,
                        acc_max[name.split("_")[1]], cfg.max_decay_error)
             for name in TRACE_NAMES]
    # I_syn = (xd - xr)_A - (xd - xr)_G: the difference of exponentials of the largest
    # steady input, plus rounding margins
    def diff(kd, kr, a):
        return a * ((1 - kd) / kd - (1 - kr) / kr)
    sa = diff(specs[0].K.quantized, specs[1].K.quantized, acc_max["ampa"])
    sg = diff(specs[2].K.quantized, specs[3].K.quantized, acc_max["gaba"])
    marg = sum((s.Y.lsb + 2 * lsb) / s.K.quantized for s in specs) + 8 * lsb
    lo = -(max(0.0, sg) + marg)
    hi = max(0.0, sa) + marg
    return specs, (int(math.floor(lo / lsb)), int(math.ceil(hi / lsb)))


#: the LIF core's current-based synapse: one signed trace per neuron
CUBA_TRACE = "x_syn"


def derive_cuba_trace(cfg) -> tuple[list[TraceSpec], tuple[int, int]]:
    """The current-based synapse of a discrete LIF core (``syn_alpha``, NIR's ``CubaLIF``):
    one signed trace ``x`` per neuron; per tick ``y = x + I + a`` (the host current ``I`` and
    ``a = sum_i w_i x_i``, the weighted input spikes of the tick), ``D = y`` and ``x' = y - k y``
    with ``k = 1 - syn_alpha``. The synaptic current of a spike enters the membrane in its own
    tick and decays by ``syn_alpha`` per tick after (snnTorch's ``Synaptic``; the schemes of
    :mod:`cuneate.sim.nir.discretize` put their factors into the weights). Returns the spec
    and the raw bounds of ``y`` (state fraction bits), which is all of ``D``."""
    fv, lsb = cfg.v_frac_bits, 2.0 ** -cfg.v_frac_bits
    wsh, ish = fv - cfg.W.frac_bits, fv - cfg.I.frac_bits
    lo_raw = (int(cfg.syn_lo_raw.min()) << wsh if cfg.n_inputs else 0) + (cfg.i_lo_raw << ish)
    hi_raw = (int(cfg.syn_hi_raw.max()) << wsh if cfg.n_inputs else 0) + (cfg.i_hi_raw << ish)
    tau_ms = -cfg.dt_ms / math.log(cfg.syn_alpha)
    spec = trace_spec(CUBA_TRACE, tau_ms, cfg.dt_ms, cfg.operand_width, fv, hi_raw * lsb,
                      cfg.max_decay_error, "current-based synapse", input_min=lo_raw * lsb)
    return [spec], (spec.t_bounds[0] + lo_raw, spec.t_bounds[1] + hi_raw)


def cuba_input(cfg, traces, I, acc):
    """Stage 3 of the current-based synapse: ``y = x + I + a`` (``I`` in current LSBs, ``a``
    in weight LSBs, ``y`` in state LSBs)."""
    fv = cfg.V.frac_bits
    return traces[0] + (I << (fv - cfg.I.frac_bits)) + (acc << (fv - cfg.W.frac_bits))


# ----------------------------------------------------------------------------------------------
# stage functions (twin and RTL)

def trace_inputs(cfg, traces, x, w):
    """Stage 3: ``I_syn`` from the fetched traces and ``y = x + a_T`` for each trace; returns
    ``(I_syn, [y...], acc)`` with ``acc = a_A - a_G`` in weight LSBs."""
    terms = [select(xi, wi, 0) for xi, wi in zip(x, w)]
    acc_a = tree_sum(t for t, e in zip(terms, cfg.input_exc) if e)
    acc_g = tree_sum(t for t, e in zip(terms, cfg.input_exc) if not e)
    wsh = cfg.V.frac_bits - cfg.W.frac_bits
    xd_a, xr_a, xd_g, xr_g = traces
    i_syn = (xd_a - xr_a) - (xd_g - xr_g)
    ys = [t + (a << wsh) for t, a in zip(traces, (acc_a, acc_a, acc_g, acc_g))]
    return i_syn, ys, acc_a - acc_g


def trace_products(cfg, ys):
    """Stage 4: ``round(k round(y))`` for each trace (one multiplier each)."""
    out = []
    for s, y in zip(cfg.traces, ys):
        yq = narrow(round_shift(y, cfg.V.frac_bits - s.Y.frac_bits, cfg.rounding), s.Y,
                    s.y_bounds, f"{s.name} operand")
        out.append(round_shift(product(yq, s.K.raw, "trace_products"), s.product_shift,
                               cfg.rounding))
    return out


def trace_update(cfg, ys, ps):
    """Stage 5: ``x' = y - k y`` for each trace, in its proven format (no clamp)."""
    return [narrow(y - p, s.T, s.t_bounds, s.name) for s, y, p in zip(cfg.traces, ys, ps)]


def trace_golden_check(cfg, ys, traces_out):
    """Float64 golden trace step ``exp(-dt/tau) y`` from the same ``y`` (raw, state fraction
    bits) against the fixed result; returns ``(abs errors, bounds)`` arrays (4, n). The bound:
    the represented ``k`` against the exact one, the rounding of the operand and the product."""
    half = 0.5 if cfg.rounding == "nearest" else 1.0
    lsb = cfg.V.lsb
    errs, bounds = [], []
    for s, y, t in zip(cfg.traces, ys, traces_out):
        yf = np.asarray(y, dtype=np.float64) * lsb
        gold = yf * math.exp(-cfg.dt_ms / s.tau_ms)
        errs.append(np.abs(np.asarray(t, dtype=np.float64) * lsb - gold))
        bounds.append(abs(s.K.quantized - s.k_exact) * np.abs(yf) + s.K.quantized * half * s.Y.lsb
                      + half * lsb + 1e-12 * (1 + np.abs(yf)))
    return np.array(errs), np.array(bounds)
