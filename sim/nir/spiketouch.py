"""SpikeTouch on cuneate's hardware: what INT8 and INT4 weights cost a tactile classifier.

The seed study trained a small spiking classifier and quantized its weights FP32 -> INT8 ->
INT4: 95.0 % -> 84.5 % -> 74.75 % without quantization-aware training, 90.75 % / 84.88 % with
it. Here the same question is asked of the LIF cores:

1. **Data** from cuneate's own physics (:func:`synthesize`): grasps of the four materials of
   the brief (Dragon Skin, Vytaflex, ABS, aluminium; :func:`cuneate.golden.tactile.
   synthesize_grasp`, per-trial spreads of velocity, pad, modulus and coupling, interrogator
   noise), two gratings, the first ``WINDOW_MS`` after contact in ``STEPS`` steps. Each grating
   is encoded into spikes by level crossings of the wavelength shift (``LEVELS`` levels up to
   the stop shift: a channel spikes in the step the shift first passes its level) and by
   thresholds on its slope per step (``LEVELS`` channels). Held-out test trials.
2. **Training** in snnTorch (the framework the graph then leaves; its own environment, see
   :mod:`cuneate.sim.nir.crosscheck`): ``Linear -> Leaky -> Linear -> Leaky``, ``HIDDEN`` hidden
   neurons, beta 0.9, threshold 1, reset to zero; float, INT8 and INT4 weights (symmetric
   per-tensor), each without quantization-aware training (post-training quantization of the
   float model) and with it; snnTorch's own test accuracy of the weights it exports.
3. **Export -> import**: snnTorch's ``export_to_nir``, then :func:`cuneate.sim.nir.mapping.
   map_graph` (Euler scheme: snnTorch's recursion; ``weight_scale="max"`` so the INT weights map
   exactly; 16-bit weights for the float model) and test accuracy on ``golden``, ``fixed`` and,
   on a subset of test trials, ``verilator`` (its spikes checked equal to ``fixed`` on the same
   input). The class is the output neuron with the most spikes (ties: the lowest index).
4. **Resources** of the first layer's LIF core per weight width (yosys ``synth_ecp5``).
"""

from __future__ import annotations

import json
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...golden.tactile import MATERIALS, GraspSpec, apply_effects, synthesize_grasp
from ...hdl.lif import lif_verilog
from .crosscheck import peer_python
from .engines import run_network
from .graph import layers_of, read_graph
from .mapping import map_graph

__all__ = ["synthesize", "run_spiketouch", "format_table", "SEED_FIGURES", "CONFIGS"]

STEPS = 100
WINDOW_MS = 300.0
LEVELS = 8
HIDDEN = 64
BETA, THRESHOLD = 0.9, 1.0
#: the seed study's test accuracies (%)
SEED_FIGURES = {"float": 95.0, "int8": 84.5, "int4": 74.75, "int8-qat": 90.75,
                "int4-qat": 84.88}
#: the ECP5 cells the resource table lists (yosys ``synth_ecp5`` names)
RESOURCE_CELLS = ("LUT4", "TRELLIS_FF", "TRELLIS_DPR16X4", "DP16KD", "MULT18X18D", "CCU2C")
#: name -> (weight bits, quantization-aware training)
CONFIGS = {"float": (0, 0), "int8": (8, 0), "int4": (4, 0), "int8-qat": (8, 1),
           "int4-qat": (4, 1)}


def _encode(dl: np.ndarray, fs_hz: float, contact_ms: float, stop_nm: float) -> np.ndarray:
    """(STEPS, 2 gratings x 2 LEVELS) spikes of one trace (see the module docstring)."""
    i0 = int(round(contact_ms * fs_hz / 1000.0))
    n = int(round(WINDOW_MS * fs_hz / 1000.0))
    x = dl[i0:i0 + n]
    per = n // STEPS
    x = x[:per * STEPS].reshape(STEPS, per, -1).mean(axis=1)          # (STEPS, gratings)
    levels = stop_nm * (np.arange(1, LEVELS + 1) / LEVELS)
    out = []
    for g in range(x.shape[1]):
        above = x[:, g][:, None] > levels[None, :]
        first = above & ~np.vstack([np.zeros((1, LEVELS), bool), np.maximum.accumulate(above)[:-1]])
        slope = np.diff(x[:, g], prepend=0.0)
        sl = stop_nm / STEPS * np.geomspace(0.5, 16.0, LEVELS)
        out += [first, slope[:, None] > sl[None, :]]
    return np.hstack(out)


