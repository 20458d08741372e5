"""The learning layer compiled by Verilator with a C++ harness (``harness.cpp``): whole
presentation protocols with no Python per cycle (the ``verilator-fast`` engine of the block).

:func:`run_fast` writes the presentations (:class:`~cuneate.golden.cuneate_layer
.Presentations`) and each one's learn flag, runs the executable (built and cached per Verilog
by :func:`cuneate.sim.engines.verilator_fast.compile_harness`) and reads back every spike of
the layer's stream and the weights through its host read port (every ``snapshot_every``
presentations, and after the last)."""

from __future__ import annotations

import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ...hdl.plasticity import CLAMP_KINDS, PlasticityConfig
from ...hdl.plasticity.core import learning_verilog
from ..engines.verilator_fast import HarnessError, compile_harness

__all__ = ["HARNESS", "TOP", "build", "run_fast"]

HARNESS = Path(__file__).with_name("harness.cpp")
TOP = "learning_layer"


def build(cfg: PlasticityConfig, build_root: Path | None = None) -> Path:
    """The harness executable of ``cfg``'s layer (built, or from the cache)."""
    return compile_harness(learning_verilog(cfg, name=TOP), TOP, HARNESS, {}, build_root,
                           prefix="Vtop")


def _schedule(cfg, pres, flags) -> bytes:
    hdr = np.array([cfg.n_targets, cfg.n_synapses, cfg.n_sources, pres.n, pres.n_ticks,
                    pres.window_ticks, len(pres.ticks)], dtype="<i8")
    parts = [hdr, np.asarray(pres.offsets, "<i8"), np.asarray(flags, "<i8"),
             np.asarray(pres.ticks, "<i8"), np.asarray(pres.sources, "<i8")]
    return b"".join(p.tobytes() for p in parts)


def run_fast(cfg: PlasticityConfig, pres, learn=True, snapshot_every: int = 0,
             build_root: Path | None = None) -> dict:
    """Run ``pres`` on the compiled layer. Returns ``spike_pres``, ``spike_tick``,
    ``spike_cn``, ``counts`` (``(n, M)`` within the window), ``weights`` (raw, ``(M, K)``, after
    the last presentation), ``snapshots`` (raw weights every ``snapshot_every``
    presentations), ``summary`` (cycles, counters) and ``clamp_counts``."""
    flags = np.broadcast_to(np.asarray(learn, dtype=bool), (pres.n,)).astype(np.int64)
    exe = build(cfg, build_root)
    M, K = cfg.n_targets, cfg.n_synapses
    with tempfile.TemporaryDirectory(prefix="cuneate-learning-") as tmp:
        tmp = Path(tmp)
        (tmp / "schedule.bin").write_bytes(_schedule(cfg, pres, flags))
        cmd = [str(exe), str(tmp / "schedule.bin"), str(tmp)]
        if snapshot_every:
            cmd += ["--snap", str(int(snapshot_every))]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise HarnessError(f"learning harness failed ({proc.returncode}): "
                               f"{proc.stderr.strip()}")
        summary = json.loads((tmp / "summary.json").read_text())
        sp = np.fromfile(tmp / "spikes.bin", dtype="<i8").reshape(-1, 3)
        ws = np.fromfile(tmp / "weights.bin", dtype="<i8").reshape(-1, M, K)
    counts = np.zeros((pres.n, M), np.int64)
    inside = sp[:, 1] < pres.window_ticks
    np.add.at(counts, (sp[inside, 0], sp[inside, 2]), 1)
    clamps = dict(zip(CLAMP_KINDS, summary.pop("clamp_counts")))
    for k, want in (("tick_count", pres.n * pres.n_ticks), ("learn_count", pres.n)):
        if summary[k] != want:
            raise HarnessError(f"the layer counted {summary[k]} {k}, the schedule has {want}")
    if summary["overrun_count"] or summary["learn_overrun_count"] or summary["hazard_count"]:
        raise HarnessError(f"the layer reported overruns or hazards: {summary}")
    return {"spike_pres": sp[:, 0].copy(), "spike_tick": sp[:, 1].copy(),
            "spike_cn": sp[:, 2].copy(), "counts": counts, "weights": ws[-1],
            "snapshots": list(ws[:-1]), "summary": summary, "clamp_counts": clamps}
