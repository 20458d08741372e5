"""cuneate's own networks written as NIR graphs, and read back.

**Skin** (the taxel-skin scenes' LIF layer): ``Input`` (the taxel forces, N) -> ``Affine``
(``W = k2 I``, ``b = k1``: force to current in mV) -> ``LIF`` (``tau`` = tau_m in s, ``r = 1``,
``v_leak`` = rest, ``v_threshold``, ``v_reset``) -> ``Output``. NIR's LIF has no refractory
period; the core's is carried in the LIF node's metadata as ``cuneate_t_ref_s`` (a documented
extension: other tools skip metadata and simulate without it). NIR's threshold is strict
(``v > v_th``), the core's continuous form spikes at ``v >= v_th``; on the core's grid the two
differ only when ``v`` lands exactly on the threshold.

**Ridge** (the ridge scenes' coincidence detector, the second layer): ``Input`` (the S afferent
spike trains) -> ``Linear`` (fan-out, one-hot: each of the T x S synapses takes its source) ->
``Delay`` (the conduction delay of each synapse, s) -> ``Linear`` (T x (T S): ``J w`` of each
synapse into its target, mV/ms) -> two ``LI`` (``tau`` = the PSP decay and rise time constants,
``r = tau``, so a spike of weight ``J w`` starts each trace at ``J w``) -> ``Scale`` (+1 decay,
-1 rise) -> ``Output``: the bi-exponential PSP current ``J w (exp(-t/tau_d) - exp(-t/tau_r))``
of every cuneate neuron, which NIR expresses. The cuneate neurons themselves are Izhikevich
neurons, which NIR cannot express: they travel in the Output node's metadata
(``cuneate_extension = "izhikevich"``, ``cuneate_izhikevich`` = their parameter sets as JSON,
``cuneate_update_hz``): a documented extension that other tools skip, so they compute the PSP
currents (correctly) and stop there.

**Learning** (the learning scenes' layer, :mod:`cuneate.hdl.plasticity`, with its learned
weights): ``Input`` (the S afferent spike trains) -> ``Linear`` (``M x S``: each CN's weight of
each afferent, mV/ms, 0 where it has no synapse) -> ``LI`` (``tau`` = ``tau_syn``, ``r = tau``:
a spike of weight ``w`` starts the excitation at ``w``) -> ``Output``, and beside it the lumped
interneuron: ``Input`` -> ``Linear`` (``1 x S`` of ones) -> ``LI`` (``tau_syn``) -> ``Scale``
(``-g``, to every CN) -> ``Output``: the CNs' net drive ``E - g H``. The Izhikevich CNs and the
AIDP rule travel in the Output node's metadata (``cuneate_extension = "izhikevich+aidp"``,
``cuneate_izhikevich``, ``cuneate_aidp`` and ``cuneate_layer`` as JSON, ``cuneate_sources``: each
synapse's afferent, so a learned weight of 0 stays a synapse).

The first layer's **Izhikevich afferents** are refused (:func:`refuse_afferents`): NIR has no
Izhikevich node and no other node approximates one.

:func:`skin_graph`/:func:`skin_from_graph` and :func:`ridge_graph`/:func:`ridge_from_graph`
convert both ways; ``from(to(x)) == x`` for the parameters (the round trip the tests check).
"""

from __future__ import annotations

import json

import numpy as np

from .graph import NirError

__all__ = ["skin_graph", "skin_from_graph", "ridge_graph", "ridge_from_graph",
           "learning_graph", "learning_from_graph", "refuse_afferents", "scene_graph"]

EXT = "cuneate_extension"


def refuse_afferents(name: str = "afferent") -> None:
    """Always raises: the Izhikevich afferents have no NIR form."""
    raise NirError(f"population {name!r} (izhikevich): NIR has no Izhikevich neuron node (its "
                   f"neurons are LIF, IF, LI, CubaLIF and integrators), so the afferents cannot "
                   f"be exported; export the second layer, whose input are the afferent spikes")


