"""The channel fan-out's engines: channel samples ``(n_runs, n_channels)`` in, the afferents'
currents ``(n_runs, n_neurons)`` out (mV/ms), as an
:class:`~cuneate.sim.engines.run.EngineRun` whose ``values`` hold them.

``golden`` evaluates :func:`~cuneate.golden.fanout.fanout_currents` on the samples as given;
``fixed`` quantizes them to the sample format (saturating, as the host does) and runs
:class:`~cuneate.hdl.fanout.FanoutTwin`; ``icarus`` and ``verilator`` run the same quantized
samples through the generated Verilog (the bench's ``engine`` test: channel writes through the
handshake, one run per sample).

The fan-out is also an adapter in front of another block (a scene that streams channels;
:func:`~cuneate.hdl.lib.payload.payload_spec`'s ``fanout``): its engines register for
:data:`FRONT` (:class:`FanoutFront`: raw channel samples in, the spikes of the block behind it
out, :func:`run_front`). ``fixed`` puts the fan-out's twin in front of the block's twin
(:class:`FanoutTransport`); ``board`` and ``axi`` (:mod:`cuneate.sim.engines.board`,
:mod:`cuneate.sim.engines.axi`) hold it on chip in front of the block behind their face.
"""

from __future__ import annotations

import time

import numpy as np

from ...golden.fanout import RECTIFY, fanout_currents
from ...hdl.fanout import CLAMP_KINDS, FanoutConfig, FanoutTwin, fanout_verilog
from ..engines.engine import BlockEngine
from ..engines.registry import engine_for, implements
from ..engines.run import EngineRun
from ..host.transport import Transport

__all__ = ["FanoutEngine", "run_fanout", "FRONT", "FanoutFront", "run_front",
           "FanoutTransport"]

#: The name the fan-out's engines register under as an adapter in front of another block.
FRONT = "fanout_front"


class FanoutEngine(BlockEngine):
    """The channel fan-out on one engine: :meth:`run` samples into afferent currents."""

    block = "fanout"

    def run(self, cfg: FanoutConfig, x: np.ndarray) -> EngineRun:
        """Real samples ``x`` ``(n_runs, n_channels)``: their currents, one row per run."""
        t0 = time.perf_counter()
        currents, counts, figures = self.currents(cfg, x)
        return EngineRun(self.name, 1000.0 / cfg.sample_hz, x.shape[0], None, counts, {},
                         time.perf_counter() - t0, figures, values=currents)

    def currents(self, cfg: FanoutConfig, x: np.ndarray):
        """``(currents (n_runs, n_neurons) mV/ms, clamp counts or None, figures)``."""
        raise NotImplementedError


@implements("fanout", "golden", speed=2e7)
class FanoutGolden(FanoutEngine):
    def currents(self, cfg, x):
        th = [np.nan if t is None else t for t in cfg.thresholds_]
        return fanout_currents(x, cfg.channels_, cfg.gain, [RECTIFY[m] for m in cfg.modes_],
                               th), None, {}


@implements("fanout", "fixed", speed=1e7)
class FanoutFixed(FanoutEngine):
    def currents(self, cfg, x):
        raw = cfg.S.to_raw(x)
        twin = FanoutTwin(cfg)
        out = np.empty((x.shape[0], cfg.n_neurons), dtype=np.int64)
        for k in range(x.shape[0]):
            twin.samples[:] = raw[k]
            out[k] = twin.run()[0]
        return cfg.I.to_float(out), dict(twin.clamp_counts), {}


@implements("fanout", "icarus", speed=5e3)
@implements("fanout", "verilator", speed=5e4)
class FanoutCocotb(FanoutEngine):
    def currents(self, cfg, x):
        rep = self.engine_bench(lambda lowered: fanout_verilog(cfg, lowered=lowered),
                                "channel_fanout",
                                {"fanout": cfg.to_kwargs(), "samples": cfg.S.to_raw(x).tolist()})
        counts = dict(zip(CLAMP_KINDS, (rep["clamp_low_count"], rep["clamp_high_count"])))
        return (cfg.I.to_float(np.asarray(rep["currents"], dtype=np.int64)), counts,
                {"cycles": rep["cycles"], "wall_s": rep["wall_s"]})


