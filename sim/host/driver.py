"""The host driver: FBG wavelength shifts in, core currents out, spikes back.

:class:`FbgDriver` applies the front end of each neuron's afferent (:class:`AfferentEncoding`:
FA = band-pass filter, gain, rectification; SA = thresholded gain), quantizes the currents to
the core's current format (every saturation counted and reported), and streams them to a core
through a :class:`~cuneate.sim.host.transport.Transport`, then reads the spikes back and checks that
nothing was lost.

Alignment and latency
---------------------
Sensor samples arrive at ``fs`` (1 kHz); the core updates every neuron at ``update_hz``
(16 kHz), so each sample is held for ``R = update_hz / fs`` ticks (16; a whole number, refused
otherwise). Sample ``j`` (taken at ``t = j / fs``) is written for tick ``j R + L`` and is used by
every update of sweeps ``j R + L`` .. ``(j + 1) R + L - 1``; ``L = latency_ticks`` (default 0)
models the host's transport delay. Before tick ``L`` the currents are zero. A spike of sweep
``k`` is at ``(k + 1) dt`` (the golden convention), so with ``L = 0`` the first update that sees
sample ``j`` reports its spike at ``t_j + dt``. Samples whose tick falls past the end of the run
(the last ``L`` ticks' worth) are not sent and are counted (``samples_past_end``).

Only the neurons whose raw current changed are written (one contiguous span per sample), so a
held or repeated value costs nothing on a slow link.

Loss detection
--------------
After the run the transport's counters (one contract for every transport, read from the device
where it counts them: :data:`~cuneate.sim.host.transport.COUNTERS`) must show no frame lost or
damaged on a link, every write applied (``writes == sent``), every spike of the core's own
count received (``spikes == spikes_counted``) and no overflow, overrun or late write, else
:class:`~cuneate.sim.host.transport.TransportError` names what was lost
(:func:`~cuneate.sim.host.transport.check_counters`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from ...golden.encoders import sa_current
from ...golden.fbg import FbgFrontEnd, IIRFilter
from .transport import SpikeBatch, Transport, check_counters

__all__ = ["AfferentEncoding", "FbgDriver", "OnlineStream", "DriverRun", "GapError"]


class GapError(ValueError):
    """A sample is missing (NaN) and the driver was told not to hold over gaps."""


@dataclass(frozen=True)
class AfferentEncoding:
    """How one afferent turns ``d_lambda`` (nm) into a current (mV/ms).

    ``mode="FA"``: ``gain * rectify(filter(d_lambda / unit))``; ``mode="SA"``:
    ``gain * (d_lambda / unit)`` where ``d_lambda >= threshold``, else 0. ``unit_pm`` is the size
    of one unit of ``d_lambda`` as the gain expects it, in pm (10 pm for the published S = 180,
    see docs/scenes.md).
    """

    mode: str = "FA"
    gain: float = 180.0
    unit_pm: float = 10.0
    filter: IIRFilter | None = None
    rectify: str = "positive"
    threshold_pm: float = 0.0
    fs_hz: float = 1000.0

    def __post_init__(self):
        if self.mode not in ("FA", "SA"):
            raise ValueError(f"mode must be 'FA' or 'SA', got {self.mode!r}")
        if self.mode == "FA" and self.filter is None:
            raise ValueError("an FA afferent needs a filter")
        for k in ("gain", "unit_pm", "threshold_pm", "fs_hz"):
            v = getattr(self, k)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                    or not math.isfinite(v):
                raise ValueError(f"{k} must be a finite number, got {v!r}")
        if not self.unit_pm > 0:
            raise ValueError(f"unit_pm must be > 0, got {self.unit_pm!r}")
        if not self.fs_hz > 0:
            raise ValueError(f"fs_hz must be > 0, got {self.fs_hz!r}")
        if self.rectify not in ("positive", "abs", "none"):
            raise ValueError(f"rectify must be positive, abs or none, got {self.rectify!r}")

    def currents(self, d_lambda_nm: np.ndarray) -> np.ndarray:
        x = np.asarray(d_lambda_nm, dtype=np.float64) * (1000.0 / self.unit_pm)
        if self.mode == "SA":
            return sa_current(x, gain_K=self.gain,
                              threshold=self.threshold_pm / self.unit_pm)
        y = FbgFrontEnd(self.filter, 1.0, self.fs_hz).currents(x) * self.gain
        return self._rectify(y)

    def currents_online(self, d_lambda_nm: np.ndarray, state):
        """Like :meth:`currents` for one chunk ``(n, k)`` of a longer trace; ``state`` is the
        filter state returned by the previous chunk (``None`` for the first). Returns
        ``(currents, state)``; chunks fed in order give exactly :meth:`currents` of the whole."""
        x = np.asarray(d_lambda_nm, dtype=np.float64) * (1000.0 / self.unit_pm)
        if self.mode == "SA":
            return self.currents(d_lambda_nm), None
        f = self.filter
        f.require_stable()
        if state is None:
            state = np.zeros((max(f.a.size, f.b.size) - 1, x.shape[1]))
        y, state = scipy.signal.lfilter(f.b, f.a, x, axis=0, zi=state)
        return self._rectify(y * self.gain), state

    def _rectify(self, y):
        if self.rectify == "positive":
            y = np.maximum(y, 0.0)
        elif self.rectify == "abs":
            y = np.abs(y)
        return y


@dataclass
class DriverRun:
    """What a streamed run produced."""

    spikes: SpikeBatch
    n_ticks: int
    writes_sent: int
    words_sent: int
    saturations: dict
    counters: dict
    samples_past_end: int = 0
    gaps_held: int = 0
    info: dict = field(default_factory=dict)


class FbgDriver:
    """Host driver for one core.

    Parameters
    ----------
    config
        The core configuration (:class:`~cuneate.hdl.izhikevich.IzhikevichConfig`): its current
        format, accepted range and update rate.
    encodings
        One :class:`AfferentEncoding` per driven neuron (neurons ``first`` .. ``first + n - 1``).
    fs_hz
        Sample rate of the traces.
    latency_ticks
        Ticks between a sample's arrival and the first update that uses it (``L`` above).
    on_gap
        ``"error"`` (default): a NaN sample raises :class:`GapError` naming sample and channel;
        ``"hold"``: the previous sample is held and the gap counted (``gaps_held``).
    """

    def __init__(self, config, encodings, fs_hz: float = 1000.0, latency_ticks: int = 0,
                 first: int = 0, on_gap: str = "error"):
        self.cfg = config
        self.encodings = list(encodings)
        self.fs_hz = float(fs_hz)
        if not (math.isfinite(self.fs_hz) and self.fs_hz > 0):
            raise ValueError(f"fs_hz must be a finite rate > 0 Hz, got {fs_hz!r}")
        ratio = config.update_hz / self.fs_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"update rate {config.update_hz:g} Hz is not a whole multiple of "
                             f"the sample rate {self.fs_hz:g} Hz")
        self.hold_ticks = int(round(ratio))
        if int(latency_ticks) != latency_ticks or latency_ticks < 0:
            raise ValueError(f"latency_ticks must be an integer >= 0, got {latency_ticks!r}")
        self.latency_ticks = int(latency_ticks)
        if first < 0 or first + len(self.encodings) > config.n_neurons:
            raise ValueError(f"neurons {first}..{first + len(self.encodings) - 1} do not fit a "
                             f"core of {config.n_neurons}")
        self.first = first
        if on_gap not in ("error", "hold"):
            raise ValueError(f"on_gap must be 'error' or 'hold', got {on_gap!r}")
        self.on_gap = on_gap

    # ---------------------------------------------------------------- front end
    def fill_gaps(self, d_lambda_nm, offset: int = 0) -> tuple[np.ndarray, int]:
        kind = np.asarray(d_lambda_nm).dtype.kind
        if kind not in "iuf":
            what = {"c": "complex numbers (the imaginary part would be lost)",
                    "b": "booleans, not shifts"}.get(
                kind, f"values of type {np.asarray(d_lambda_nm).dtype}")
            raise ValueError(f"d_lambda holds {what}; give real shifts in nm")
        x = np.array(d_lambda_nm, dtype=np.float64)
        if x.ndim == 1:
            x = x[:, None]
        if x.ndim != 2 or x.shape[1] != len(self.encodings):
            raise ValueError(f"d_lambda must have shape (n_samples, {len(self.encodings)}), got "
                             f"{np.shape(d_lambda_nm)}")
        bad = ~np.isfinite(x)
        if not bad.any():
            return x, 0
        j, c = (int(v) for v in np.argwhere(bad)[0])
        if self.on_gap == "error" or bad[0].any():
            raise GapError(f"sample {j + offset} of channel {c} is missing ({x[j, c]!r}); "
                           f"{int(bad.sum())} missing sample(s) in all")
        for j in np.flatnonzero(bad.any(axis=1)):
            x[j, bad[j]] = x[j - 1, bad[j]]
        return x, int(bad.sum())

    def currents(self, d_lambda_nm) -> np.ndarray:
        """Float currents (mV/ms), shape ``(n_samples, n_neurons)``, before quantization."""
        x, _ = self.fill_gaps(d_lambda_nm)
        return self._currents(x)

    def _currents(self, x: np.ndarray) -> np.ndarray:
        out = np.empty_like(x)
        groups: dict = {}
        for i, e in enumerate(self.encodings):
            groups.setdefault(e, []).append(i)
        for e, cols in groups.items():
            out[:, cols] = e.currents(x[:, cols])
        return out

    def quantize(self, currents) -> tuple[np.ndarray, dict]:
        """Raw currents in the core's format and the saturation counts: ``format_low`` /
        ``format_high`` (outside the current format, saturated by the driver) and
        ``range_low`` / ``range_high`` (outside the accepted range, clamped and flagged by the
        core), each a number of (sample, neuron) values, plus the worst offenders."""
        cur = np.asarray(currents, dtype=np.float64)
        I = self.cfg.I
        lo, hi = self.cfg.current_range if self.cfg.current_range else (I.min_value,
                                                                        I.max_value)
        sat = {"format_low": int(np.count_nonzero(cur < I.min_value)),
               "format_high": int(np.count_nonzero(cur > I.max_value)),
               "range_low": int(np.count_nonzero(cur < lo)),
               "range_high": int(np.count_nonzero(cur > hi)),
               "min_mV_per_ms": float(cur.min()) if cur.size else 0.0,
               "max_mV_per_ms": float(cur.max()) if cur.size else 0.0,
               "format": str(I), "values": int(cur.size)}
        return I.to_raw(cur, rounding=self.cfg.rounding), sat

    def tick_of_sample(self, j) -> np.ndarray:
        """First tick at which sample ``j`` is in effect (``j R + L``)."""
        return np.asarray(j) * self.hold_ticks + self.latency_ticks

    def held(self, per_sample: np.ndarray, n_ticks: int | None = None) -> np.ndarray:
        """Per-tick values ``(n_ticks, n)`` of per-sample values under the driver's alignment
        (zero before the first sample's tick): what the golden engine integrates."""
        per_sample = np.asarray(per_sample)
        n_s = per_sample.shape[0]
        n_ticks = n_s * self.hold_ticks if n_ticks is None else n_ticks
        k = np.arange(n_ticks)
        j = (k - self.latency_ticks) // self.hold_ticks
        out = np.zeros((n_ticks,) + per_sample.shape[1:], dtype=per_sample.dtype)
        ok = (j >= 0) & (j < n_s)
        out[ok] = per_sample[j[ok]]
        return out

    # ---------------------------------------------------------------- streaming
    def stream(self, transport: Transport, d_lambda_nm, n_ticks: int | None = None,
               raw: np.ndarray | None = None) -> DriverRun:
        """Stream a whole ``d_lambda`` trace (or precomputed ``raw`` currents) through
        ``transport`` (already opened) and return the spikes with loss checks applied."""
        s = self.online(transport, n_ticks)
        if raw is None:
            s.feed(d_lambda_nm)
        else:
            s.feed_raw(raw)
        return s.finish(n_ticks)

    def online(self, transport: Transport, n_ticks: int | None = None) -> "OnlineStream":
        """A chunk-by-chunk stream for a live link (see :class:`OnlineStream`); ``n_ticks``
        caps the run (default: every received sample's hold)."""
        return OnlineStream(self, transport, n_ticks)


class OnlineStream:
    """Chunk-by-chunk streaming (a live interrogator feeding a board): the front end's filter
    state, the held value of a gap and the last written currents carry across chunks, so any
    split of a trace gives exactly the writes and spikes of :meth:`FbgDriver.stream`.

    Sample ``j``'s write (tick ``j R + L``) is sent once it is known to lie inside the run,
    i.e. once ``(j R + L) < received * R``; :meth:`finish` counts the samples left beyond the
    end (``samples_past_end``), runs the last ticks, collects and checks the counters.
    """

    def __init__(self, driver: FbgDriver, transport: Transport, n_ticks: int | None = None):
        self.d, self.tr = driver, transport
        self.limit = None if n_ticks is None else int(n_ticks)
        self.states: dict = {}
        self.last = None                   # last finite sample (for held gaps)
        self.pending: list[np.ndarray] = []
        self.received = 0                  # samples received
        self.next_j = 0                    # next sample whose write is due
        self.tick = 0
        self.prev = np.zeros(len(driver.encodings), dtype=np.int64)
        self.sent = self.words = self.gaps = 0
        self.sat: dict = {}

    def _count(self, sat: dict):
        if not self.sat:
            self.sat = dict(sat)
            return
        for k in ("format_low", "format_high", "range_low", "range_high", "values"):
            self.sat[k] += sat[k]
        self.sat["min_mV_per_ms"] = min(self.sat["min_mV_per_ms"], sat["min_mV_per_ms"])
        self.sat["max_mV_per_ms"] = max(self.sat["max_mV_per_ms"], sat["max_mV_per_ms"])

    def feed(self, d_lambda_nm) -> None:
        """Front end, quantization and writes for the next chunk ``(n, neurons)`` of samples."""
        x = np.array(d_lambda_nm, dtype=np.float64)
        if x.ndim == 1:
            x = x[:, None]
        if self.last is not None and self.d.on_gap == "hold":
            x, g = self.d.fill_gaps(np.concatenate([self.last[None, :], x]), self.received - 1)
            x = x[1:]
        else:
            x, g = self.d.fill_gaps(x, self.received)
        self.gaps += g
        if x.shape[0] == 0:
            return
        self.last = x[-1].copy()
        cur = np.empty_like(x)
        groups: dict = {}
        for i, e in enumerate(self.d.encodings):
            groups.setdefault(e, []).append(i)
        for e, cols in groups.items():
            cur[:, cols], self.states[e] = e.currents_online(x[:, cols], self.states.get(e))
        raw, sat = self.d.quantize(cur)
        self._count(sat)
        self.feed_raw(raw)

    def feed_raw(self, raw) -> None:
        """Writes for the next chunk of raw currents (already quantized)."""
        raw = np.asarray(raw, dtype=np.int64)
        if raw.ndim != 2 or raw.shape[1] != len(self.d.encodings):
            raise ValueError(f"raw currents must have shape (n, {len(self.d.encodings)}), got "
                             f"{raw.shape}")
        self.pending.extend(raw)
        self.received += raw.shape[0]
        horizon = self.received * self.d.hold_ticks
        self._send(horizon if self.limit is None else min(horizon, self.limit))

    def _send(self, horizon: int) -> None:
        d, tr = self.d, self.tr
        while self.pending:
            t = int(d.tick_of_sample(self.next_j))
            if t >= horizon:
                break
            row = self.pending.pop(0)
            self.next_j += 1
            changed = np.flatnonzero(row != self.prev)
            if not changed.size:
                continue
            a, b = int(changed[0]), int(changed[-1]) + 1
            if t > self.tick:
                tr.run(t - self.tick)
                self.tick = t
            tr.write_currents(t, d.first + a, row[a:b])
            self.sent += 1
            self.words += b - a
            self.prev = row

    def finish(self, n_ticks: int | None = None) -> DriverRun:
        """Run to ``n_ticks`` (default: every received sample's hold), collect, check."""
        if n_ticks is None:
            n_ticks = self.limit
        n_ticks = self.received * self.d.hold_ticks if n_ticks is None else int(n_ticks)
        self._send(n_ticks)
        past = len(self.pending)
        if n_ticks > self.tick:
            self.tr.run(n_ticks - self.tick)
            self.tick = n_ticks
        spikes = self.tr.collect()
        cnt = self.tr.counters()
        check_counters(self.tr, cnt, self.sent, len(spikes))
        return DriverRun(spikes, n_ticks, self.sent, self.words, self.sat, cnt, past,
                         self.gaps)
