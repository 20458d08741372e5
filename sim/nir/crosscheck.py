"""The cross-check against an independent NIR consumer: snnTorch, in its own environment.

:func:`peer_python` makes (once) and returns snnTorch's environment
(``scripts/crosscheck_env.sh``: a CPU build of PyTorch, snnTorch, nirtorch, nir;
``build/crosscheck-venv``), the way the Brian2 peer of the speed benchmark has its own.
:func:`run_peer` runs a graph there (:mod:`cuneate.sim.nir.peer_snntorch`).
:func:`compare` runs the same graph and input on cuneate's engines and on snnTorch and compares
the spike counts per output neuron.

What differs, and why (the tolerances of :data:`TOLERANCE` are measured against these):

* **Latency.** snnTorch hands a layer's spike to the next layer within the same step; on
  cuneate's grid a spike of update ``k`` is emitted at ``(k + 1) dt`` and enters the next layer
  in update ``k + 1`` (as on the chained cores). In a feed-forward chain this is a pure shift of
  ``L - 1`` steps for ``L`` layers: cuneate's run gets ``L - 1`` extra steps of zero input and
  its counts are taken over the steps shifted by ``L - 1``.
* **Delay.** snnTorch's NIR import has no Delay node: the graph's input Delay is applied to the
  input trains before snnTorch, which gets the graph without it.
* **Discretization.** snnTorch discretizes NIR's neurons by forward Euler with the synaptic
  current first (``alpha = 1 - dt/tau``); cuneate's ``euler`` scheme is the same recursion, so
  the remaining differences are float32 (snnTorch) against float64 (golden) at threshold ties;
  cuneate's default ``exact`` scheme uses ``alpha = exp(-dt/tau)`` and impulse inputs, so its
  counts differ by the discretization (``O(dt/tau)`` per step in the decays and gains).
* **Reset.** snnTorch imports NIR's LIF with ``reset_mechanism="zero"`` and no reset delay: the
  same reset to ``v_reset = 0`` within the step as cuneate's.
* **Quantization** (``fixed`` and the RTL engines): 8-bit weights, 16 fraction bits of state.
"""

from __future__ import annotations

import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ...golden.nir import delay_inputs
from .engines import run_network
from .graph import layers_of
from .mapping import map_graph

__all__ = ["peer_python", "run_peer", "crosscheck_graph", "compare", "TOLERANCE"]

#: per-neuron |count difference| allowed against snnTorch: the measured worst cases with margin
#: (docs/nir.md gives the measurements)
TOLERANCE = {"golden-euler": {"abs": 1, "rel": 0.0},
             "fixed-euler": {"abs": 3, "rel": 0.15},
             "golden-exact": {"abs": 3, "rel": 0.25},
             "fixed-exact": {"abs": 3, "rel": 0.3}}

ROOT = Path(__file__).resolve().parents[2]


def peer_python(root: Path | None = None) -> tuple[str | None, str]:
    """snnTorch's python (made on first use), or None and the reason it is unavailable."""
    root = Path(root or ROOT)
    script = root / "scripts" / "crosscheck_env.sh"
    if not script.exists():
        return None, f"{script} not found (run from a source checkout)"
    r = subprocess.run(["bash", str(script)], capture_output=True, text=True, cwd=root)
    if r.returncode:
        return None, f"crosscheck_env.sh failed: {r.stderr.strip()[-300:]}"
    py = r.stdout.strip().splitlines()[-1]
    return str(root / py) if not Path(py).is_absolute() else py, ""


def run_peer(py: str, graph, x: np.ndarray) -> np.ndarray:
    """snnTorch's output spikes (steps, n_out) for ``graph`` (a NIR graph or file) on ``x``."""
    import nir
    peer = Path(__file__).with_name("peer_snntorch.py")
    with tempfile.TemporaryDirectory(prefix="cuneate-snntorch-") as tmp:
        t = Path(tmp)
        gp = t / "graph.nir"
        if isinstance(graph, (str, Path)):
            gp = Path(graph)
        else:
            nir.write(gp, graph)
        np.save(t / "x.npy", np.asarray(x, dtype=np.float32))
        r = subprocess.run([py, str(peer), "run", str(gp), str(t / "x.npy"), str(t / "y.npy")],
                           capture_output=True, text=True, timeout=1800)
        if r.returncode:
            raise RuntimeError(f"snnTorch failed: {r.stderr.strip()[-400:]}")
        return np.load(t / "y.npy")


