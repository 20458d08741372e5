"""The brief's LIF experiments (section 6) as functions a scene runner or the CLI can call.

:func:`skin_3x3`
    A 3x3 sensorized skin, one continuous LIF neuron per taxel, input ``I = k1 + k2 f(t)``.
    One taxel is pressed with rectangular force pulses of growing width, then of growing
    amplitude; its neighbours feel a fraction of the force (edge 0.5, diagonal 0.25 by
    default). Spikes are counted per pulse and per taxel; the result says whether counts grow
    monotonically with width and with amplitude, which taxel wins, and the row and column sums.
    Runs on any engine of :mod:`cuneate.sim.lif_engines`.
:func:`quantization_table`
    A layer of discrete LIF neurons driven by random input spike trains through FP32 weights
    (golden float64) and through the same weights quantized to INT8 and INT4 in the core's
    weight format (the bit-exact twin, i.e. the hardware's arithmetic). For each width: spike
    count error and Victor-Purpura distance against FP32, per neuron, averaged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..golden import lif as golden
from ..golden.metrics import victor_purpura
from ..hdl.lif import LifConfig, LifTwin
from .lif_engines import LifProgram, engine_config, run_lif

__all__ = ["SkinResult", "skin_protocol", "skin_3x3", "QuantRow", "quantization_table",
           "format_skin", "format_quantization"]

#: spread of a press on the centre of the 3x3 grid to its neighbours
SPREAD = np.array([[0.25, 0.5, 0.25], [0.5, 1.0, 0.5], [0.25, 0.5, 0.25]])


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


def skin_3x3(engine: str = "fixed", pressed: int = 4, k1: float = 5.0, k2: float = 20.0,
             update_hz: float = 1000.0, protocol: dict | None = None, core: dict | None = None,
             build_dir=None) -> SkinResult:
    """Run the 3x3 skin on ``engine`` (see the module docstring).

    ``k1`` (mV) and ``k2`` (mV per force unit) map force to current; ``pressed`` is the taxel
    index (row-major); ``core`` adds constructor keywords of the LIF core (default: the
    brief's excitatory cell, tau_m 20 ms, threshold 18 mV, reset 11 mV, refractory 2 ms).
    """
    if not 0 <= pressed < 9:
        raise ValueError(f"pressed taxel must be in 0..8, got {pressed}")
    dt = 1000.0 / update_hz
    force, pulses = skin_protocol(dt_ms=dt, **(protocol or {}))
    r, c = divmod(pressed, 3)
    spread = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            di, dj = i - r, j - c
            if abs(di) <= 1 and abs(dj) <= 1:
                spread[i, j] = SPREAD[1 + di, 1 + dj]
    f_taxel = force[:, None] * spread.ravel()[None, :]
    currents = golden.force_to_current(f_taxel, k1, k2)
    cfg = engine_config({"update_hz": update_hz} | (core or {}), 9)
    run = run_lif(engine, cfg, LifProgram(currents), n=9, build_dir=build_dir)
    counts = np.array([len(s) for s in run.spikes_ms]).reshape(3, 3)
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
    res.width_monotonic = bool(all(b >= a for a, b in zip(wk, wk[1:])) and wk[-1] > wk[0])
    res.amplitude_monotonic = bool(all(b >= a for a, b in zip(ak, ak[1:])) and ak[-1] > ak[0])
    flat = counts.ravel()
    res.winner = int(np.argmax(flat)) if (flat == flat.max()).sum() == 1 else -1
    res.row_sums = [int(x) for x in counts.sum(axis=1)]
    res.col_sums = [int(x) for x in counts.sum(axis=0)]
    return res


def format_skin(res: SkinResult) -> str:
    lines = [f"3x3 skin on {res.engine} (dt = {res.dt_ms:g} ms), pressed taxel {res.pressed}"]
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
        spk = np.array([twin.sweep(x[k]) for k in range(n_steps)])[:, :n_neurons]
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
