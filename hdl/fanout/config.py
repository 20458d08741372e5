"""Configuration of the channel fan-out: formats derived, bad input refused.

:class:`FanoutConfig` holds what :class:`cuneate.hdl.fanout.ChannelFanout` is built from: a
table with one entry per afferent (its channel, gain, rectification and optional threshold
gate) that turns ``n_channels`` sensor samples into ``n_neurons`` currents, per afferent::

    r   = rectify(s[channel])                    none | positive: max(s, 0) | abs: |s|
    p   = r * g                                  full width (gain in a shared-exponent format)
    I   = clamp(round(p * 2**-shift))            flagged and counted when it acts
    I   = 0 where the afferent is gated and s < theta

It derives:

* the sample format (``sample_width`` bits holding ``[-sample_max, sample_max]``);
* the gains as constants of ``gain_width`` bits sharing one exponent (the largest gain
  normalized), each with its representation error;
* thresholds as raw samples, rounded up, so that ``s_raw >= theta_raw`` holds exactly when the
  quantized sample is at or above the threshold (the gate of the golden model on the same
  sample, no error of its own);
* the table entry (channel, gain, threshold, mode bits) and its packing;
* the proven range of the rounded product, so the current clamp is built only where it can act;
* the one-sample bound of the fixed current against golden on the same quantized sample
  (:meth:`FanoutConfig.golden_bound`) and against the unquantized sample
  (:meth:`FanoutConfig.sample_bound`).

Refused at construction, one line each: a channel index outside ``0 .. n_channels - 1``, a
non-finite gain or one whose product with the largest sample exceeds float64 (every finite
product is exact: a gain of 1e18 clamps, flagged), a gain whose representation error exceeds ``max_gain_error``, a
threshold outside the sample range, an unknown rectification, a table larger than the block
RAM of the largest supported FPGA, and a run of ``n_neurons + LATENCY`` cycles that does not fit
one sample period at ``clock_hz``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Sequence

import numpy as np

from ...golden.fanout import RECTIFY
from ..lib.config import (MAX_BLOCK_RAM_BITS, ConfigError, check_rounding, refusing,
                          shared_exponent)
from ..lib.fixed import QFormat

__all__ = ["FanoutConfig", "ConfigError", "CLAMP_KINDS", "LATENCY", "MAX_TABLE_BITS",
           "check_table_size",
           "RECTIFY"]

#: the clamps that can act: the current below / above its format
CLAMP_KINDS = ("current_low", "current_high")
#: cycles from issuing an afferent's table read to its current on ``i_wr_*``
LATENCY = 5
#: the most table bits a fan-out may hold: the block RAM of the largest supported FPGA
MAX_TABLE_BITS = MAX_BLOCK_RAM_BITS


def check_table_size(n_neurons: int, n_channels: int, gain_width: int = 18,
                     sample_width: int = 16) -> int:
    """The table bits of ``n_neurons`` entries (channel index, gain, threshold, mode, gate), or
    a :class:`ConfigError` when no supported FPGA holds them: cheap, so a command checks it
    before building a table of that size."""
    entry = max(1, (int(n_channels) - 1).bit_length()) + gain_width + sample_width + 3
    bits = int(n_neurons) * entry
    if bits > MAX_TABLE_BITS:
        raise ConfigError(f"the fan-out table of {n_neurons} afferents needs {bits} bits; "
                          f"the largest supported FPGA holds {MAX_TABLE_BITS}")
    return bits


@dataclass
class FanoutConfig:
    """A channel fan-out: ``n_neurons`` afferents, each listening to one of ``n_channels``.

    Parameters
    ----------
    n_channels
        Channels (gratings, or a grating's band-passed signal) the host streams.
    channel
        Per afferent, the channel it listens to.
    gain
        Per afferent, its current per sample unit (mV/ms per unit); negative allowed.
    rectify
        One of ``none``, ``positive``, ``abs``, or one per afferent.
    threshold
        ``None`` (no gate), or per afferent the sample below which its current is 0 (``None``
        or ``nan`` in the list: that afferent has no gate).
    sample_width, sample_max
        The samples' format: the signed format of ``sample_width`` bits with the most fraction
        bits that holds ``[-sample_max, sample_max]``.
    current_format
        The currents' format: the fed core's current format (default the Izhikevich core's).
    gain_width, max_gain_error
        Width of the gain constants and the largest accepted relative error of a non-zero gain.
    rounding
        ``nearest`` or ``truncate``, for the product's dropped bits.
    clock_hz, sample_hz
        The clock and the channel sample rate: a run must fit one sample period.
    """

    n_channels: int
    channel: Sequence[int]
    gain: Sequence[float]
    rectify: object = "none"
    threshold: Sequence[float | None] | None = None
    sample_width: int = 16
    sample_max: float = 512.0
    current_format: QFormat = QFormat(10, 8)
    gain_width: int = 18
    max_gain_error: float = 1e-3
    rounding: str = "nearest"
    clock_hz: float = 40e6
    sample_hz: float = 1e3

    S: QFormat = field(init=False, repr=False)
    I: QFormat = field(init=False, repr=False)

    def __post_init__(self):
        with refusing("channel fan-out"):
            self._derive()

    # ------------------------------------------------------------------------------------------
    def _derive(self):
        C = self.n_channels
        if not isinstance(C, (int, np.integer)) or C < 1:
            raise ConfigError(f"n_channels must be an integer >= 1, got {C!r}")
        ch = np.asarray(self.channel)
        if ch.ndim != 1 or ch.size < 1 or not np.issubdtype(ch.dtype, np.integer):
            raise ConfigError("channel must list one integer channel index per afferent")
        bad = np.flatnonzero((ch < 0) | (ch >= C))
        if bad.size:
            raise ConfigError(f"afferent {bad[0]} listens to channel {int(ch[bad[0]])}, outside "
                              f"0 .. {C - 1}")
        N = self.n_neurons = int(ch.size)
        self.channels_ = tuple(int(x) for x in ch)
        g = np.asarray(self.gain, dtype=np.float64)
        if g.shape != (N,):
            raise ConfigError(f"gain has {g.size} entries for {N} afferents")
        if not np.all(np.isfinite(g)):
            raise ConfigError(f"the gain of afferent {int(np.flatnonzero(~np.isfinite(g))[0])} "
                              f"is not finite")
        modes = [self.rectify] * N if isinstance(self.rectify, str) else list(self.rectify)
        if len(modes) != N:
            raise ConfigError(f"rectify has {len(modes)} entries for {N} afferents")
        for i, m in enumerate(modes):
            if m not in RECTIFY:
                raise ConfigError(f"afferent {i}: unknown rectify {m!r}; known: "
                                  f"{', '.join(RECTIFY)}")
        self.modes_ = tuple(RECTIFY.index(m) for m in modes)
        check_rounding(self.rounding)
        if not (isinstance(self.sample_width, int) and 2 <= self.sample_width <= 32):
            raise ConfigError(f"sample_width must be 2 .. 32 bits, got {self.sample_width!r}")
        if not (isinstance(self.gain_width, int) and 2 <= self.gain_width <= 27):
            raise ConfigError(f"gain_width must be 2 .. 27 bits, got {self.gain_width!r}")
        if not (math.isfinite(self.sample_max) and self.sample_max > 0):
            raise ConfigError(f"sample_max must be > 0, got {self.sample_max!r}")
        self.S = QFormat.for_range(-self.sample_max, self.sample_max, self.sample_width)
        self.I = self.current_format
        big = int(np.argmax(np.abs(g)))
        if not math.isfinite(float(g[big]) * self.S.min_value):
            raise ConfigError(f"the gain of afferent {big}, {float(g[big]):g}, times the "
                              f"largest sample {-self.S.min_value:g} exceeds float64 (the "
                              f"golden model's numbers): the gain must be below "
                              f"{np.finfo(np.float64).max / -self.S.min_value:.4g}")
        self.gains_ = shared_exponent("gain", [float(x) for x in g], self.gain_width,
                                      max_rel_error=self.max_gain_error)
        self.gain_frac = self.gains_[0].frac_bits
        self._thresholds(N)
        self.shift = self.S.frac_bits + self.gain_frac - self.I.frac_bits
        # the rectified sample (|min| needs one bit more) and the full product, as registered
        self.r_width = self.S.width + 1
        p_width = self.p_width = self.r_width + self.gain_width
        if self.shift >= p_width:
            raise ConfigError(f"every current would round to 0: the product of a {self.S} "
                              f"sample and the gains ({self.gain_width} bits, largest "
                              f"{max(abs(float(x)) for x in g):g}) drops {self.shift} of its "
                              f"{p_width} bits to reach {self.I}")
        self._ranges()
        self.chan_bits = max(1, (C - 1).bit_length())
        self.neuron_bits = max(1, (N - 1).bit_length())
        self.entry_fields = (("channel", self.chan_bits), ("gain", self.gain_width),
                             ("theta", self.S.width), ("mode", 2), ("gated", 1))
        self.entry_width = sum(w for _, w in self.entry_fields)
        check_table_size(N, C, self.gain_width, self.S.width)
        self.cycles_per_run = N + LATENCY
        budget = self.clock_hz / self.sample_hz
        if self.cycles_per_run > budget:
            raise ConfigError(f"a fan-out run of {N} afferents takes {self.cycles_per_run} "
                              f"cycles; one sample at {self.sample_hz:g} Hz has {budget:g} at "
                              f"{self.clock_hz:g} Hz")

    def _thresholds(self, N: int):
        th = self.threshold
        if th is None:
            th = [None] * N
        th = [None if x is None or (isinstance(x, float) and math.isnan(x)) else float(x)
              for x in th]
        if len(th) != N:
            raise ConfigError(f"threshold has {len(th)} entries for {N} afferents")
        raw = []
        for i, x in enumerate(th):
            if x is None:
                raw.append(0)
                continue
            if not self.S.contains(x):
                raise ConfigError(f"afferent {i}: threshold {x:g} is outside the sample format "
                                  f"{self.S} [{self.S.min_value:g}, {self.S.max_value:g}]")
            r = math.ceil(math.ldexp(x, self.S.frac_bits))   # s_raw >= r  <=>  s >= x
            raw.append(min(r, self.S.max_raw))
        self.thresholds_ = tuple(th)
        self.theta_raw = tuple(raw)
        self.gated_ = tuple(x is not None for x in th)

    def _ranges(self):
        S = self.S
        r_lo = min([S.min_raw if m == 0 else 0 for m in self.modes_])
        r_hi = max([S.max_raw if m != 2 else -S.min_raw for m in self.modes_])
        gr = [c.raw for c in self.gains_]
        corners = [a * b for a in (r_lo, r_hi) for b in (min(gr), max(gr))]
        p_lo, p_hi = min(corners), max(corners)
        self.r_bounds = (r_lo, r_hi)
        self.p_bounds = (p_lo, p_hi)
        sh = self.shift
        carry = 1 if self.rounding == "nearest" else 0      # the first dropped bit
        self.i_bounds = ((p_lo >> sh, (p_hi >> sh) + carry) if sh > 0
                         else (p_lo << -sh, p_hi << -sh))
        self.can_clamp = not (self.I.min_raw <= self.i_bounds[0]
                              and self.i_bounds[1] <= self.I.max_raw)

    # ------------------------------------------------------------------------------------------
    def to_kwargs(self) -> dict:
        """The constructor's arguments as JSON values (``current_format`` as ``[int_bits,
        frac_bits]``); :meth:`from_kwargs` rebuilds the configuration."""
        return {"n_channels": int(self.n_channels), "channel": list(self.channels_),
                "gain": [float(x) for x in self.gain],
                "rectify": [RECTIFY[m] for m in self.modes_],
                "threshold": list(self.thresholds_), "sample_width": self.sample_width,
                "sample_max": float(self.sample_max),
                "current_format": [self.I.int_bits, self.I.frac_bits],
                "gain_width": self.gain_width, "max_gain_error": self.max_gain_error,
                "rounding": self.rounding, "clock_hz": self.clock_hz,
                "sample_hz": self.sample_hz}

    @classmethod
    def from_kwargs(cls, kw: dict) -> "FanoutConfig":
        kw = dict(kw)
        if isinstance(kw.get("current_format"), (list, tuple)):
            kw["current_format"] = QFormat(*kw["current_format"])
        return cls(**kw)

    def padded(self, n_neurons: int) -> "FanoutConfig":
        """The same fan-out feeding ``n_neurons`` afferents: the ones past its own listen to
        channel 0 with gain 0, no gate and positive rectification (current 0; the
        rectification keeps the proven current range the fan-out's own), as a core's idle
        neurons get (a core holds at least its fewest neurons)."""
        extra = int(n_neurons) - self.n_neurons
        if extra < 0:
            raise ConfigError(f"a fan-out of {self.n_neurons} afferents cannot be padded to "
                              f"{n_neurons}")
        if extra == 0:
            return self
        kw = self.to_kwargs()
        kw["channel"] += [0] * extra
        kw["gain"] += [0.0] * extra
        kw["rectify"] += ["positive"] * extra
        kw["threshold"] += [None] * extra
        return FanoutConfig.from_kwargs(kw)

    def first(self, n_neurons: int) -> "FanoutConfig":
        """The table of the first ``n_neurons`` afferents and the channels up to the last one
        they listen to (a board holding some trials of a scene: its afferents and channels
        come first), in the same sample format."""
        if not 1 <= n_neurons <= self.n_neurons:
            raise ConfigError(f"the first {n_neurons} of a fan-out of {self.n_neurons} "
                              f"afferents")
        kw = self.to_kwargs()
        for key in ("channel", "gain", "rectify", "threshold"):
            kw[key] = kw[key][:n_neurons]
        kw["n_channels"] = max(kw["channel"]) + 1
        return FanoutConfig.from_kwargs(kw)

    def written(self, core) -> SimpleNamespace:
        """What the host writes to the fan-out in front of ``core``, as the host's driver and
        transport see a core's currents: ``n_neurons`` values (the channels) in the format
        ``I`` (the sample format), at the core's update rate and rounding, with no accepted
        range of their own."""
        return SimpleNamespace(n_neurons=self.n_channels, I=self.S, update_hz=core.update_hz,
                               rounding=core.rounding, current_range=None)

    def table(self) -> list[int]:
        """The table's words, one per afferent, fields packed from the LSB in the order of
        :attr:`entry_fields`."""
        words = []
        for n in range(self.n_neurons):
            fields = (self.channels_[n], self.gains_[n].raw, self.theta_raw[n], self.modes_[n],
                      int(self.gated_[n]))
            word, pos = 0, 0
            for raw, (_, w) in zip(fields, self.entry_fields):
                word |= (int(raw) & ((1 << w) - 1)) << pos
                pos += w
            words.append(word)
        return words

    def golden_bound(self, samples) -> np.ndarray:
        """Per afferent, the largest ``|I_fixed - I_golden|`` for the quantized samples
        ``samples`` (float, ``(..., n_channels)``) where the clamp does not act: the gain's
        representation error times the rectified sample, plus the rounding of the product
        (half an LSB of the current to nearest, one LSB truncating, none when no bit is
        dropped), widened by ``1e-9`` relative and a few float64 ulps of ``|g r|`` for the
        float64 evaluation of both sides (the bound is reached: the gain error and the
        rounding can add up to it exactly)."""
        x = np.asarray(samples, dtype=np.float64)[..., list(self.channels_)]
        modes = np.asarray(self.modes_)
        r = np.where(modes == 1, np.maximum(x, 0), np.where(modes == 2, np.abs(x), x))
        dg = np.abs(np.array([c.abs_error for c in self.gains_]))
        rnd = 0.0 if self.shift <= 0 else (0.5 if self.rounding == "nearest" else 1.0)
        g = np.abs(np.asarray(self.gain, dtype=np.float64))
        return (np.abs(r) * dg + rnd * self.I.lsb) * (1 + 1e-9) + 4e-16 * g * np.abs(r)

    def sample_bound(self, samples) -> np.ndarray:
        """:meth:`golden_bound` plus the sample's own quantization (half an LSB of the sample times
        the gain, rectification and gate being 1-Lipschitz away from the threshold): the bound
        against golden on the unquantized sample, away from a gate's threshold (within half a
        sample LSB of it the gate may decide either way)."""
        return self.golden_bound(samples) + 0.5 * self.S.lsb * np.abs(
            np.asarray(self.gain, dtype=np.float64))

    def to_dict(self) -> dict:
        return {"block": "channel_fanout", "n_channels": self.n_channels,
                "n_neurons": self.n_neurons, "sample_format": self.S.to_dict(),
                "current_format": self.I.to_dict(), "gain_frac_bits": self.gain_frac,
                "gain_width": self.gain_width, "shift": self.shift,
                "rounding": self.rounding, "latency": LATENCY,
                "cycles_per_run": self.cycles_per_run, "entry_width": self.entry_width,
                "table_bits": self.n_neurons * self.entry_width,
                "current_clamp_built": self.can_clamp,
                "max_gain_rel_error": max(abs(c.rel_error) for c in self.gains_),
                "clock_hz": self.clock_hz, "sample_hz": self.sample_hz}
