"""An afferent scene's channels and its fan-out table (``hardware.fanout = true``): the host
streams one sample per channel and sample period, the chip turns them into every afferent's
current.

A channel is a grating of a trial as one kind of afferent takes it: its Bragg shift in pm
(``shift``, what SA afferents read) or that shift band-passed by the front end's filter
(``band``, FA afferents; the filter runs on the host, one state per channel). Each afferent
listens to one channel with the gain of its encoding per pm (``gain / unit_pm``), FA
afferents with the front end's rectification, SA afferents gated at their threshold (pm).
Outside a trial's loading window (``frontend.window = "loading"``) its channels carry 0, so
every current is 0 as the host-side front end makes it.

Engines (:func:`fanout_scene_engines`): those registered for the fan-out in front of a block
(:data:`~cuneate.sim.fanout.engines.FRONT`): ``fixed`` runs the fan-out twin in front of the
Izhikevich twin (:class:`~cuneate.sim.fanout.engines.FanoutTransport`), ``board`` and ``axi``
the fan-out on chip in front of the block behind their face; and ``golden``, which integrates
the float currents as without the fan-out, so the fixed engines' difference from golden
includes the samples' quantization (the fan-out's bound:
:meth:`~cuneate.hdl.fanout.FanoutConfig.sample_bound`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...hdl.fanout import FanoutConfig
from ..engines.engine import BlockEngine
from ..engines.registry import ENGINES, block_engines, engine_for, refuse_engines_outside
from ..host.driver import FbgDriver
from ..host.transport import Transport
from .engines import FRONT, FanoutTransport

__all__ = ["ChannelPlan", "channel_plan", "scene_fanout", "check_fanout_engines",
           "fanout_transport", "FanoutTransport", "fanout_scene_engines"]


def fanout_scene_engines() -> tuple[str, ...]:
    """The engines that run a scene's channel fan-out, in :data:`ENGINES` order: those
    registered for the fan-out in front of a block, and golden (it needs none: it integrates
    the float currents)."""
    front = block_engines(FRONT)
    return tuple(e for e in ENGINES if e == "golden" or e in front)


@dataclass
class ChannelPlan:
    """The channels a scene streams and the fan-out that feeds its afferents.

    ``channels``: ``(trial, grating, kind)`` per channel; ``samples``: their values (pm) per
    sample ``(n_samples, n_channels)``; ``raw``: the same in the fan-out's sample format;
    ``config``: the :class:`~cuneate.hdl.fanout.FanoutConfig`; ``driver``: the host driver
    that streams the raw samples (same sample rate and latency as the scene's)."""

    channels: list
    samples: np.ndarray
    raw: np.ndarray
    config: FanoutConfig
    driver: FbgDriver

    def describe(self) -> dict:
        kinds = [k for _, _, k in self.channels]
        return self.config.to_dict() | {
            "channels_shift": kinds.count("shift"), "channels_band": kinds.count("band"),
            "afferents_per_channel": round(self.config.n_neurons / len(self.channels), 2)}


def channel_plan(scene, neurons, traces, infos, core, drv: FbgDriver) -> ChannelPlan:
    """The scene's channels, their samples and the fan-out table for ``neurons`` (the
    afferents of the scene, in core order) feeding ``core``; ``drv`` is the scene's host
    driver (rates, latency). Refuses (``ConfigError``, one line) a table the fan-out cannot
    hold."""
    keys: dict = {}
    first: dict = {}                    # channel -> the first afferent listening to it
    channel, gain, rectify, threshold = [], [], [], []
    for i, (t, g, e) in enumerate(zip(neurons.trial, neurons.grating, neurons.encoding)):
        key = (t, g, "band" if e.mode == "FA" else "shift")
        channel.append(keys.setdefault(key, len(keys)))
        first.setdefault(key, i)
        gain.append(e.gain / e.unit_pm)
        rectify.append(e.rectify if e.mode == "FA" else "none")
        threshold.append(e.threshold_pm if e.mode == "SA" else None)
    chans = list(keys)
    filt = next((e.filter for e in neurons.encoding if e.mode == "FA"), None)
    # the shifts as the host driver holds their gaps, a channel from its first afferent's
    held, _ = drv.fill_gaps(np.stack([traces[t][:, g] for t, g in zip(neurons.trial,
                                                                      neurons.grating)], axis=1))
    shifts = held[:, [first[k] for k in chans]] * 1000.0
    samples = shifts.copy()
    band = [i for i, (_, _, k) in enumerate(chans) if k == "band"]
    if band:
        samples[:, band] = filt.apply(shifts[:, band])
    if scene["frontend"]["window"] == "loading":
        t_ms = np.arange(samples.shape[0]) * 1000.0 / scene["sensor"]["sample_rate_hz"]
        for i, (t, _, _) in enumerate(chans):
            outside = (t_ms < scene["stimulus"]["contact_ms"]) | (t_ms > infos[t]["stop_ms"])
            samples[outside, i] = 0.0
    hw = scene["hardware"]
    peak = float(np.max(np.abs(samples))) if samples.size else 0.0
    cfg = FanoutConfig(n_channels=len(chans), channel=channel, gain=gain, rectify=rectify,
                       threshold=threshold, sample_width=hw["fanout_sample_bits"],
                       sample_max=max(peak, 1.0), current_format=core.I,
                       rounding=core.rounding, clock_hz=hw["clock_hz"],
                       sample_hz=scene["sensor"]["sample_rate_hz"])
    cdrv = FbgDriver(cfg.written(core), [None] * cfg.n_channels, drv.fs_hz, drv.latency_ticks)
    return ChannelPlan(chans, samples, cfg.S.to_raw(samples), cfg, cdrv)


def scene_fanout(scene, neurons, traces, infos, core, drv, engines, blocks) -> ChannelPlan | None:
    """The scene's :class:`ChannelPlan` when it asks for the fan-out (``hardware.fanout``),
    its description appended to ``blocks``; else ``None``. Refuses an engine that does not
    run the fan-out."""
    if not scene["hardware"]["fanout"]:
        return None
    check_fanout_engines(scene, engines)
    plan = channel_plan(scene, neurons, traces, infos, core, drv)
    blocks.append(plan.describe())
    return plan


def check_fanout_engines(scene, engines) -> None:
    """Refuse (one line) an engine of ``engines`` that does not run the scene's fan-out."""
    if not scene["hardware"]["fanout"]:
        return
    refuse_engines_outside(engines, fanout_scene_engines(), "hardware.fanout", "channel fan-out")


def fanout_transport(engine: str, plan: ChannelPlan, inner: BlockEngine, kw: dict) -> Transport:
    """The transport a scene streams its channels through on ``engine`` (``kw``: its
    options): the registry's fan-out in front of ``inner``, the engine's implementation of
    the block the fan-out feeds."""
    return engine_for(FRONT, engine, **kw).front(plan.config, inner)