def synthesize(n_per_class: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``x`` (trials, STEPS, inputs) spikes and ``y`` (trials,) material labels."""
    rng = np.random.default_rng(seed)
    spec = GraspSpec()
    xs, ys = [], []
    for label, mat in enumerate(MATERIALS.values()):
        for _ in range(n_per_class):
            strain, _ = synthesize_grasp(mat, spec, rng)
            tr = apply_effects(strain, ["strain", "noise"], {"noise": {"sigma_pm": 0.3}}, rng,
                               spec.fs_hz)
            xs.append(_encode(tr.d_lambda_nm, spec.fs_hz, spec.contact_ms, spec.stop_nm))
            ys.append(label)
    x, y = np.array(xs), np.array(ys)
    perm = rng.permutation(len(y))
    return x[perm], y[perm]


@dataclass
class SpikeTouchResult:
    rows: list = field(default_factory=list)
    resources: list = field(default_factory=list)
    data: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"rows": self.rows, "resources": self.resources, "data": self.data,
                "seed_figures": SEED_FIGURES}


def _accuracy(counts: np.ndarray, y: np.ndarray) -> float:
    return float((counts.argmax(axis=1) == y).mean())


def _engine_counts(engine, mapped, x, build_dir=None) -> np.ndarray:
    counts = []
    for trial in x:
        xs = np.vstack([trial, np.zeros((1, trial.shape[1]))])       # one flush step
        counts.append(run_network(engine, mapped, xs, build_dir=build_dir).counts())
    return np.array(counts)


def _hdl_subset(mapped, x, y, build: Path, gap: int = 40) -> dict:
    """The subset's trials back to back (``gap`` empty steps between) on Verilator and on the
    fixed engine: spikes equal, and the accuracy of the Verilator run."""
    pad = np.zeros((gap, x.shape[2]))
    seq = np.vstack([np.vstack([t, pad]) for t in x])
    hdl = run_network("verilator", mapped, seq, build_dir=build)
    fixed = run_network("fixed", mapped, seq)
    span = STEPS + gap
    counts = np.array([hdl.spikes[i * span:(i + 1) * span].sum(axis=0) for i in range(len(y))])
    return {"trials": int(len(y)), "accuracy": _accuracy(counts, y),
            "equal_to_fixed": bool(np.array_equal(hdl.spikes, fixed.spikes)),
            "wall_s": hdl.wall_s}


def _resources(mapped_by_bits: dict, out: Path) -> list:
    from ...hdl.flow.synth import synthesize
    rows = []
    for bits, mapped in mapped_by_bits.items():
        cfg = mapped.config.layers[0]
        res = synthesize(lif_verilog(cfg), "lif_core", "ecp5", workdir=out / f"synth_w{bits}")
        rows.append({"weight_bits": bits, "neurons": cfg.n_neurons, "inputs": cfg.n_inputs,
                     "weight_ram_bits": cfg.n_neurons * cfg.n_inputs * cfg.W.width,
                     "flow": res["flow"], "synth_s": res["seconds"],
                     **{k: int(res["cells"].get(k, 0)) for k in RESOURCE_CELLS}})
    return rows


def run_spiketouch(out: Path, quick: bool = False, hdl_trials: int = 20, seed: int = 0,
                   log=print) -> SpikeTouchResult:
    """The whole experiment (see the module docstring); writes ``out/spiketouch.json``."""
    out = Path(out)
    py, why = peer_python()
    if py is None:
        raise RuntimeError(f"the training framework (snnTorch) is unavailable: {why}")
    n_per, epochs, hidden = (40, 4, 32) if quick else (150, 25, HIDDEN)
    x, y = synthesize(n_per, seed)
    n_test = len(y) // 4
    data = out / "data.npz"
    np.savez(data, x_train=x[n_test:], y_train=y[n_test:], x_test=x[:n_test], y_test=y[:n_test],
             beta=BETA, threshold=THRESHOLD)
    xte, yte = x[:n_test], y[:n_test]
    res = SpikeTouchResult(data={"trials": int(len(y)), "test_trials": int(n_test),
                                 "inputs": int(x.shape[2]), "steps": STEPS, "hidden": hidden,
                                 "classes": 4, "epochs": epochs,
                                 "input_rate": float(x.mean())})
    log(f"data: {len(y)} trials ({n_test} test), {x.shape[2]} inputs, {STEPS} steps, input "
        f"spike rate {x.mean():.3f}")
    peer = Path(__file__).with_name("peer_snntorch.py")
    mapped_by_bits = {}
    for name, (bits, qat) in CONFIGS.items():
        d = out / name
        t0 = time.perf_counter()
        r = subprocess.run([py, str(peer), "train", str(data), str(d), str(bits), str(qat),
                            str(seed), str(hidden), str(epochs)], capture_output=True, text=True,
                           timeout=7200)
        if r.returncode:
            raise RuntimeError(f"training {name} failed: {r.stderr.strip()[-300:]}")
        own = json.loads(r.stdout.strip().splitlines()[-1])
        chain = layers_of(read_graph(d / "model.nir"))
        hw_bits = bits or 16
        mapped = map_graph(chain, update_hz=1e4, scheme="euler", weight_bits=hw_bits,
                           weight_scale="max")
        mapped_by_bits.setdefault(hw_bits, mapped)
        row = {"config": name, "weight_bits": bits or "float", "qat": bool(qat),
               "snntorch": own["accuracy"], "train_s": own["train_s"],
               "golden": _accuracy(_engine_counts("golden", mapped, xte), yte),
               "fixed": _accuracy(_engine_counts("fixed", mapped, xte), yte),
               "hardware_weight_bits": hw_bits,
               "weights_max_abs_error": max(lr["weights"]["max_abs_error"] /
                                            lr["state_scale"] for lr in mapped.report),
               "seed": SEED_FIGURES[name]}
        if hdl_trials:
            k = min(hdl_trials, n_test)
            row["verilator"] = _hdl_subset(mapped, xte[:k], yte[:k], out / f"{name}_hdl")
        row["wall_s"] = time.perf_counter() - t0
        res.rows.append(row)
        log(f"{name}: snnTorch {100 * row['snntorch']:.1f} %, golden {100 * row['golden']:.1f} "
            f"%, fixed {100 * row['fixed']:.1f} % ({row['wall_s']:.0f} s)")
    if not quick:
        res.resources = _resources(mapped_by_bits, out)
    (out / "spiketouch.json").write_text(json.dumps(res.to_dict(), indent=1, default=float))
    return res


def format_table(res: SpikeTouchResult) -> str:
    """The table of docs/nir.md (markdown)."""
    lines = ["| weights | QAT | seed study | snnTorch (float32) | golden | fixed | Verilator "
             "(subset; == fixed) |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in res.rows:
        v = r.get("verilator")
        hv = (f"{100 * v['accuracy']:.1f} % of {v['trials']} ({'yes' if v['equal_to_fixed'] else 'NO'})"
              if v else "-")
        lines.append(f"| {r['weight_bits']} | {'yes' if r['qat'] else 'no'} | {r['seed']:.2f} % "
                     f"| {100 * r['snntorch']:.1f} % | {100 * r['golden']:.1f} % | "
                     f"{100 * r['fixed']:.1f} % | {hv} |")
    if res.resources:
        lines += ["", "| weight bits | neurons x inputs | weight RAM bits | "
                  + " | ".join(RESOURCE_CELLS) + " |", "| --- " * (3 + len(RESOURCE_CELLS)) + "|"]
        for r in res.resources:
            lines.append(f"| {r['weight_bits']} | {r['neurons']} x {r['inputs']} | "
                         f"{r['weight_ram_bits']} | "
                         + " | ".join(str(r.get(k, "-")) for k in RESOURCE_CELLS) + " |")
    return "\n".join(lines)
