"""An afferent scene's cuneate layer: coincidence-detecting cuneate neurons on the afferents of
every trial, the on-chip network's second population.

An afferent scene may name one population with ``model = "cuneate"`` (driven by spikes): its
``size`` cuneate neurons a trial have receptive fields that tile the population's ``gratings``
(default: every grating) in consecutive groups (:func:`numpy.array_split`), and listen to the
afferents of its ``inputs`` (Izhikevich populations of the scene). One ``[[projection]]`` from
each input to it gives the PSP amplitude ``weight`` (``J w``, mV/ms, bi-exponential PSPs) and
the conduction delays ``delays_ms``: one for every cuneate neuron, or one per cuneate neuron
(whole ticks). Cuneate neuron ``j`` of trial ``t`` listens to the afferents of trial ``t`` of
the input populations whose grating lies in its field, so each trial (a hand, on a board) has
its own layer.

The layer is the detector of the on-chip afferent -> cuneate network
(:class:`~cuneate.hdl.network.NetworkConfig`): every afferent of the scene's core is a source,
targets run trial-major, and a weight of 0 disconnects a pair (a target outside a source's
trial or field). Engines (those whose Izhikevich implementation runs the layer,
:func:`layer_engines`):

``golden``
    the float64 cuneate model (:func:`cuneate.golden.coincidence.simulate_cuneate`) on the
    golden engine's afferent spikes, trial by trial;
``fixed``
    the detector's twin (:class:`~cuneate.hdl.coincidence.CoincidenceTwin`) on the fixed
    engine's afferent spikes, each stamped as the network stamps it (the update of sweep ``k``
    at detector tick ``k + 1``): bit for bit :class:`~cuneate.hdl.network.NetworkTwin`;
``board``
    the network on chip behind the link (with the channel fan-out in front when the scene
    streams channels): both populations' spikes come back over the line.

The network of the engines runs every trial at once: its clock is raised to hold a tick's
work (the results depend on the tick rate alone); a board built for the scene holds
``hardware.board_trials`` of them (:mod:`cuneate.boards.scene`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...golden.izhikevich import spike_ticks, to_params
from ...hdl.coincidence import CoincidenceConfig
from ...hdl.coincidence.config import CYCLES_PER_TARGET_EXTRA
from ...hdl.lib.config import ConfigError
from ...hdl.network import NetworkConfig
from ...hdl.network.config import SWEEP_EXTRA
from ..coincidence.engines import run_coincidence
from ..engines.registry import (block_engines, estimate_seconds, implementation,
                                refuse_engines_outside)

__all__ = ["CuneateLayer", "layer_engines", "validate_layer", "scene_layer", "layer_network",
           "layer_config", "run_layer", "check_layer_engines", "layer_estimate"]

def layer_engines() -> tuple[str, ...]:
    """The engines that run an afferent scene's cuneate layer: on the host after the
    afferents (golden, fixed: :func:`run_layer`) or on chip (board)."""
    return tuple(e for e in block_engines("izhikevich")
                 if implementation("izhikevich", e).layer)


def validate_layer(V, sections: dict, pops: list, projs: list) -> None:
    """Check and complete an afferent scene's cuneate layer in place (its population and its
    projections); ``V.err`` raises the scene error."""
    cn = [(i, p) for i, p in enumerate(pops) if p["model"] == "cuneate"]
    if not cn:
        if projs:
            V.err("projection[0]", "projections drive a cuneate population (model = "
                                   "\"cuneate\"); the scene has none")
        return
    if len(cn) > 1:
        V.err(f"population[{cn[1][0]}].model", "an afferent scene has at most one cuneate "
                                               "population (its layer)")
    (ci, c), = cn
    key = f"population[{ci}]"
    if c["encoding"] not in (None, "spikes"):
        V.err(f"{key}.encoding", "a cuneate population is driven by spikes (encoding = "
                                 "\"spikes\")")
    c["encoding"], c["preset"] = "spikes", c["preset"] or "RS"
    try:
        to_params(c["preset"])
    except ValueError as exc:
        V.err(f"{key}.preset", str(exc))
    afferents = [p["name"] for p in pops if p["model"] == "izhikevich"]
    if not c["inputs"]:
        V.err(f"{key}.inputs", "name the afferent populations the cuneate layer listens to")
    for j, s in enumerate(c["inputs"]):
        if s not in afferents or c["inputs"].index(s) != j:
            V.err(f"{key}.inputs[{j}]", f"{s!r}: the inputs are distinct afferent (Izhikevich) "
                                        f"populations of the scene ({', '.join(afferents)})")
    channels = sections["sensor"]["channels"]
    g = c["gratings"] if c["gratings"] is not None else list(range(channels))
    for j, x in enumerate(g):
        if not 0 <= x < channels or g.index(x) != j:
            V.err(f"{key}.gratings[{j}]", f"grating {x}: the fields tile distinct gratings of "
                                          f"the sensor's {channels}")
    c["gratings"] = g
    if c["size"] is not None and not 1 <= c["size"] <= len(g):
        V.err(f"{key}.size", f"out of range: at most one cuneate neuron a grating of its "
                             f"fields ({len(g)}), got {c['size']}")
    dt = 1000.0 / sections["hardware"]["update_hz"]
    seen = {}
    for i, q in enumerate(projs):
        if q["target"] != c["name"] or q["source"] not in c["inputs"] or q["source"] in seen:
            V.err(f"projection[{i}]", f"one projection from each input of {c['name']!r} "
                                      f"({', '.join(c['inputs'])}) to it")
        if q["psp"] != "biexp":
            V.err(f"projection[{i}].psp", "the coincidence detector's PSP is \"biexp\"")
        if q["weight"] <= 0:
            V.err(f"projection[{i}].weight", "out of range: J w must be > 0 mV/ms")
        d = q["delays_ms"]
        if len(d) not in (1, c["size"]):
            V.err(f"projection[{i}].delays_ms", f"one delay for every cuneate neuron or one "
                                                f"per cuneate neuron ({c['size']}), got {len(d)}")
        for x in d:
            if abs(x / dt - round(x / dt)) > 1e-9:
                V.err(f"projection[{i}].delays_ms", f"{x:g} ms is not a whole number of ticks "
                                                    f"(dt = {dt:g} ms)")
        seen[q["source"]] = i
    missing = [s for s in c["inputs"] if s not in seen]
    if missing:
        V.err("projection", f"the cuneate layer needs a projection from {missing[0]!r} to "
                            f"{c['name']!r} (its weight and delays)")
    ok = layer_engines()
    for i, e in enumerate(sections["run"]["engines"]):
        if e not in ok:
            V.err(f"run.engines[{i}]", f"engine {e!r} does not run the cuneate layer (engines "
                                       f"that do: {', '.join(ok)})")
    # one trial's detector, as every trial's: each neuron listens to some afferent, and the
    # detector holds its weights, delays and tick (as it is refused on chip)
    by_name = {p["name"]: p for p in pops}
    fields = _fields(g, c["size"])
    src = [(q["source"], x) for q in projs for x in by_name[q["source"]]["gratings"]]
    delays = np.zeros((c["size"], max(1, len(src))), dtype=np.int64)
    weights = np.zeros((c["size"], max(1, len(src))))
    proj = {q["source"]: q for q in projs}
    for s, (pop, x) in enumerate(src):
        syn = _synapse(fields, proj, pop, x, dt)
        if syn is not None:
            j, d, w = syn
            delays[j, s], weights[j, s] = d, w
    for j, f in enumerate(fields):
        if not weights[j].any():
            V.err(f"population[{ci}].gratings", f"cuneate neuron {j}'s field (gratings "
                                                f"{', '.join(map(str, f))}) holds none of its "
                                                f"inputs' afferents")
    try:
        layer_config(delays, weights, c["preset"], sections["hardware"]["update_hz"],
                     sections["hardware"]["rounding"])
    except ConfigError as exc:
        V.err(f"population[{ci}]", f"the cuneate layer's detector is refused: {exc}")


@dataclass
class CuneateLayer:
    """The cuneate layer of an afferent scene over the core's afferents.

    ``population``: its name; ``per_trial``: cuneate neurons a trial; ``fields``: the
    gratings of each one's receptive field; ``trial`` and ``index``: per target (trial-major)
    its trial and its neuron within the trial; ``delays`` (ticks) and ``weights`` (mV/ms):
    ``(n_targets, n_sources)`` over the core's neurons; ``preset``: the targets' Izhikevich
    set; ``network``: the network of the engines (every trial at once)."""

    population: str
    per_trial: int
    fields: list
    trial: list
    index: list
    delays: np.ndarray
    weights: np.ndarray
    preset: str
    network: NetworkConfig

    @property
    def n_targets(self) -> int:
        return len(self.trial)

    def describe(self) -> dict:
        """The layer as a block of the run (``ran["blocks"]``)."""
        det = self.network.det
        conn = self.weights > 0
        return {"block": "coincidence_detector", "population": self.population,
                "neurons": self.n_targets, "per_trial": self.per_trial,
                "fields": self.fields, "sources": int(self.weights.shape[1]),
                "synapses": int(conn.sum()),
                "fan_in": sorted({int(x) for x in conn.sum(axis=1)}),
                "delays_ms": sorted({float(x) for x in self.delays[conn] * det.dt_ms}),
                "weights_mV_per_ms": sorted({float(x) for x in self.weights[conn]}),
                "weight_format": str(det.W), "max_delay_ticks": int(det.max_delay_ticks),
                "role": "cuneate layer"}


def layer_config(delays, weights, preset: str, update_hz: float, rounding: str = "nearest"):
    """The :class:`~cuneate.hdl.coincidence.CoincidenceConfig` of a layer with ``delays``
    (ticks) and ``weights`` (mV/ms), ``(n_targets, n_sources)``, targets of Izhikevich set
    ``preset``, at ``update_hz`` and a clock that holds a tick's work: its refusals are the
    layer's (validation builds one trial's)."""
    d, w = np.asarray(delays, dtype=np.int64), np.asarray(weights, dtype=np.float64)
    M, N = w.shape
    det = {"n_sources": N, "n_targets": M, "delays_ticks": d.tolist(), "weights": w.tolist(),
           "max_delay_ticks": int(d.max(initial=0)) + 1, "param_sets": (preset,),
           "rounding": rounding}
    return CoincidenceConfig(**det, update_hz=update_hz,
                             clock_hz=update_hz * (M * (N + CYCLES_PER_TARGET_EXTRA) + 2))


def layer_network(core, delays, weights, preset: str, **network) -> NetworkConfig:
    """The network of ``core``'s afferents (an :class:`~cuneate.hdl.izhikevich.IzhikevichConfig`:
    its parameter sets, formats and rounding) and a detector with ``delays`` (ticks) and
    ``weights`` (mV/ms), ``(n_targets, n_afferents)``, targets of Izhikevich set ``preset``.
    The clock holds a tick's work unless ``network`` gives one (more
    :class:`~cuneate.hdl.network.NetworkConfig` keywords)."""
    d, w = np.asarray(delays, dtype=np.int64), np.asarray(weights, dtype=np.float64)
    M, N = w.shape
    det = {"n_sources": N, "n_targets": M, "delays_ticks": d.tolist(),
           "weights": w.tolist(), "max_delay_ticks": int(d.max(initial=0)) + 1,
           "param_sets": (preset,), "rounding": core.rounding}
    work = max(N + SWEEP_EXTRA, M * (N + CYCLES_PER_TARGET_EXTRA) + 2) + 2
    kw = {"clock_hz": core.update_hz * work, "cuneate_fifo_depth": max(16, M)} | network
    return NetworkConfig(
        n_afferents=N, detector=det, afferent_param_sets=tuple(core.to_kwargs()["param_sets"]),
        afferent_sets=list(core.neuron_sets), update_hz=core.update_hz,
        tick_source="external",
        afferent_options={"current_format": [core.I.int_bits, core.I.frac_bits],
                          "rounding": core.rounding}, **kw)


def _fields(gratings, size: int) -> list[list[int]]:
    """The receptive fields of ``size`` cuneate neurons tiling ``gratings`` in order."""
    return [[int(x) for x in f] for f in np.array_split(np.asarray(gratings), size)]


def _synapse(fields: list, proj: dict, pop: str, grating: int, dt: float):
    """``(cuneate neuron, delay in ticks, J w)`` of the synapse an afferent of ``pop`` on
    ``grating`` makes (``proj``: the layer's projections by source), or ``None``."""
    q = proj.get(pop)
    j = next((j for j, f in enumerate(fields) if grating in f), None)
    if q is None or j is None:
        return None
    d = q["delays_ms"][j if len(q["delays_ms"]) > 1 else 0]
    return j, int(round(d / dt)), q["weight"]


def scene_layer(scene, neurons, core) -> CuneateLayer | None:
    """The cuneate layer of ``scene`` over ``neurons`` (its afferents in core order) on
    ``core`` (the scene's core: the sources are its neurons, idle ones included), or ``None``
    when the scene names none."""
    cn = next((p for p in scene.populations if p["model"] == "cuneate"), None)
    if cn is None:
        return None
    M = cn["size"]
    fields = _fields(cn["gratings"], M)
    proj = {q["source"]: q for q in scene.projections}
    T = (max(neurons.trial) + 1) if len(neurons) else 0
    delays = np.zeros((M * T, core.n_neurons), dtype=np.int64)
    weights = np.zeros((M * T, core.n_neurons))
    for i, (t, pop, g) in enumerate(zip(neurons.trial, neurons.population, neurons.grating)):
        syn = _synapse(fields, proj, pop, g, core.dt_ms)
        if syn is not None:
            j, d, w = syn
            delays[t * M + j, i], weights[t * M + j, i] = d, w
    net = layer_network(core, delays, weights, cn["preset"])
    return CuneateLayer(cn["name"], M, fields, [t for t in range(T) for _ in range(M)],
                        [j for _ in range(T) for j in range(M)], delays, weights, cn["preset"],
                        net)


def layer_estimate(scene, trials: int, n_sources: int, n_ticks: float,
                   engines) -> tuple[float, float]:
    """Memory (bytes) and time (s) of ``scene``'s cuneate layer over ``trials`` trials of a core
    of ``n_sources`` neurons for ``n_ticks`` ticks on ``engines``: its dense delay and weight
    matrices (as arrays and as the detector's lists, about 150 bytes a pair), the twin's and the
    board's target-source pairs every tick, the golden model's synapses every tick."""
    cn = next((p for p in scene.populations if p["model"] == "cuneate"), None)
    if cn is None:
        return 0.0, 0.0
    pairs = float(cn["size"]) * trials * n_sources
    synapses = float(trials) * sum(p["size"] for p in scene.populations
                                   if p["name"] in cn["inputs"])
    seconds = 2e-6 * pairs
    for e in engines:
        if e == "golden":
            seconds += synapses * n_ticks / 2e7
        elif e == "fixed":
            seconds += pairs * n_ticks / 1e8
        elif implementation("izhikevich", e).layer == "chip":  # the detector's cycles on chip
            seconds += estimate_seconds("izhikevich", e, pairs * n_ticks)
    return 150.0 * pairs, seconds


def check_layer_engines(scene, engines) -> None:
    """Refuse (one line) an engine of ``engines`` that does not run the scene's cuneate layer."""
    if not any(p["model"] == "cuneate" for p in scene.populations):
        return
    refuse_engines_outside(engines, layer_engines(), 'population model "cuneate"', "cuneate layer")


def run_layer(engine: str, layer: CuneateLayer, afferent_ms: list, n_ticks: int):
    """The layer's spike trains (ms, one array per target) and counters on ``engine``'s
    coincidence detector (:func:`~cuneate.sim.coincidence.engines.run_coincidence`: golden, the
    float64 model; fixed, the twin, bit for bit the network's) from that engine's afferent
    trains ``afferent_ms`` (ms, golden convention: the update of tick ``k`` at ``(k + 1) dt``),
    each spike stamped as the network stamps it (the update of sweep ``k`` at detector tick
    ``k + 1``)."""
    det = layer.network.det
    ticks = [spike_ticks(s, det.dt_ms) + 1 for s in afferent_ms]
    ticks += [np.zeros(0, dtype=np.int64)] * (det.n_sources - len(ticks))
    run = run_coincidence(engine, det, ticks, n_ticks)
    out = [np.asarray(s, dtype=np.float64) for s in run.spikes_ms]
    return out, {"spikes": int(run.counts().sum()), "events": run.counters["events"],
                 "merged": run.counters.get("merged_count", 0)} | {
        f"clamp_{k}": v for k, v in run.clamp_counts.items()}