def skin_graph(n_taxels: int, k1: float, k2: float, lif: dict):
    """The skin's LIF layer as a NIR graph (see the module docstring). ``lif``: the LIF set
    (``tau_m_ms``, ``v_th``, ``v_reset``, ``v_rest``, ``t_ref_ms``)."""
    import nir
    n = int(n_taxels)

    def full(x):
        return np.full(n, float(x))
    return nir.NIRGraph.from_list(
        nir.Input(input_type=np.array([n])),
        nir.Affine(weight=np.eye(n) * float(k2), bias=full(k1)),
        nir.LIF(tau=full(lif["tau_m_ms"] / 1000.0), r=full(1.0), v_leak=full(lif["v_rest"]),
                v_threshold=full(lif["v_th"]), v_reset=full(lif["v_reset"]),
                metadata={"cuneate_t_ref_s": float(lif["t_ref_ms"]) / 1000.0,
                          EXT: "refractory period (cuneate_t_ref_s)"}),
        nir.Output(output_type=np.array([n])))


def _one(node, key, what):
    a = np.unique(np.asarray(getattr(node, key), dtype=np.float64))
    if a.size != 1:
        raise NirError(f"{what}: {key} differs between neurons; the skin has one LIF set")
    return float(a[0])


def _by_type(graph, kind):
    return [k for k, v in graph.nodes.items() if type(v).__name__ == kind]


def skin_from_graph(graph) -> dict:
    """The skin parameters of a graph written by :func:`skin_graph`."""
    (ak,), (lk,) = _by_type(graph, "Affine"), _by_type(graph, "LIF")
    aff, lif = graph.nodes[ak], graph.nodes[lk]
    W = np.asarray(aff.weight, dtype=np.float64)
    k2 = float(W[0, 0])
    if not np.allclose(W, np.eye(W.shape[0]) * k2, rtol=0, atol=0):
        raise NirError(f"node {ak!r} (Affine): not a skin's diagonal force gain")
    meta = dict(lif.metadata or {})
    t_ref = float(np.asarray(meta.get("cuneate_t_ref_s", 0.0))) * 1000.0
    return {"n_taxels": int(W.shape[0]), "k1": _one(aff, "bias", ak), "k2": k2,
            "lif": {"tau_m_ms": _one(lif, "tau", lk) * 1000.0, "v_th": _one(lif, "v_threshold", lk),
                    "v_reset": _one(lif, "v_reset", lk), "v_rest": _one(lif, "v_leak", lk),
                    "t_ref_ms": t_ref}}


def ridge_graph(cfg) -> "object":
    """The coincidence detector ``cfg`` (:class:`~cuneate.hdl.coincidence.CoincidenceConfig`)
    as a NIR graph (see the module docstring)."""
    import nir
    T, S = cfg.n_targets, cfg.n_sources
    fan = np.zeros((T * S, S))
    fan[np.arange(T * S), np.tile(np.arange(S), T)] = 1.0
    syn = np.zeros((T, T * S))
    for t in range(T):
        syn[t, t * S:(t + 1) * S] = cfg.weights_real[t]
    delays = cfg.delays.reshape(-1).astype(np.float64) / cfg.update_hz
    taus = {"decay": cfg.tau_decay_ms / 1000.0, "rise": cfg.tau_rise_ms / 1000.0}
    ps = [p if isinstance(p, str) else dict(p) for p in cfg.param_sets]
    nodes = {"input": nir.Input(input_type=np.array([S])),
             "fanout": nir.Linear(weight=fan), "delay": nir.Delay(delay=delays),
             "synapses": nir.Linear(weight=syn),
             "output": nir.Output(output_type=np.array([T]), metadata={
                 EXT: "izhikevich", "cuneate_izhikevich": json.dumps(ps),
                 "cuneate_target_sets": np.asarray(cfg.target_sets_, dtype=np.int64),
                 "cuneate_update_hz": float(cfg.update_hz)})}
    edges = [("input", "fanout"), ("fanout", "delay"), ("delay", "synapses")]
    for name, sign in (("decay", 1.0), ("rise", -1.0)):
        tau = np.full(T, taus[name])
        nodes[f"psp_{name}"] = nir.LI(tau=tau, r=tau.copy(), v_leak=np.zeros(T))
        nodes[f"sign_{name}"] = nir.Scale(scale=np.full(T, sign))
        edges += [("synapses", f"psp_{name}"), (f"psp_{name}", f"sign_{name}"),
                  (f"sign_{name}", "output")]
    return nir.NIRGraph(nodes=nodes, edges=edges)


