"""The brief's LIF experiments (section 6) as functions a scene runner or the CLI can call.

:func:`skin_grid`, :func:`skin_3x3`
    A sensorized skin (3x3 in the brief, any grid in a scene), one continuous LIF neuron per
    taxel, input ``I = k1 + k2 f(t)``. One taxel is pressed with rectangular force pulses of
    growing width, then of growing amplitude; its neighbours feel a fraction of the force
    (edge 0.5, diagonal 0.25 by default). Spikes are counted per pulse and per taxel; the
    result says whether counts grow monotonically with width and with amplitude, which taxel
    wins, and the row and column sums. Runs on any engine of :mod:`cuneate.sim.lif.engines`.
:func:`quantization_table`
    A layer of discrete LIF neurons driven by random input spike trains through FP32 weights
    (golden float64) and through the same weights quantized to INT8 and INT4 in the core's
    weight format (the bit-exact twin, i.e. the hardware's arithmetic). For each width: spike
    count error and Victor-Purpura distance against FP32, per neuron, averaged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...golden import budget
from ...golden import lif as golden
from ...golden.metrics import victor_purpura
from ...hdl.lif import LifConfig, LifTwin
from ..engines.registry import estimate_seconds
from .engines import LifProgram, engine_config, run_lif

__all__ = ["SkinResult", "skin_protocol", "press_spread", "skin_grid", "skin_3x3", "QuantRow",
           "quantization_table", "quantization_estimate", "format_skin", "format_quantization"]



@dataclass
class SkinResult:
    engine: str
    dt_ms: float
    pressed: int
    pulses: list[dict]                 # kind, width_ms, amplitude, start_ms, counts (9,)
    counts: np.ndarray                 # (3, 3) total spikes per taxel
    spikes_ms: list[list[float]]
    width_monotonic: bool = False
    amplitude_monotonic: bool = False
    winner: int = -1
    row_sums: list[int] = field(default_factory=list)
    col_sums: list[int] = field(default_factory=list)
    currents: np.ndarray | None = None          # (n_steps, taxels) mV, as driven
    force: np.ndarray | None = None             # (n_steps,) on the pressed taxel
    clamp_counts: dict = field(default_factory=dict)
    wall_s: float = 0.0
    #: what the engine counted besides the spikes (the ``board`` engine: its line's figures,
    #: ``board_*``, and the host's and the device's counters)
    counters: dict = field(default_factory=dict)

    @property
    def pressed_wins(self) -> bool:
        return self.winner == self.pressed

    def to_dict(self) -> dict:
        return {"engine": self.engine, "dt_ms": self.dt_ms, "pressed": self.pressed,
                "winner": self.winner, "pressed_wins": self.pressed_wins,
                "width_monotonic": self.width_monotonic,
                "amplitude_monotonic": self.amplitude_monotonic,
                "counts": self.counts.tolist(), "row_sums": self.row_sums,
                "col_sums": self.col_sums,
                "pulses": [p | {"counts": list(map(int, p["counts"]))} for p in self.pulses],
                "clamp_counts": self.clamp_counts, "counters": self.counters,
                "spikes_ms": self.spikes_ms}


def skin_protocol(widths_ms=(20.0, 40.0, 80.0), amplitudes=(1.0, 1.5, 2.0),
                  base_amplitude: float = 1.0, base_width_ms: float = 40.0,
                  gap_ms: float = 60.0, dt_ms: float = 1.0):
    """Force on the pressed taxel, per step: pulses of growing width at ``base_amplitude``,
    then of growing amplitude at ``base_width_ms``, each followed by ``gap_ms`` of rest.
    Returns ``(force (n_steps,), pulses)``."""
    pulses, t = [], gap_ms / 2
    for w in widths_ms:
        pulses.append({"kind": "width", "width_ms": float(w), "amplitude": base_amplitude,
                       "start_ms": t})
        t += w + gap_ms
    for a in amplitudes:
        pulses.append({"kind": "amplitude", "width_ms": base_width_ms, "amplitude": float(a),
                       "start_ms": t})
        t += base_width_ms + gap_ms
    n = int(round(t / dt_ms))
    tk = np.arange(n) * dt_ms
    force = np.zeros(n)
    for p in pulses:
        on = (tk >= p["start_ms"]) & (tk < p["start_ms"] + p["width_ms"])
        force[on] = p["amplitude"]
    return force, pulses


def press_spread(rows: int, cols: int, pressed: int, edge: float = 0.5,
                 diagonal: float = 0.25) -> np.ndarray:
    """Fraction of the pressed taxel's force felt by each taxel of a ``rows x cols`` grid
    (row-major ``(rows * cols,)``): 1 on the pressed taxel, ``edge`` on its edge neighbours,
    ``diagonal`` on its diagonal neighbours, 0 elsewhere."""
    if not 0 <= pressed < rows * cols:
        raise ValueError(f"pressed taxel must be in 0..{rows * cols - 1}, got {pressed}")
    r, c = divmod(pressed, cols)
    kernel = np.array([[diagonal, edge, diagonal], [edge, 1.0, edge], [diagonal, edge, diagonal]])
    spread = np.zeros((rows, cols))
    for i in range(max(0, r - 1), min(rows, r + 2)):
        for j in range(max(0, c - 1), min(cols, c + 2)):
            spread[i, j] = kernel[1 + i - r, 1 + j - c]
    return spread.ravel()


def skin_grid(engine: str = "fixed", rows: int = 3, cols: int = 3, pressed: int = 4,
              k1: float = 5.0, k2: float = 20.0, update_hz: float = 1000.0,
              protocol: dict | None = None, spread: tuple[float, float] = (0.5, 0.25),
              core: dict | None = None, build_dir=None, sample_hz: float | None = None,
              duration_ms: float | None = None) -> SkinResult:
    """Run a ``rows x cols`` skin on ``engine`` (see the module docstring).

    ``k1`` (mV) and ``k2`` (mV per force unit) map force to current; ``pressed`` is the taxel
    index (row-major); ``spread`` is the fraction of the force on edge and diagonal neighbours;
    ``core`` adds constructor keywords of the LIF core (default: the brief's excitatory cell,
    tau_m 20 ms, threshold 18 mV, reset 11 mV, refractory 2 ms). ``sample_hz`` samples the
    force at that rate and holds each sample for ``update_hz / sample_hz`` ticks (default: one
    sample per tick); ``duration_ms`` extends the run with rest after the protocol.
    """
    n = rows * cols
    dt = 1000.0 / update_hz
    hold = 1
    if sample_hz is not None:
        hold = int(round(update_hz / sample_hz))
        if hold < 1 or abs(hold * sample_hz - update_hz) > 1e-9 * update_hz:
            raise ValueError(f"update_hz {update_hz:g} is not a whole multiple of the sample "
                             f"rate {sample_hz:g}")
    force, pulses = skin_protocol(dt_ms=dt * hold, **(protocol or {}))
    force = np.repeat(force, hold)
    if duration_ms is not None:
        n_steps = int(round(duration_ms / dt))
        if n_steps < force.size:
            raise ValueError(f"duration {duration_ms:g} ms is shorter than the press protocol "
                             f"({force.size * dt:g} ms)")
        force = np.concatenate([force, np.zeros(n_steps - force.size)])
    f_taxel = force[:, None] * press_spread(rows, cols, pressed, *spread)[None, :]
    currents = golden.force_to_current(f_taxel, k1, k2)
    cfg = engine_config({"update_hz": update_hz} | (core or {}), n)
    run = run_lif(engine, cfg, LifProgram(currents), n=n, build_dir=build_dir)
    counts = np.array([len(s) for s in run.spikes_ms]).reshape(rows, cols)
    for p in pulses:
        t0, t1 = p["start_ms"], p["start_ms"] + p["width_ms"] + 0.5 * (pulses[1]["start_ms"]
                                                                     - pulses[0]["start_ms"]
                                                                     - pulses[0]["width_ms"])
        p["counts"] = np.array([int(np.sum((np.asarray(s) > t0) & (np.asarray(s) <= t1)))
                                for s in run.spikes_ms])
    own = [p["counts"][pressed] for p in pulses]
    wk = [o for o, p in zip(own, pulses) if p["kind"] == "width"]
    ak = [o for o, p in zip(own, pulses) if p["kind"] == "amplitude"]
    res = SkinResult(engine, dt, pressed, pulses, counts, run.spikes_ms)
    res.width_monotonic = bool(len(wk) > 1 and all(b >= a for a, b in zip(wk, wk[1:]))
                               and wk[-1] > wk[0])
    res.amplitude_monotonic = bool(len(ak) > 1 and all(b >= a for a, b in zip(ak, ak[1:]))
                                   and ak[-1] > ak[0])
    flat = counts.ravel()
    res.winner = int(np.argmax(flat)) if (flat == flat.max()).sum() == 1 else -1
    res.row_sums = [int(x) for x in counts.sum(axis=1)]
    res.col_sums = [int(x) for x in counts.sum(axis=0)]
    res.currents = currents
    res.force = force
    res.clamp_counts = dict(run.clamp_counts)
    res.wall_s = run.wall_s
    res.counters = dict(run.counters)
    return res


def skin_3x3(engine: str = "fixed", pressed: int = 4, k1: float = 5.0, k2: float = 20.0,
             update_hz: float = 1000.0, protocol: dict | None = None, core: dict | None = None,
             build_dir=None) -> SkinResult:
    """The brief's 3x3 skin (:func:`skin_grid` with 3 rows and 3 columns)."""
    if not 0 <= pressed < 9:
        raise ValueError(f"pressed taxel must be in 0..8, got {pressed}")
    return skin_grid(engine, 3, 3, pressed, k1, k2, update_hz, protocol, core=core,
                     build_dir=build_dir)


