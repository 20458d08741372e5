"""Float64 reference model of NIR's neuron nodes on a time grid, vectorized over neurons.

A feed-forward chain of layers, each ``[Delay] -> Affine/Linear -> neuron`` in NIR's terms (the
graph reading is :mod:`cuneate.sim.nir.graph`'s; this module sees only numbers). The neuron
equations are NIR's (times in seconds, as NIR writes them)::

    LIF      tau dv/dt = (v_leak - v) + r I          spike when v > v_threshold, v <- v_reset
    IF       dv/dt = r I                             spike and reset as LIF
    LI, I    as LIF, IF without threshold (the output is v)
    CubaLIF  tau_syn dI_s/dt = -I_s + w_in I,  tau_mem dv/dt = (v_leak - v) + r I_s,  spike as LIF
    CubaLI   as CubaLIF without threshold

Time grid and signals (the convention NIR's reference simulators use): every signal is sampled
on a grid of step ``dt``; a spike is the value 1 in one step. Update ``k`` advances ``k dt`` to
``(k + 1) dt`` with the layer's input ``I[k] = W x[k] + b``; the threshold is tested on the
updated ``v``; a spike of update ``k`` is reported at ``(k + 1) dt`` and is the next layer's
input of update ``k + 1`` (a spike enters the next layer at the instant it is emitted: no
latency is added, and a chain of ``L`` layers reports its last layer's spikes ``L - 1`` steps
after a simulator that passes spikes on within the step). ``Delay`` shifts its channels by
whole steps.

Schemes (``scheme=``), both the recursion ``I_s[k] = alpha_s I_s[k-1] + g_s I[k]``,
``u[k] = alpha_m u[k-1] + g_m I_s[k]`` (``u = v - v_leak``; without a synapse ``I_s = I``):

``"exact"``
    Every input sample acts as an impulse of area ``dt I[k]`` at the step start; between grid
    points the linear equations are solved exactly: ``alpha = exp(-dt/tau)``; no synapse:
    ``g_m = alpha_m dt r / tau``; with a synapse ``g_s = dt w_in / tau_syn`` and
    ``g_m = r tau_syn (alpha_s - alpha_m) / (tau_syn - tau_mem)`` (``r dt alpha_m / tau`` for
    equal time constants); no leak (IF, I): ``alpha = 1``, ``g_m = dt r``. Exact for impulses
    on the grid; for a current held over the step it differs by ``O(dt / tau)`` relative.
``"euler"``
    Forward Euler, the synaptic current updated first (snnTorch's and Norse's reading of
    NIR's neurons): ``alpha = 1 - dt/tau``, ``g_s = dt w_in / tau_syn``, ``g_m = dt r / tau``;
    refused for ``dt >= tau`` (``alpha <= 0``). Its local error is ``O((dt/tau)^2)`` per step.

Initial state: ``v = 0`` and ``I_s = 0`` (NIR's), i.e. ``u = -v_leak``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["SCHEMES", "SPIKING", "SYNAPTIC", "LEAKY", "NEURON_KINDS", "NirLayer", "LayerSteps",
           "step_constants", "simulate_layers", "LayerResult"]

SCHEMES = ("exact", "euler")
#: neuron node types this model runs, and which of them spike / have a synapse / leak
NEURON_KINDS = ("LIF", "CubaLIF", "IF", "LI", "CubaLI", "I")
SPIKING = ("LIF", "CubaLIF", "IF")
SYNAPTIC = ("CubaLIF", "CubaLI")
LEAKY = ("LIF", "CubaLIF", "LI", "CubaLI")


@dataclass
class NirLayer:
    """One layer: the weights of its input projection and its neurons' NIR parameters (arrays
    of the layer's size; ``tau_syn`` and ``w_in`` for the synaptic kinds; ``v_threshold`` and
    ``v_reset`` for the spiking ones). ``delay_s`` (per input channel, seconds) or None;
    ``nodes`` names the NIR nodes the layer came from (for messages)."""

    kind: str
    weight: np.ndarray
    bias: np.ndarray
    tau: np.ndarray | None = None
    r: np.ndarray | None = None
    v_leak: np.ndarray | None = None
    v_threshold: np.ndarray | None = None
    v_reset: np.ndarray | None = None
    tau_syn: np.ndarray | None = None
    w_in: np.ndarray | None = None
    delay_s: np.ndarray | None = None
    nodes: dict = field(default_factory=dict)

    @property
    def n_out(self) -> int:
        return int(self.weight.shape[0])

    @property
    def n_in(self) -> int:
        return int(self.weight.shape[1])

    @property
    def name(self) -> str:
        return str(self.nodes.get("neuron", self.kind))


@dataclass
class LayerSteps:
    """Per-neuron constants of one layer's recursion on the grid (see the module docstring)."""

    alpha_m: np.ndarray
    g_m: np.ndarray
    alpha_s: np.ndarray | None
    g_s: np.ndarray | None
    u_th: np.ndarray | None
    u_reset: np.ndarray | None
    u0: np.ndarray
    delay_steps: np.ndarray | None


def _delays(layer: NirLayer, dt: float) -> np.ndarray | None:
    if layer.delay_s is None:
        return None
    steps = np.asarray(layer.delay_s, dtype=np.float64) / dt
    if np.any(steps < 0) or not np.allclose(steps, np.round(steps), rtol=0, atol=1e-6):
        bad = float(np.asarray(layer.delay_s).ravel()[np.argmax(np.abs(steps - np.round(steps)))])
        raise ValueError(f"Delay {layer.nodes.get('delay', '?')!r}: {bad:g} s is not a whole "
                         f"number of steps of {dt:g} s")
    return np.round(steps).astype(np.int64)