def run_fanout(engine: str, cfg: FanoutConfig, samples, build_dir=None) -> EngineRun:
    """Run ``samples`` (real, ``(n_runs, n_channels)``) through the fan-out on ``engine``."""
    impl = engine_for("fanout", engine, build_dir=build_dir)
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != cfg.n_channels:
        raise ValueError(f"samples must be (n_runs, {cfg.n_channels}), got shape {x.shape}")
    return impl.run(cfg, x)


class FanoutFront(BlockEngine):
    """The channel fan-out in front of another block on one engine: :meth:`front` the
    transport a scene streams its channels through, :meth:`run` raw channel samples into the
    spikes of the block behind it. By default the fan-out's twin stands in front of the
    block's engine's transport (:class:`FanoutTransport`)."""

    block = FRONT

    def front(self, fanout: FanoutConfig, inner: BlockEngine) -> Transport:
        """The transport of the fan-out ``fanout`` in front of ``inner`` (this engine's
        implementation of the block behind it), to be opened for that block's
        configuration."""
        return FanoutTransport(inner.transport(), fanout)

    def run(self, fanout: FanoutConfig, config, writes: dict, n_ticks: int,
            block: str = "izhikevich") -> EngineRun:
        """Raw channel samples ``writes`` (``{tick: [(first channel, raw samples), ...]}``)
        through ``fanout`` in front of ``block`` (configuration ``config``) for ``n_ticks``
        ticks, every counter of the transport contract checked: the spikes of the
        ``fanout.n_neurons`` neurons it feeds (no clamps seen: ``None``; the counters hold
        what the transport counted)."""
        inner = engine_for(block, self.name, build_dir=self.build_dir, progress=self.progress,
                           waves=self.waves)
        t0 = time.perf_counter()
        got, counters = self.stream(config, writes, n_ticks, self.front(fanout, inner))
        return EngineRun(self.name, config.dt_ms, n_ticks,
                         got.times_ms(config.dt_ms, fanout.n_neurons), None, None,
                         time.perf_counter() - t0, counters)


@implements(FRONT, "fixed", speed=2e6)
class FanoutFrontFixed(FanoutFront):
    """The fan-out's twin in front of the block's twin."""


def run_front(engine: str, fanout: FanoutConfig, config, writes: dict, n_ticks: int,
              block: str = "izhikevich", build_dir=None) -> EngineRun:
    """Raw channel samples through the fan-out in front of ``block`` on ``engine``
    (:meth:`FanoutFront.run`)."""
    return engine_for(FRONT, engine, build_dir=build_dir).run(fanout, config, writes, n_ticks,
                                                              block)


class FanoutTransport(Transport):
    """The fan-out twin in front of another transport (the ``fixed`` engine's twin): channel
    writes set the twin's samples, and each write is followed by a fan-out run whose currents
    go to ``inner`` for the same sweep, as :class:`~cuneate.hdl.link.LinkedTop` does
    on chip. The fan-out's clamp counts join the counters (``fanout_current_low`` /
    ``fanout_current_high``)."""

    def __init__(self, inner: Transport, fanout: FanoutConfig):
        self.inner, self.fanout = inner, fanout
        self.name = inner.name

    def open(self, config) -> None:
        self.twin = FanoutTwin(self.fanout)
        self.inner.open(config)

    def write_currents(self, tick: int, first: int, raw) -> None:
        raw = np.asarray(raw, dtype=np.int64)
        self.twin.samples[first:first + raw.size] = raw
        self.inner.write_currents(tick, 0, self.twin.run()[0])

    def run(self, n_ticks: int) -> None:
        self.inner.run(n_ticks)

    def collect(self):
        return self.inner.collect()

    def counters(self) -> dict[str, int]:
        return dict(self.inner.counters(), **{f"fanout_{k}": v
                                              for k, v in self.twin.clamp_counts.items()})

    def loss_detail(self, counters: dict) -> str:
        return self.inner.loss_detail(counters)

    def close(self) -> None:
        self.inner.close()

    def __getattr__(self, name):
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)      # sim_s, figures of the inner transport