def _text(x) -> str:
    """A metadata string as written or as read back from a NIR file (bytes)."""
    return x.decode() if isinstance(x, bytes) else str(x)


def _extension_meta(graph, kind: str, needed: tuple, ext: str, carries: str) -> dict:
    """The Output node's metadata of a cuneate ``kind`` graph, refused (one line naming it)
    without one of the ``needed`` nodes or without the ``ext`` extension."""
    for k in needed:
        if k not in graph.nodes:
            raise NirError(f"not a cuneate {kind} graph: no node {k!r}")
    meta = dict(graph.nodes["output"].metadata or {})
    if EXT not in meta or _text(meta[EXT]) != ext:
        raise NirError(f"node 'output' (Output): no cuneate {carries}")
    return meta


def ridge_from_graph(graph) -> dict:
    """The coincidence detector's keywords (``n_sources``, ``n_targets``, ``delays_ticks``,
    ``weights``, ``tau_rise_ms``, ``tau_decay_ms``, ``param_sets``, ``target_sets``,
    ``update_hz``) of a graph written by :func:`ridge_graph`."""
    nodes = graph.nodes
    meta = _extension_meta(graph, "ridge", ("fanout", "delay", "synapses", "psp_decay",
                                            "psp_rise", "output"), "izhikevich",
                           "Izhikevich extension in its metadata (the cuneate neurons' "
                           "parameters)")
    hz = float(np.asarray(meta["cuneate_update_hz"]))
    fan = np.asarray(nodes["fanout"].weight)
    syn = np.asarray(nodes["synapses"].weight)
    T, TS = syn.shape
    S = fan.shape[1]
    if TS != T * S or not np.array_equal(fan.argmax(axis=1), np.tile(np.arange(S), T)):
        raise NirError("node 'fanout' (Linear): not the one-hot fan-out of T x S synapses")
    ticks = np.asarray(nodes["delay"].delay, dtype=np.float64) * hz
    if not np.allclose(ticks, np.round(ticks), atol=1e-6):
        raise NirError(f"node 'delay' (Delay): not whole ticks at {hz:g} Hz")
    w = np.array([syn[t, t * S:(t + 1) * S] for t in range(T)])
    ps = meta["cuneate_izhikevich"]
    ps = json.loads(_text(ps))
    return {"n_sources": S, "n_targets": T,
            "delays_ticks": np.round(ticks).astype(np.int64).reshape(T, S).tolist(),
            "weights": w.tolist(),
            "tau_decay_ms": float(np.unique(nodes["psp_decay"].tau)[0]) * 1000.0,
            "tau_rise_ms": float(np.unique(nodes["psp_rise"].tau)[0]) * 1000.0,
            "param_sets": ps,
            "target_sets": np.asarray(meta["cuneate_target_sets"]).astype(int).tolist(),
            "update_hz": hz}


def learning_graph(cfg, weights=None):
    """The learning layer ``cfg`` (:class:`~cuneate.hdl.plasticity.PlasticityConfig`) with
    ``weights`` (``(M, K)`` mV/ms; default its initial ones) as a NIR graph (see the module
    docstring)."""
    import nir
    M, K, S = cfg.n_targets, cfg.n_synapses, cfg.n_sources
    w = cfg.weights_real if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != (M, K):
        raise NirError(f"learned weights must be ({M}, {K}), got {w.shape}")
    full = np.zeros((M, S))
    for j in range(M):
        full[j, cfg.src[j]] = w[j]
    tau = cfg.tau_syn_ms / 1000.0
    kw = cfg.to_kwargs()
    layer = {k: kw[k] for k in ("tau_syn_ms", "g_inh", "current_limit", "update_hz",
                                "clock_hz", "weight_bits", "trace_frac_bits",
                                "drive_int_bits", "drive_frac_bits", "sigmoid_bits",
                                "operand_width", "rounding", "target_sets")}
    nodes = {"input": nir.Input(input_type=np.array([S])),
             "synapses": nir.Linear(weight=full),
             "excitation": nir.LI(tau=np.full(M, tau), r=np.full(M, tau), v_leak=np.zeros(M)),
             "interneuron_in": nir.Linear(weight=np.ones((1, S))),
             "interneuron": nir.LI(tau=np.full(1, tau), r=np.full(1, tau),
                                   v_leak=np.zeros(1)),
             "inhibition": nir.Linear(weight=np.full((M, 1), -float(cfg.g_inh))),
             "output": nir.Output(output_type=np.array([M]), metadata={
                 EXT: "izhikevich+aidp", "cuneate_izhikevich": json.dumps(kw["param_sets"]),
                 "cuneate_aidp": json.dumps(kw["rule"]), "cuneate_layer": json.dumps(layer),
                 "cuneate_sources": np.asarray(cfg.src, dtype=np.int64)})}
    edges = [("input", "synapses"), ("synapses", "excitation"), ("excitation", "output"),
             ("input", "interneuron_in"), ("interneuron_in", "interneuron"),
             ("interneuron", "inhibition"), ("inhibition", "output")]
    return nir.NIRGraph(nodes=nodes, edges=edges)