def step_constants(layer: NirLayer, dt: float, scheme: str = "exact") -> LayerSteps:
    """The grid constants of ``layer`` at step ``dt`` (s) under ``scheme``; ``ValueError``
    naming the node for what the scheme cannot discretize."""
    if scheme not in SCHEMES:
        raise ValueError(f"unknown scheme {scheme!r}; known: {', '.join(SCHEMES)}")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    k, name, n = layer.kind, layer.name, layer.n_out
    r = np.broadcast_to(np.asarray(layer.r, dtype=np.float64), (n,))

    def decay(tau, what):
        tau = np.broadcast_to(np.asarray(tau, dtype=np.float64), (n,))
        if np.any(~np.isfinite(tau)) or np.any(tau <= 0):
            raise ValueError(f"{k} {name!r}: {what} must be > 0 s")
        if scheme == "exact":
            return np.exp(-dt / tau), tau
        a = 1.0 - dt / tau
        if np.any(a <= 0):
            raise ValueError(f"{k} {name!r}: {what} {float(tau.min()):g} s <= dt {dt:g} s, "
                             f"where forward Euler does not decay (alpha <= 0)")
        return a, tau

    alpha_s = g_s = None
    if k in LEAKY:
        tm_name = "tau_mem" if k in SYNAPTIC else "tau"
        alpha_m, tau_m = decay(layer.tau, tm_name)
        if k in SYNAPTIC:
            alpha_s, tau_s = decay(layer.tau_syn, "tau_syn")
            g_s = dt * np.broadcast_to(layer.w_in, (n,)) / tau_s
            if scheme == "exact":
                same = np.isclose(tau_s, tau_m, rtol=1e-9, atol=0)
                diff = np.where(same, 1.0, tau_s - tau_m)
                g_m = np.where(same, r * dt * alpha_m / tau_m,
                               r * tau_s * (alpha_s - alpha_m) / diff)
            else:
                g_m = dt * r / tau_m
        else:
            g_m = (alpha_m if scheme == "exact" else 1.0) * dt * r / tau_m
        v_leak = np.broadcast_to(np.asarray(layer.v_leak, dtype=np.float64), (n,))
    else:
        alpha_m, g_m = np.ones(n), dt * r
        v_leak = np.zeros(n)
    u_th = u_reset = None
    if k in SPIKING:
        u_th = np.broadcast_to(layer.v_threshold, (n,)) - v_leak
        u_reset = np.broadcast_to(layer.v_reset, (n,)) - v_leak
    return LayerSteps(np.asarray(alpha_m, float), np.asarray(g_m, float),
                      None if alpha_s is None else np.asarray(alpha_s, float),
                      None if g_s is None else np.asarray(g_s, float), u_th, u_reset,
                      -v_leak.astype(np.float64), _delays(layer, dt))


@dataclass
class LayerResult:
    """One layer's run: ``spikes`` (steps, n) bool (spiking kinds) and ``v`` (steps, n), the
    membrane after each update (the output of LI, CubaLI and I)."""

    spikes: np.ndarray | None
    v: np.ndarray


def delay_inputs(x: np.ndarray, delay_steps: np.ndarray | None) -> np.ndarray:
    """Channel ``i`` of ``x`` (steps, channels) delayed by ``delay_steps[i]`` steps (zeros
    before)."""
    if delay_steps is None or not np.any(delay_steps):
        return x
    out = np.zeros_like(x)
    T = x.shape[0]
    for i, d in enumerate(delay_steps):
        if d < T:
            out[d:, i] = x[:T - d, i]
    return out


def simulate_layers(layers: list[NirLayer], inputs, dt: float, scheme: str = "exact",
                    record_v: bool = True) -> list[LayerResult]:
    """Run the chain on ``inputs`` (steps, n_in of the first layer; spikes as 0/1 or graded
    values). Layer ``l > 0`` takes layer ``l - 1``'s spikes (or, after a non-spiking layer, its
    ``v``) one step later (see the module docstring). Raises ``ValueError`` on a non-finite
    state, naming the layer."""
    x = np.asarray(inputs, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != layers[0].n_in:
        raise ValueError(f"inputs must have shape (steps, {layers[0].n_in}), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("inputs must be finite")
    out = []
    for li, layer in enumerate(layers):
        c = step_constants(layer, dt, scheme)
        if li:
            prev = out[-1]
            src = prev.spikes.astype(np.float64) if prev.spikes is not None else prev.v
            x = np.vstack([np.zeros((1, src.shape[1])), src[:-1]])
        xin = delay_inputs(x, c.delay_steps)
        drive = xin @ np.asarray(layer.weight, dtype=np.float64).T + layer.bias
        T, n = drive.shape
        u = c.u0.copy()
        s = np.zeros(n)
        spikes = np.zeros((T, n), dtype=bool) if c.u_th is not None else None
        v = np.zeros((T, n)) if record_v or spikes is None else None
        v_leak = -c.u0
        for k in range(T):
            if c.alpha_s is not None:
                s = c.alpha_s * s + c.g_s * drive[k]
                u = c.alpha_m * u + c.g_m * s
            else:
                u = c.alpha_m * u + c.g_m * drive[k]
            if spikes is not None:
                fire = u > c.u_th
                spikes[k] = fire
                u = np.where(fire, c.u_reset, u)
            if v is not None:
                v[k] = u + v_leak
        if not np.all(np.isfinite(u)):
            raise ValueError(f"layer {layer.name!r}: the state became non-finite")
        out.append(LayerResult(spikes, v if v is not None else np.zeros((0, n))))
    return out