def format_skin(res: SkinResult) -> str:
    rows, cols = res.counts.shape
    lines = [f"{rows}x{cols} skin on {res.engine} (dt = {res.dt_ms:g} ms), pressed taxel "
             f"{res.pressed}"]
    for p in res.pulses:
        lines.append(f"  {p['kind']:9s} pulse {p['width_ms']:5g} ms x {p['amplitude']:g}: "
                     f"{int(p['counts'][res.pressed])} spikes on the pressed taxel, "
                     f"{int(p['counts'].sum())} in total")
    lines.append("  spike counts:")
    for i, row in enumerate(res.counts):
        lines.append("    " + " ".join(f"{int(x):4d}" for x in row) + f"  | row sum "
                     f"{res.row_sums[i]}")
    lines.append("    " + " ".join(f"{x:4d}" for x in res.col_sums) + "  <- column sums")
    lines.append(f"  counts grow with width: {res.width_monotonic}; with amplitude: "
                 f"{res.amplitude_monotonic}; winner: taxel {res.winner} "
                 f"({'the pressed one' if res.pressed_wins else 'NOT the pressed one'})")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------
@dataclass
class QuantRow:
    weights: str
    bits: int | None
    weight_format: str
    weight_rms_error: float
    total_spikes: int
    count_error_mean: float           # mean over neurons of |n_q - n_fp32|
    count_error_rel: float            # sum |n_q - n_fp32| / sum n_fp32
    vp_mean: float                    # mean Victor-Purpura distance to FP32 (per neuron)

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def quantization_estimate(n_inputs: int, n_neurons: int, n_steps: int, n_bits: int = 2
                          ) -> dict:
    """Memory (bytes) and time (s) of :func:`quantization_table` before it allocates: the
    weight matrix and its copies (float, per format raw and rounded), the input spikes (and
    their float copy for the golden model), the spike rasters; the golden layer's products and
    each format's twin run at the registry's speed."""
    n_core = max(8, n_neurons)
    w = budget.array_bytes(n_inputs, n_core)
    nbytes = (budget.BASE_BYTES + (4 + 3 * n_bits) * w
              + budget.array_bytes(n_steps, n_inputs, 9)
              + (2 + n_bits) * budget.array_bytes(n_steps, n_core, 1))
    seconds = 1e-9 * n_steps * n_inputs * n_neurons + n_bits * estimate_seconds(
        "lif", "fixed", n_steps * n_core * (1.0 + n_inputs / 64.0))
    return {"bytes": nbytes, "seconds": seconds}