def crosscheck_graph(seed: int = 3, dt: float = 1e-4, n_in: int = 8, n_hidden: int = 16,
                     n_out: int = 4):
    """Input -> Delay -> Affine -> CubaLIF -> Affine -> LIF -> Output, in snnTorch's NIR
    conventions (``r = tau/dt``, ``w_in = tau_syn/dt``) so snnTorch imports it unscaled."""
    import nir
    rng = np.random.default_rng(seed)
    ts, tm = dt / (1 - 0.8), dt / (1 - 0.9)

    def full(n, v):
        return np.full(n, float(v))
    return nir.NIRGraph.from_list(
        nir.Input(input_type=np.array([n_in])),
        nir.Delay(delay=rng.integers(0, 4, n_in) * dt),
        nir.Affine(weight=rng.normal(0.05, 0.2, (n_hidden, n_in)), bias=full(n_hidden, 0.0)),
        nir.CubaLIF(tau_syn=full(n_hidden, ts), tau_mem=full(n_hidden, tm),
                    r=full(n_hidden, tm / dt), v_leak=full(n_hidden, 0),
                    v_threshold=full(n_hidden, 1), v_reset=full(n_hidden, 0),
                    w_in=full(n_hidden, ts / dt)),
        nir.Affine(weight=rng.normal(0.05, 0.3, (n_out, n_hidden)), bias=full(n_out, 0.0)),
        nir.LIF(tau=full(n_out, tm), r=full(n_out, tm / dt), v_leak=full(n_out, 0),
                v_threshold=full(n_out, 1), v_reset=full(n_out, 0)),
        nir.Output(output_type=np.array([n_out])))


def _for_peer(graph, x: np.ndarray, dt: float):
    """snnTorch's graph (the input Delay removed) and its input (the Delay applied)."""
    import nir

    nodes = dict(graph.nodes)
    edges = list(graph.edges)
    for k, v in list(nodes.items()):
        if type(v).__name__ == "Delay":
            (pre,) = [a for a, b in edges if b == k]
            if type(nodes[pre]).__name__ != "Input":
                raise ValueError(f"node {k!r}: snnTorch has no Delay; only an input Delay is "
                                 f"applied to its input")
            (post,) = [b for a, b in edges if a == k]
            x = delay_inputs(x, np.round(np.asarray(v.delay) / dt).astype(np.int64))
            edges = [e for e in edges if k not in e] + [(pre, post)]
            del nodes[k]
    return nir.NIRGraph(nodes=nodes, edges=edges), x


def compare(py: str, graph, x: np.ndarray, engines=("golden",), schemes=("euler", "exact"),
            update_hz: float = 1e4) -> dict:
    """Spike counts per output neuron on cuneate's ``engines`` (each ``scheme``) against
    snnTorch's. Returns per pair the counts, max and mean |difference|, and whether it is
    within :data:`TOLERANCE` (when a tolerance is stated for the pair)."""
    dt = 1.0 / update_hz
    chain = layers_of(graph)
    shift = len(chain.layers) - 1
    g_peer, x_peer = _for_peer(graph, np.asarray(x, dtype=np.float64), dt)
    peer = run_peer(py, g_peer, x_peer)
    ref = peer.sum(axis=0).astype(np.int64)
    xs = np.vstack([x, np.zeros((shift, x.shape[1]))])
    out = {"snntorch_counts": ref.tolist(), "steps": int(x.shape[0]), "shift_steps": shift,
           "pairs": {}}
    for scheme in schemes:
        mapped = map_graph(chain, update_hz=update_hz, scheme=scheme)
        for e in engines:
            run = run_network(e, mapped, xs)
            c = run.spikes[shift:].sum(axis=0).astype(np.int64)
            d = np.abs(c - ref)
            key = f"{e}-{scheme}"
            tol = TOLERANCE.get(key)
            ok = None if tol is None else bool(np.all(d <= tol["abs"] + tol["rel"] * ref))
            out["pairs"][key] = {"counts": c.tolist(), "max_abs_diff": int(d.max()),
                                 "mean_abs_diff": float(d.mean()),
                                 "max_rel_diff": float((d / np.maximum(ref, 1)).max()),
                                 "identical": bool(np.all(d == 0)), "within_tolerance": ok,
                                 "tolerance": tol}
    return out


def main() -> int:                     # pragma: no cover - the cross-check lane's report
    py, why = peer_python()
    if py is None:
        print(json.dumps({"error": why}))
        return 1
    rng = np.random.default_rng(0)
    x = (rng.random((400, 8)) < 0.15).astype(float)
    print(json.dumps(compare(py, crosscheck_graph(), x, engines=("golden", "fixed"))))
    return 0
