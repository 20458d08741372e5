"""Configuration of the on-chip afferent -> cuneate network: an afferent Izhikevich core and a
coincidence detector on one tick (see :mod:`cuneate.hdl.network.core` for the link and its
latency)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..coincidence.config import CoincidenceConfig
from ..izhikevich.config import PIPELINE_DEPTH, IzhikevichConfig, min_neurons
from ..lib.config import ConfigError, check_tick_source
from ..lib.fixed import QFormat

__all__ = ["NetworkConfig", "ConfigError", "POPULATIONS", "SWEEP_EXTRA", "AFFERENT_OPTIONS"]

POPULATIONS = ("afferent", "cuneate")
#: cycles from ``go`` to a sweep's ``sweep_done`` beyond one per afferent (pipeline and flags)
SWEEP_EXTRA = PIPELINE_DEPTH + 3
#: keywords of the afferent core a network takes beside its own settings
AFFERENT_OPTIONS = ("current_format", "rounding")


@dataclass
class NetworkConfig:
    """An afferent core and a coincidence detector on one tick.

    Parameters
    ----------
    n_afferents
        Afferent neurons on the core (>= the core's pipeline depth, 5).
    detector
        Constructor keywords of :class:`~cuneate.hdl.coincidence.CoincidenceConfig` (its clock and
        tick settings are the network's).
    first_source
        Detector source ``s`` is afferent neuron ``first_source + s``.
    afferent_param_sets, afferent_sets
        Izhikevich parameter sets of the afferents and each afferent's set (default RS).
    clock_hz, update_hz, tick_source
        One clock and one tick for both blocks.
    cuneate_fifo_depth
        Depth of the cuneate spike FIFO on the output stream.
    afferent_options
        More keywords of the afferent core (:data:`AFFERENT_OPTIONS`: its current format, as
        ``[int_bits, frac_bits]``, and rounding), as a scene's core has them.
    """

    n_afferents: int = 8
    detector: dict = field(default_factory=dict)
    first_source: int = 0
    afferent_param_sets: tuple = ("RS",)
    afferent_sets: list | None = None
    clock_hz: float = 40e6
    update_hz: float = 16e3
    tick_source: str = "internal"
    cuneate_fifo_depth: int = 16
    afferent_options: dict = field(default_factory=dict)

    def __post_init__(self):
        check_tick_source(self.tick_source)
        N = self.n_afferents
        if not isinstance(N, (int, np.integer)) or N < min_neurons():
            raise ConfigError(f"n_afferents must be an integer >= {min_neurons()} (the core's "
                              f"smallest: its pipeline depth + 1), got {N!r}")
        det = dict(self.detector)
        for k in ("clock_hz", "update_hz", "tick_source"):
            if k in det:
                raise ConfigError(f"detector.{k} is the network's own setting; give it to the "
                                  f"network")
        try:
            self.det = CoincidenceConfig(**det, clock_hz=self.clock_hz,
                                         update_hz=self.update_hz, tick_source="external")
        except ConfigError as exc:
            raise ConfigError(f"network detector refused: {exc}") from None
        S, F = self.det.n_sources, self.first_source
        if not isinstance(F, (int, np.integer)) or F < 0 or F + S > N:
            raise ConfigError(f"the detector's {S} sources from afferent {F!r} on do not fit "
                              f"the core's {N} afferents (source s is afferent first_source + "
                              f"s)")
        sets = [0] * N if self.afferent_sets is None else list(self.afferent_sets)
        opts = dict(self.afferent_options)
        bad = sorted(set(opts) - set(AFFERENT_OPTIONS))
        if bad:
            raise ConfigError(f"afferent_options: {bad[0]!r} is not an afferent core option "
                              f"(those are: {', '.join(AFFERENT_OPTIONS)})")
        if isinstance(opts.get("current_format"), (list, tuple)):
            opts["current_format"] = QFormat(*opts["current_format"])
        try:
            self.core = IzhikevichConfig(
                n_neurons=N, clock_hz=self.clock_hz, update_hz=self.update_hz,
                param_sets=tuple(self.afferent_param_sets), neuron_sets=sets,
                tick_source="external", spike_fifo_depth=max(16, 2 * N), **opts)
        except ConfigError as exc:
            raise ConfigError(f"network afferent core refused: {exc}") from None
        if not isinstance(self.cuneate_fifo_depth, (int, np.integer)) or \
                self.cuneate_fifo_depth < self.det.n_targets:
            raise ConfigError(f"cuneate_fifo_depth must be an integer >= n_targets "
                              f"({self.det.n_targets})")
        self.dt_ms = 1000.0 / self.update_hz
        self.cycles_per_tick = self.core.cycles_per_tick
        # a tick is taken once the previous sweep is done and the detector idle
        self.cycles_needed = max(N + SWEEP_EXTRA, self.det.cycles_needed) + 2
        if self.cycles_needed > self.cycles_per_tick:
            raise ConfigError(f"the network needs {self.cycles_needed} cycles per tick "
                              f"({N} afferents, detector {self.det.cycles_needed}); "
                              f"{self.clock_hz:g} Hz / {self.update_hz:g} Hz gives "
                              f"{self.cycles_per_tick}")
        self.tick_width = self.core.sweep_number_width

    @property
    def n_sources(self) -> int:
        return self.det.n_sources

    @property
    def n_targets(self) -> int:
        return self.det.n_targets

    def to_kwargs(self) -> dict:
        det = self.det.to_kwargs()
        for k in ("clock_hz", "update_hz", "tick_source"):
            det.pop(k)
        return {"n_afferents": int(self.n_afferents), "detector": det,
                "first_source": int(self.first_source),
                "afferent_param_sets": [p if isinstance(p, str) else dict(p)
                                        for p in self.afferent_param_sets],
                "afferent_sets": list(self.core.neuron_sets), "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "tick_source": self.tick_source,
                "cuneate_fifo_depth": int(self.cuneate_fifo_depth),
                "afferent_options": {"current_format": [self.core.I.int_bits,
                                                        self.core.I.frac_bits],
                                     "rounding": self.core.rounding}}

    def latency(self) -> dict:
        return {
            "afferent_update_to_stamp_ticks": 1,
            "afferent_update_to_input_sum_ticks": "1 + delay[t, s]",
            "afferent_update_to_psp_onset_ticks": "2 + delay[t, s]",
            "fetch_to_detector_event_cycles": PIPELINE_DEPTH + 1,
            "text": "the update of afferent s in sweep k is stamped with detector tick k + 1, "
                    "enters target t's input sum at tick k + 1 + delay[t, s] and first changes "
                    "its PSP current at tick k + 2 + delay[t, s]",
        }

    def to_dict(self) -> dict:
        core = self.core.to_dict()
        return {"block": "AfferentCuneateNetwork", "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "dt_ms": self.dt_ms,
                "tick_source": self.tick_source, "cycles_per_tick": self.cycles_per_tick,
                "cycles_needed": self.cycles_needed, "n_afferents": self.n_afferents,
                "first_source": self.first_source,
                "n_sources": self.n_sources, "n_targets": self.n_targets,
                "populations": list(POPULATIONS), "out_tick_bits": self.tick_width,
                "latency": self.latency(),
                "afferent_core": {k: core[k] for k in ("formats", "param_sets", "constants",
                                                       "proven_range", "clamps")
                                  if k in core},
                "detector": self.det.to_dict(),
                "multipliers": 4 + self.det.to_dict()["multipliers"]}