def quantization_table(n_inputs: int = 64, n_neurons: int = 32, n_steps: int = 100,
                       rate: float = 0.2, alpha: float = golden.DISCRETE_ALPHA,
                       u_th: float = golden.DISCRETE_U_TH, weight_scale: float = 0.12,
                       bits=(8, 4), vp_q: float = 0.5, seed: int = 0) -> list[QuantRow]:
    """FP32 vs INT8 vs INT4 weights in a discrete LIF layer (see the module docstring).

    Weights ``N(0.25 weight_scale, weight_scale)``; inputs Bernoulli(``rate``) per step. The
    FP32 reference is the float64 golden model with the weights rounded to float32; INT-n runs
    the core's arithmetic (twin) with the weights in an n-bit format whose fraction bits hold
    the largest weight. VP cost ``vp_q`` per step of shift.
    """
    est = quantization_estimate(n_inputs, n_neurons, n_steps, len(bits))
    budget.check(f"the quantization table ({n_inputs} inputs x {n_neurons} neurons, {n_steps} "
                 f"steps)", est["bytes"], est["seconds"], "fewer inputs, neurons or steps")
    rng = np.random.default_rng(seed)
    w = (rng.normal(0.25 * weight_scale, weight_scale, (n_inputs, n_neurons))
         .astype(np.float32).astype(np.float64))
    x = rng.random((n_steps, n_inputs)) < rate
    ref = golden.simulate_discrete_lif(x.astype(np.float64), w, alpha=alpha, u_th=u_th)
    ref_trains = [np.flatnonzero(ref.spikes[:, n]).astype(float) for n in range(n_neurons)]
    n_ref = np.array([len(t) for t in ref_trains])
    rows = [QuantRow("FP32", 32, "float32", 0.0, int(n_ref.sum()), 0.0, 0.0, 0.0)]
    for b in bits:
        cfg = LifConfig(n_neurons=max(8, n_neurons), form="discrete",
                        weights=np.vstack([w.T, np.zeros((max(8, n_neurons) - n_neurons,
                                                          n_inputs))]),
                        weight_bits=b, current_format=(4, 12),
                        param_sets=[{"alpha": alpha, "u_th": u_th}])
        twin = LifTwin(cfg)
        ks, ns = twin.run_raw(np.zeros(cfg.n_neurons, dtype=np.int64), n_steps, x)
        spk = np.zeros((n_steps, cfg.n_neurons), dtype=bool)
        spk[ks, ns] = True
        spk = spk[:, :n_neurons]
        trains = [np.flatnonzero(spk[:, n]).astype(float) for n in range(n_neurons)]
        n_q = np.array([len(t) for t in trains])
        wq = cfg.W.to_float(cfg.weights_raw[:n_neurons]).T
        vp = [victor_purpura(a, r, vp_q) for a, r in zip(trains, ref_trains)]
        rows.append(QuantRow(f"INT{b}", b, str(cfg.W), float(np.sqrt(np.mean((wq - w) ** 2))),
                             int(n_q.sum()), float(np.mean(np.abs(n_q - n_ref))),
                             float(np.abs(n_q - n_ref).sum() / max(1, n_ref.sum())),
                             float(np.mean(vp))))
    return rows


def format_quantization(rows: list[QuantRow]) -> str:
    head = (f"{'weights':8s} {'format':8s} {'w rms err':>10s} {'spikes':>7s} "
            f"{'|dn| mean':>10s} {'|dn| rel':>9s} {'VP mean':>8s}")
    out = [head, "-" * len(head)]
    for r in rows:
        out.append(f"{r.weights:8s} {r.weight_format:8s} {r.weight_rms_error:10.4g} "
                   f"{r.total_spikes:7d} {r.count_error_mean:10.3f} {r.count_error_rel:9.3f} "
                   f"{r.vp_mean:8.3f}")
    return "\n".join(out)
