"""Mapping a chain of NIR layers onto LIF cores, with every quantization reported.

:func:`map_graph` takes the layers of :func:`cuneate.sim.nir.graph.layers_of`, the step ``dt``
and the scheme (:mod:`cuneate.golden.nir`) and builds a :class:`MappedNetwork`: one discrete LIF
core per layer (:class:`~cuneate.hdl.nir.NirNetworkConfig`). Per layer, with the scheme's grid
constants ``alpha_m, g_m`` (and ``alpha_s, g_s`` with a synapse), ``u = v - v_leak``:

* **Weights** ``g_m W`` (``g_m g_s W`` with a synapse) in ``weight_bits`` signed bits, the
  scale (LSB ``2**-f``) the finest that holds the layer's largest weight, or ``weight_frac_bits``
  when given (a weight outside that format is refused: it would saturate). Rounded to nearest.
* **Bias** ``g_m b`` (``g_m g_s b``) as the host current, in a 16-bit format sized to the layer.
* **Neurons** ``alpha_m``, ``u_th = v_threshold - v_leak``, ``u_reset = v_reset - v_leak`` as
  the core's parameter sets (one per distinct triple), ``v_init = -v_leak``; the synapse's
  ``syn_alpha`` (one per layer); the Delay as input delays in ticks.
* **Readout** (LI, CubaLI; last layer only): the threshold above the proven state range.
* **Scale** (``weight_scale="max"``): the layer's state (weights, bias, threshold, reset,
  initial value) multiplied by ``s = (2**(bits-1) - 1) / max |g W|``, exact for LIF dynamics
  (linear between spikes, the next layer sees only spikes); a readout's membrane is divided back.

Refused, naming the node: IF and I (no leak: the core's decay lies in (0, 1)); a non-spiking
layer anywhere but last (a core passes spikes, not values); a synapse decay that differs
between the neurons of one layer; a delay longer than the core's input history; anything the
core's configuration refuses (its one-line reason follows the node's name).

The report (:attr:`MappedNetwork.report`) gives per layer and quantity the range, the scale, the
worst-case error, how many values saturated or rounded to zero.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from ...golden.nir import LEAKY, SPIKING, SYNAPTIC, step_constants
from ...hdl.lib.config import ConfigError
from ...hdl.lib.fixed import FixedPointError, QFormat
from ...hdl.lif import LifConfig
from ...hdl.lif.config import MAX_INPUT_DELAY
from ...hdl.nir import NirNetworkConfig
from .graph import GraphChain, NirError

__all__ = ["MappedNetwork", "map_graph", "MIN_CORE", "DEFAULT_UPDATE_HZ"]

MIN_CORE = 8                      #: the LIF core's smallest size (idle neurons pad a layer)
DEFAULT_UPDATE_HZ = 10_000.0      #: dt = 0.1 ms, the step snnTorch's NIR export assumes
CURRENT_BITS = 16


@dataclass
class MappedNetwork:
    """A NIR graph on LIF cores: the chain (NIR parameters, for the golden model), the
    network configuration, the host currents (raw, per layer), ``dt`` (s), the scheme and the
    quantization report."""

    chain: GraphChain
    config: NirNetworkConfig
    currents_raw: list
    dt: float
    scheme: str
    report: list

    @property
    def n_inputs(self) -> int:
        return self.chain.n_inputs

    @property
    def n_outputs(self) -> int:
        return self.chain.layers[-1].n_out

    def to_dict(self) -> dict:
        return {"dt_s": self.dt, "scheme": self.scheme, "n_inputs": self.n_inputs,
                "nodes": self.chain.order, "layers": self.report,
                "input_threshold": (None if self.chain.input_threshold is None
                                    else self.chain.input_threshold.tolist()),
                "network": self.config.to_kwargs(),
                "currents_raw": [c.tolist() for c in self.currents_raw]}


def _quant(name: str, x: np.ndarray, fmt: QFormat) -> dict:
    q = fmt.to_float(fmt.to_raw(x))
    sat = int(np.count_nonzero((x > fmt.max_value + fmt.lsb / 2) | (x < fmt.min_value - fmt.lsb / 2)))
    return {"what": name, "range": [float(x.min(initial=0)), float(x.max(initial=0))],
            "format": str(fmt), "scale_lsb": fmt.lsb,
            "max_abs_error": float(np.abs(q - x).max(initial=0)),
            "max_rel_error_of_largest": (float(np.abs(q - x).max(initial=0) / np.abs(x).max())
                                         if x.size and np.abs(x).max() > 0 else 0.0),
            "saturated": sat, "zeroed": int(np.count_nonzero((q == 0) & (x != 0))),
            "values": int(x.size), "zero": int(np.count_nonzero(x == 0))}


def _weight_format(node, W, bits, frac_bits, v_frac) -> QFormat:
    if frac_bits is not None:
        if not 0 <= frac_bits < bits:
            raise NirError(f"node {node!r}: {frac_bits} fraction bits leave no sign bit in "
                           f"{bits}-bit weights")
        fmt = QFormat(bits - frac_bits, frac_bits)
        big = W[np.abs(W) > fmt.max_value + fmt.lsb / 2] if W.size else W
        if big.size:
            raise NirError(f"node {node!r}: weight {float(big.flat[0]):g} saturates "
                           f"{bits}-bit weights of {frac_bits} fraction bits ({fmt}, "
                           f"[{fmt.min_value:g}, {fmt.max_value:g}])")
    else:
        lo, hi = (float(W.min()), float(W.max())) if W.size else (0.0, 0.0)
        fmt = QFormat.for_range(min(lo, 0.0), max(hi, 0.0), bits) if (lo or hi) else \
            QFormat(1, bits - 1)
    if fmt.frac_bits > v_frac:
        fmt = QFormat(bits - v_frac, v_frac)
    return fmt


def _check_zeroed(name, kind, q: dict, fmt: QFormat) -> None:
    """Refuse a layer whose every non-zero weight rounds to 0 (it would never see its input);
    warn, in one line, when more than half of them do."""
    nz = q["values"] - q.get("zero", 0)
    if not q["zeroed"] or not nz:
        return
    what = (f"{q['zeroed']} of its {nz} non-zero weights round to 0 in {fmt} (LSB "
            f"{fmt.lsb:.3g}; largest |g W| {max(abs(x) for x in q['range']):.3g})")
    if q["zeroed"] >= nz:
        raise NirError(f"node {name!r} ({kind}): every one of its weights rounds to 0: {what}; "
                       f"the layer would never see its input (raise --v-frac-bits or "
                       f"--weight-bits)")
    if 2 * q["zeroed"] > nz:
        warnings.warn(f"node {name!r} ({kind}): {what}")


def _layer_core(li, layer, c, chain, n_src, update_hz, opts, readout):
    """The LIF core keywords of one layer and its report."""
    name, kind, n = layer.name, layer.kind, layer.n_out
    N = max(n, MIN_CORE)
    g = c.g_m * (c.g_s if c.g_s is not None else 1.0)
    # weight_scale "max": the layer's state is scaled by s so that its largest weight is the
    # weight format's largest integer (symmetric per-tensor INT weights then map exactly);
    # "pow2": weights below one half (the narrowest format's top octave) scale the state up by
    # the power of two that brings the largest into [1/2, 1), exactly (thresholds, resets,
    # biases and the initial state scale with it), so that small trained weights keep their
    # bits instead of rounding to 0; a fixed weight_frac_bits keeps the scale given
    big = float(np.abs(g[:, None] * layer.weight).max(initial=0))
    qmax = 2 ** (opts["weight_bits"] - 1) - 1
    sc = 1.0
    if opts.get("weight_scale") == "max" and big > 0:
        sc = qmax / big
    elif 0 < big < 0.5 and opts.get("weight_frac_bits") is None:
        sc = 2.0 ** math.floor(math.log2(0.99 / big))
    g = g * sc
    Whw = np.zeros((N, n_src))
    Whw[:n, :layer.n_in] = g[:, None] * layer.weight
    bias = np.zeros(N)
    bias[:n] = g * layer.bias
    v_frac = opts["v_frac_bits"]
    W = _weight_format(name, Whw[:n], opts["weight_bits"], opts.get("weight_frac_bits"), v_frac)
    blo, bhi = float(bias.min()), float(bias.max())
    If = QFormat.for_range(min(blo, 0.0), max(bhi, 0.0), CURRENT_BITS) if (blo or bhi) else \
        QFormat(4, min(12, v_frac))
    if If.frac_bits > v_frac:
        If = QFormat(CURRENT_BITS - v_frac, v_frac)
    rep = {"layer": li, "node": name, "kind": kind, "nodes": dict(layer.nodes), "neurons": n,
           "state_scale": sc,
           "core_neurons": N, "inputs": layer.n_in,
           "weights": _quant("weights g W", Whw[:n, :layer.n_in], W),
           "bias": _quant("bias g b (host current)", bias[:n], If)}
    _check_zeroed(name, kind, rep["weights"], W)
    if kind in SYNAPTIC:
        a_s = np.unique(np.round(c.alpha_s, 12))
        if a_s.size != 1:
            raise NirError(f"node {name!r} ({kind}): tau_syn differs between its neurons; the "
                           f"LIF core's synapse has one decay per layer")
    # parameter sets: one per distinct (alpha_m, u_th, u_reset)
    u_th = c.u_th * sc if c.u_th is not None else None
    if readout:
        # above any state the layer can reach: |u| <= |u0| + sum |input| / (1 - alpha)
        reach = np.abs(c.u0) + (np.abs(Whw[:n]).sum(1) + np.abs(bias[:n])) / \
            np.maximum(1 - c.alpha_m, 1e-9) / (1 - (float(c.alpha_s[0]) if c.alpha_s is not None
                                                     else 0.0))
        top = float(2 ** math.ceil(math.log2(max(1.0, float(reach.max()) + 1.0))))
        u_th, u_reset = np.full(n, top), np.zeros(n)
    else:
        u_reset = c.u_reset * sc
    keys = [(float(c.alpha_m[i]), float(u_th[i]), float(u_reset[i])) for i in range(n)]
    sets = sorted(set(keys))
    if len(sets) > 64:
        raise NirError(f"node {name!r} ({kind}): {len(sets)} distinct (decay, threshold, reset) "
                       f"combinations; the core holds at most 64 parameter sets")
    ps = [{"alpha": a, "u_th": t, "u_rest": r} for a, t, r in sets]
    ns = [sets.index(k) for k in keys] + [0] * (N - n)
    v_init = list(c.u0 * sc) + [0.0] * (N - n)
    delays = None
    if c.delay_steps is not None and np.any(c.delay_steps):
        d = np.zeros(n_src, dtype=np.int64)
        d[:layer.n_in] = c.delay_steps
        if d.max() > MAX_INPUT_DELAY:
            raise NirError(f"node {layer.nodes.get('delay', name)!r} (Delay): {int(d.max())} "
                           f"ticks is longer than the LIF core's input history "
                           f"({MAX_INPUT_DELAY} ticks)")
        delays = d.tolist()
    kw = {"n_neurons": N, "update_hz": update_hz, "form": "discrete", "param_sets": ps,
          "neuron_sets": ns, "v_frac_bits": v_frac, "operand_width": opts["operand_width"],
          "current_format": (If.int_bits, If.frac_bits), "weights": Whw if n_src else None,
          "weight_bits": opts["weight_bits"], "weight_frac_bits": W.frac_bits,
          "v_init": v_init, "tick_source": "external", "spike_fifo_depth": max(16, 2 * N + 4),
          "max_decay_error": opts["max_decay_error"], "rounding": opts["rounding"],
          "syn_alpha": float(c.alpha_s[0]) if kind in SYNAPTIC else None,
          "input_delays": delays}
    return kw, bias, If, rep


def map_graph(chain: GraphChain, update_hz: float = DEFAULT_UPDATE_HZ, scheme: str = "exact",
              weight_bits: int = 8, weight_frac_bits: int | None = None, v_frac_bits: int = 16,
              operand_width: int = 18, max_decay_error: float = 1e-2,
              rounding: str = "nearest", weight_scale: str = "pow2") -> MappedNetwork:
    """Map ``chain`` onto LIF cores at ``update_hz`` (dt = 1 / update_hz) under ``scheme``;
    :class:`NirError` naming the node for what the hardware cannot hold. ``weight_scale``:
    ``"pow2"`` (the weights' scale a power of two; weights below 1/2 scale the state up by a power of
    two, exactly) or ``"max"`` (each layer's state scaled so
    map exactly; the report gives the scale)."""
    if weight_scale not in ("pow2", "max"):
        raise NirError(f"weight_scale must be 'pow2' or 'max', got {weight_scale!r}")
    dt = 1.0 / float(update_hz)
    opts = {"weight_bits": int(weight_bits), "weight_frac_bits": weight_frac_bits,
            "v_frac_bits": int(v_frac_bits), "operand_width": int(operand_width),
            "max_decay_error": float(max_decay_error), "rounding": rounding,
            "weight_scale": weight_scale}
    layers = chain.layers
    cores, currents, report = [], [], []
    n_src = chain.n_inputs
    for li, layer in enumerate(layers):
        last = li == len(layers) - 1
        if layer.kind not in LEAKY:
            raise NirError(f"node {layer.name!r} ({layer.kind}): no leak (its decay is 1); the "
                           f"LIF core's decay must lie in (0, 1) (golden runs it)")
        if layer.kind not in SPIKING and not last:
            raise NirError(f"node {layer.name!r} ({layer.kind}): a non-spiking layer feeds "
                           f"another; LIF cores pass spikes, not values")
        try:
            c = step_constants(layer, dt, scheme)
        except ValueError as exc:
            raise NirError(str(exc)) from None
        try:
            kw, bias, If, rep = _layer_core(li, layer, c, chain, n_src, update_hz, opts,
                                            layer.kind not in SPIKING)
            cfg = LifConfig(**kw)
        except FixedPointError as exc:     # ConfigError, and a constant no format holds
            raise NirError(f"node {layer.name!r} ({layer.kind}): {exc}") from None
        rep["decay"] = [{"alpha": 1 - k, "alpha_quantized": 1 - c_.quantized,
                         "abs_error": abs(c_.quantized - k)}
                        for k, c_ in zip(cfg.k_exact, cfg.K)]
        if cfg.syn_alpha is not None:
            t = cfg.traces[0]
            rep["synapse"] = {"alpha": cfg.syn_alpha, "alpha_quantized": 1 - t.K.quantized,
                              "abs_error": abs(t.K.quantized - t.k_exact), "trace": str(t.T)}
        rep["thresholds"] = [{"u_th": th.value, "quantized": th.quantized,
                              "abs_error": abs(th.abs_error)} for th in cfg.TH]
        rep["state"] = {"format": str(cfg.V), "proven_range": [cfg.v_lo_proven, cfg.v_hi_proven],
                        "input_range": [cfg.d_lo, cfg.d_hi]}
        rep["grid"] = {"alpha_m": sorted({float(a) for a in c.alpha_m}),
                       "g": sorted({float(x) for x in c.g_m * (c.g_s if c.g_s is not None
                                                                else 1.0)})[:4]}
        if c.delay_steps is not None:
            rep["delay_ticks"] = sorted({int(d) for d in c.delay_steps})
        cores.append(cfg)
        currents.append(np.asarray(If.to_raw(bias), dtype=np.int64))
        report.append(rep)
        n_src = cfg.n_neurons
    try:
        net = NirNetworkConfig(cores, [lay.n_out for lay in layers],
                               readout=layers[-1].kind not in SPIKING)
    except ConfigError as exc:
        raise NirError(f"the network: {exc}") from None
    return MappedNetwork(chain, net, currents, dt, scheme, report)