def learning_from_graph(graph) -> dict:
    """The learning layer's keywords (:meth:`~cuneate.hdl.plasticity.PlasticityConfig
    .from_kwargs`: sources, weights, rule, the layer's constants) of a graph written by
    :func:`learning_graph`; the weights are the graph's (learned) ones."""
    nodes = graph.nodes
    meta = _extension_meta(graph, "learning", ("synapses", "excitation", "interneuron",
                                               "inhibition", "output"), "izhikevich+aidp",
                           "Izhikevich+AIDP extension in its metadata (the CNs' parameters "
                           "and the learning rule)")

    def js(key):
        return json.loads(_text(meta[key]))
    src = np.asarray(meta["cuneate_sources"]).astype(np.int64)
    full = np.asarray(nodes["synapses"].weight, dtype=np.float64)
    M, S = full.shape
    if src.ndim != 2 or src.shape[0] != M or src.min() < 0 or src.max() >= S:
        raise NirError("node 'output': cuneate_sources does not fit node 'synapses' "
                       f"({M} x {S})")
    mask = np.zeros_like(full, dtype=bool)
    for j in range(M):
        mask[j, src[j]] = True
    if np.any(full[~mask] != 0):
        raise NirError("node 'synapses' (Linear): a weight where no synapse is "
                       "(cuneate_sources)")
    layer = js("cuneate_layer")
    return {"n_sources": S, "sources": src.tolist(),
            "weights": [full[j, src[j]].tolist() for j in range(M)], "rule": js("cuneate_aidp"),
            "param_sets": js("cuneate_izhikevich")} | layer


def scene_graph(scene):
    """The NIR graph of a scene's second layer: a skin scene's LIF layer, a ridge scene's
    coincidence detector, a learning scene's layer with its initial weights (its report writes
    the learned ones, ``learned_<engine>.nir``); afferent scenes are refused
    (:func:`refuse_afferents`)."""
    kind = scene.kind
    if kind == "skin":
        from ..scenes.skin import LIF_PRESETS
        from ...golden import lif as glif
        p = scene.populations[0]
        fe = scene["frontend"]
        rows, cols = scene["sensor"]["grid"]
        lif = {"tau_m_ms": glif.TAU_M_EXC_MS, "v_th": glif.V_TH, "v_reset": glif.V_RESET,
               "v_rest": glif.V_REST, "t_ref_ms": glif.T_REF_EXC_MS} | LIF_PRESETS[p["preset"]]
        return skin_graph(rows * cols, fe["force_offset_mV"], fe["force_gain_mV_per_N"], lif)
    if kind == "learning":               # the layer before learning (a run writes the learnt)
        from ..plasticity.protocol import layer_config
        return learning_graph(layer_config(scene))
    if kind == "ridge":
        from ..coincidence.experiments import detector_config
        from ..scenes.ridge import spec_of
        return ridge_graph(detector_config(spec_of(scene)))
    names = [p["name"] for p in scene.populations if p["model"] == "izhikevich"]
    refuse_afferents(names[0] if names else "afferent")
