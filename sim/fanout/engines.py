"""The channel fan-out's engines: channel samples ``(n_runs, n_channels)`` in, the afferents'
currents ``(n_runs, n_neurons)`` out (mV/ms).

``golden`` evaluates :func:`~cuneate.golden.fanout.fanout_currents` on the samples as given;
``fixed`` quantizes them to the sample format (saturating, as the host does) and runs
:class:`~cuneate.hdl.fanout.FanoutTwin`; ``icarus`` and ``verilator`` run the same quantized
samples through the generated Verilog (the bench's ``engine`` test: channel writes through the
handshake, one run per sample).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...golden.fanout import RECTIFY, fanout_currents
from ...hdl.fanout import CLAMP_KINDS, FanoutConfig, FanoutTwin, fanout_verilog
from ..engines.registry import check_engine

__all__ = ["FanoutRun", "run_fanout", "FANOUT_ENGINES"]

FANOUT_ENGINES = ("golden", "fixed", "icarus", "verilator")


@dataclass
class FanoutRun:
    """What one engine computed: currents (mV/ms) per run and afferent, and the clamps that
    acted (``None`` for golden, which has none)."""

    engine: str
    currents: np.ndarray
    clamp_counts: dict | None = None
    figures: dict = field(default_factory=dict)


def run_fanout(engine: str, cfg: FanoutConfig, samples, build_dir: Path | None = None
               ) -> FanoutRun:
    """Run ``samples`` (real, ``(n_runs, n_channels)``) through the fan-out on ``engine``."""
    check_engine("fanout", engine)
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != cfg.n_channels:
        raise ValueError(f"samples must be (n_runs, {cfg.n_channels}), got shape {x.shape}")
    if engine == "golden":
        th = [np.nan if t is None else t for t in cfg.thresholds_]
        return FanoutRun(engine, fanout_currents(x, cfg.channels_, cfg.gain,
                                                 [RECTIFY[m] for m in cfg.modes_], th))
    raw = cfg.S.to_raw(x)
    if engine == "fixed":
        twin = FanoutTwin(cfg)
        out = np.empty((x.shape[0], cfg.n_neurons), dtype=np.int64)
        for k in range(x.shape[0]):
            twin.samples[:] = raw[k]
            out[k] = twin.run()[0]
        return FanoutRun(engine, cfg.I.to_float(out), dict(twin.clamp_counts))
    from ..engines.cocotb import run_engine_bench
    rep = run_engine_bench(engine, lambda lowered: fanout_verilog(cfg, lowered=lowered),
                           "channel_fanout", "fanout",
                           {"fanout": cfg.to_kwargs(), "samples": raw.tolist()}, build_dir)
    counts = dict(zip(CLAMP_KINDS, (rep["clamp_low_count"], rep["clamp_high_count"])))
    return FanoutRun(engine, cfg.I.to_float(np.asarray(rep["currents"], dtype=np.int64)),
                     counts, {"cycles": rep["cycles"], "wall_s": rep["wall_s"]})
