"""The channel fan-out's bit-exact integer model: :class:`FanoutTwin`."""

from __future__ import annotations

import numpy as np

from ..lib.fixed import check_int64, store_raw, tally_clamps
from .config import CLAMP_KINDS, FanoutConfig
from .datapath import product, rectify_gate, to_current

__all__ = ["FanoutTwin"]


class FanoutTwin:
    """The fan-out's channel memory and table, run with the RTL's stage functions.

    :meth:`write` / :meth:`write_samples` set channel samples (raw / real); :meth:`run` turns
    the channel memory into every afferent's raw current, counting the clamps that act
    (``clamp_counts`` per kind of :data:`~cuneate.hdl.fanout.config.CLAMP_KINDS`, sticky bits in
    ``clamp_sticky``) as the RTL's counters do.
    """

    def __init__(self, cfg: FanoutConfig):
        self.cfg = cfg
        self.samples = np.zeros(cfg.n_channels, dtype=np.int64)
        self.channel = np.asarray(cfg.channels_, dtype=np.int64)
        self.gain = np.array([c.raw for c in cfg.gains_], dtype=np.int64)
        self.theta = np.asarray(cfg.theta_raw, dtype=np.int64)
        self.mode = np.asarray(cfg.modes_, dtype=np.int64)
        self.gated = np.asarray(cfg.gated_, dtype=bool)
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}
        self.clamp_sticky = 0
        self.runs = 0

    def write(self, channel: int, raw: int) -> None:
        """One channel write, raw in the sample format (as the RTL's ``ch_wr_data``)."""
        if not self.cfg.S.min_raw <= int(raw) <= self.cfg.S.max_raw:
            raise ValueError(f"raw sample {raw} is outside {self.cfg.S}")
        self.samples[int(channel)] = int(raw)

    def write_samples(self, values) -> np.ndarray:
        """Quantize real samples of every channel (saturating, as the host driver does) into
        the channel memory; returns the raw samples."""
        return store_raw(self.samples, self.cfg.S, np.asarray(values, dtype=np.float64))

    def run(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One run: ``(currents, below, above)``, raw currents and the clamp flags per
        afferent."""
        s = self.samples[self.channel]
        r = rectify_gate(s, self.mode, self.gated, self.theta)
        p = product(r, self.gain)
        check_int64("fan-out product", p)
        i, below, above = to_current(self.cfg, p)
        tally_clamps(self, CLAMP_KINDS, (int(np.sum(below)), int(np.sum(above))))
        self.runs += 1
        return np.asarray(i, dtype=np.int64), np.asarray(below), np.asarray(above)
