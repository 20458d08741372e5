"""Reading a NIR graph and turning it into a chain of layers, or refusing it in one line.

:func:`read_graph` opens a NIR file (HDF5 as written by ``nir.write``) and refuses what is not
one: a missing file, a file that is not HDF5, a truncated or damaged HDF5, an HDF5 without a NIR
graph, a node type NIR does not define (named). :func:`layers_of` walks the graph from its
``Input`` to its ``Output`` and groups the nodes into layers
(:class:`~cuneate.golden.nir.NirLayer`): ``[Delay] [Scale] [Affine | Linear]* [Scale] neuron``,
with ``Threshold`` allowed only directly after ``Input`` (the host thresholds the input signal
into spikes). What a chain of layers cannot express is refused naming the node and the reason:
convolutions, pooling and flattening (no dense weight memory form), nested graphs and cycles
(recurrence: the LIF core has no recurrent weights), branches and merges, multi-dimensional
shapes, a Delay between an Affine and its neuron (the core delays input spikes, not currents),
a Threshold anywhere but after the Input, parameters that are not finite.

Every refusal is a :class:`NirError` (a ``ValueError``) whose text names the node.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...golden.nir import NEURON_KINDS, NirLayer

__all__ = ["NirError", "read_graph", "layers_of", "GraphChain", "NODE_NOTES"]

#: node types refused by the mapping, and why (the rest of NIR's types are mapped)
NODE_NOTES = {
    "Conv1d": "convolutions are not mapped: the LIF core has a dense weight memory (unroll the "
              "convolution into an Affine)",
    "Conv2d": "convolutions are not mapped: the LIF core has a dense weight memory (unroll the "
              "convolution into an Affine)",
    "SumPool2d": "pooling is not mapped: the chain has no spatial dimensions",
    "AvgPool2d": "pooling is not mapped: the chain has no spatial dimensions",
    "Flatten": "multi-dimensional signals are not mapped: the chain is one-dimensional",
    "NIRGraph": "nested graphs (recurrent layers) are not mapped: the LIF core has no recurrent "
                "weights",
}


class NirError(ValueError):
    """A NIR file or graph cuneate cannot read or map (the message names the node)."""


def _node_types(h5node, prefix="") -> list[tuple[str, str]]:
    out = []
    if "nodes" in h5node:
        for name, sub in h5node["nodes"].items():
            t = sub["type"][()] if "type" in sub else b"?"
            t = t.decode("utf8", "replace") if isinstance(t, bytes) else str(t)
            out.append((prefix + name, t))
            if t == "NIRGraph":
                out += _node_types(sub, prefix + name + ".")
    return out


def read_graph(path):
    """The :class:`nir.NIRGraph` in ``path``, or a :class:`NirError` saying why not."""
    import h5py
    import nir
    p = Path(path)
    if not p.is_file():
        raise NirError(f"{path}: no such file")
    if not h5py.is_hdf5(p):
        raise NirError(f"{path}: not a NIR file (not HDF5)")
    try:
        with h5py.File(p, "r") as f:
            if "node" not in f:
                raise NirError(f"{path}: an HDF5 file without a NIR graph (no 'node' group)")
            kinds = _node_types(f["node"])
    except OSError as exc:
        raise NirError(f"{path}: truncated or damaged HDF5 ({exc})") from None
    known = set(nir.ir.__all__)
    for name, t in kinds:
        if t not in known:
            raise NirError(f"node {name!r}: type {t!r} is not a NIR node type")
    try:
        return nir.read(p)
    except NirError:
        raise
    except (OSError, KeyError, ValueError, AssertionError, TypeError) as exc:
        raise NirError(f"{path}: not a readable NIR graph ({type(exc).__name__}: "
                       f"{str(exc)[:200]})") from None


def _arr(node_name, kind, key, v, n=None) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64)
    if a.ndim > 1 and not (n is not None and a.size == n):
        raise NirError(f"node {node_name!r} ({kind}): {key} has shape {a.shape}; only "
                       f"one-dimensional layers are mapped")
    if not np.all(np.isfinite(a)):
        raise NirError(f"node {node_name!r} ({kind}): {key} is not finite")
    return a.reshape(-1) if a.ndim else a


@dataclass
class GraphChain:
    """The graph as layers: ``layers``, the input size, the host threshold of the input (or
    None) and the node names along the chain."""

    layers: list
    n_inputs: int
    input_threshold: np.ndarray | None
    order: list


def _chain(graph) -> list[str]:
    nodes = graph.nodes
    ins = [k for k, v in nodes.items() if type(v).__name__ == "Input"]
    outs = [k for k, v in nodes.items() if type(v).__name__ == "Output"]
    if len(ins) != 1 or len(outs) != 1:
        raise NirError(f"the graph has {len(ins)} Input and {len(outs)} Output nodes; a chain "
                       f"has one of each")
    succ: dict[str, list[str]] = {k: [] for k in nodes}
    pred: dict[str, list[str]] = {k: [] for k in nodes}
    for a, b in graph.edges:
        if a not in nodes or b not in nodes:
            raise NirError(f"edge ({a!r}, {b!r}) names a node the graph does not have")
        succ[a].append(b)
        pred[b].append(a)
    order, seen, cur = [], set(), ins[0]
    while True:
        if cur in seen:
            raise NirError(f"node {cur!r} ({type(nodes[cur]).__name__}): recurrence (the graph "
                           f"has a cycle through it); the LIF core has no recurrent weights")
        seen.add(cur)
        order.append(cur)
        if len(pred[cur]) > 1:
            raise NirError(f"node {cur!r} ({type(nodes[cur]).__name__}): {len(pred[cur])} "
                           f"inputs merge into it; only chains are mapped")
        if cur == outs[0]:
            break
        if len(succ[cur]) != 1:
            what = "no successor" if not succ[cur] else f"{len(succ[cur])} successors (a branch)"
            raise NirError(f"node {cur!r} ({type(nodes[cur]).__name__}): {what}; only chains "
                           f"from Input to Output are mapped")
        cur = succ[cur][0]
    rest = [k for k in nodes if k not in seen]
    if rest:
        raise NirError(f"node {rest[0]!r} ({type(nodes[rest[0]]).__name__}): not on the path "
                       f"from Input to Output")
    return order


def layers_of(graph) -> GraphChain:
    """The chain of layers of ``graph`` (see the module docstring), or a :class:`NirError`."""
    order = _chain(graph)
    nodes = graph.nodes
    for k in order:
        kind = type(nodes[k]).__name__
        if kind in NODE_NOTES:
            raise NirError(f"node {k!r} ({kind}): {NODE_NOTES[kind]}")
    n_in = int(np.prod(np.asarray(nodes[order[0]].output_type["output"]).reshape(-1)))
    width = n_in
    thr = None
    layers: list[NirLayer] = []
    W, b, delay, pre_scale, names = None, None, None, None, {}

    def fresh():
        return np.eye(width), np.zeros(width)

    for i, k in enumerate(order[1:-1], start=1):
        node, kind = nodes[k], type(nodes[k]).__name__
        if kind == "Threshold":
            if i != 1:
                raise NirError(f"node {k!r} (Threshold): a Heaviside without reset is mapped only "
                               f"directly after the Input (the host thresholds the input); "
                               f"after a neuron use LIF")
            thr = _arr(k, kind, "threshold", node.threshold)
            thr = np.broadcast_to(thr, (width,)).copy()
        elif kind == "Delay":
            if W is not None:
                raise NirError(f"node {k!r} (Delay): between an Affine and its neuron it would "
                               f"delay currents; the LIF core delays input spikes (move it "
                               f"before the Affine)")
            d = np.broadcast_to(_arr(k, kind, "delay", node.delay), (width,))
            if np.any(d < 0):
                raise NirError(f"node {k!r} (Delay): a negative delay")
            delay = d.copy() if delay is None else delay + d
            names["delay"] = k
        elif kind == "Scale":
            s = np.broadcast_to(_arr(k, kind, "scale", node.scale), (width,))
            if W is None:
                pre_scale = s.copy() if pre_scale is None else pre_scale * s
            else:
                W, b = W * s[:, None], b * s
            names.setdefault("scale", k)
        elif kind in ("Affine", "Linear"):
            w = np.asarray(node.weight, dtype=np.float64)
            if w.ndim != 2:
                raise NirError(f"node {k!r} ({kind}): weight of shape {w.shape}; only 2-D "
                               f"weights are mapped")
            if not np.all(np.isfinite(w)):
                raise NirError(f"node {k!r} ({kind}): weight is not finite")
            if w.shape[1] != width:
                raise NirError(f"node {k!r} ({kind}): takes {w.shape[1]} inputs, its "
                               f"predecessor gives {width}")
            bias = (_arr(k, kind, "bias", node.bias) if kind == "Affine"
                    else np.zeros(w.shape[0]))
            if W is None:
                W, b = fresh()
                if pre_scale is not None:
                    W = W * pre_scale[None, :]
            W, b = w @ W, w @ b + np.broadcast_to(bias, (w.shape[0],))
            width = w.shape[0]
            names.setdefault("affine", k)
        elif kind in NEURON_KINDS:
            if W is None:
                W, b = fresh()
                if pre_scale is not None:
                    W = W * pre_scale[None, :]
            layers.append(_neuron_layer(k, kind, node, W, b, delay, names | {"neuron": k}))
            W, b, delay, pre_scale, names = None, None, None, None, {}
        else:
            raise NirError(f"node {k!r} ({kind}): this node type is not mapped")
    if W is not None or delay is not None or pre_scale is not None:
        last = order[-2]
        raise NirError(f"node {last!r} ({type(nodes[last]).__name__}): the chain ends without "
                       f"a neuron; the Output must follow a neuron node")
    if not layers:
        raise NirError("the graph has no neuron node")
    return GraphChain(layers, n_in, thr, order)


def _neuron_layer(k, kind, node, W, b, delay, names) -> NirLayer:
    n = W.shape[0]

    def p(key, default=None):
        v = getattr(node, key, default)
        if v is None:
            return None
        a = _arr(k, kind, key, v, n)
        if a.size not in (1, n):
            raise NirError(f"node {k!r} ({kind}): {key} has {a.size} values for {n} neurons")
        return np.broadcast_to(a, (n,)).astype(np.float64)

    tau = p("tau_mem") if kind in ("CubaLIF", "CubaLI") else p("tau")
    return NirLayer(kind=kind, weight=W, bias=b, tau=tau, r=p("r"), v_leak=p("v_leak"),
                    v_threshold=p("v_threshold"), v_reset=p("v_reset"), tau_syn=p("tau_syn"),
                    w_in=p("w_in"), delay_s=delay, nodes=names)
