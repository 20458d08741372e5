"""Float64 reference of the channel fan-out: per-channel sensor samples -> per-afferent currents.

A few dozen gratings (channels) drive thousands of afferents; each afferent ``n`` listens to one
channel ``c[n]`` and turns its sample into a current with its own gain, rectification and, for
slowly adapting afferents, a threshold gate::

    r = rectify_n(s[c[n]])            none: s;  positive: max(s, 0);  abs: |s|
    I_n = g_n * r                     where s[c[n]] >= theta_n (gated afferents), else 0

This is the encoders' per-afferent step (:mod:`cuneate.golden.encoders`: SA = gain times the
shift above threshold, FA = gain times the rectified filtered shift) with the per-channel part
(the shift, or the band-passed shift) computed once per channel. It is evaluated sample by
sample: no state, no integration. The hardware's fixed-point version is
:class:`cuneate.hdl.fanout.FanoutTwin`.
"""

from __future__ import annotations

import numpy as np

from .validate import finite_array

__all__ = ["RECTIFY", "fanout_currents"]

#: per-afferent rectification of its channel sample
RECTIFY = ("none", "positive", "abs")


def fanout_currents(samples, channel, gain, rectify="none", threshold=None) -> np.ndarray:
    """The currents ``(n_samples, n_afferents)`` of the afferents for channel samples
    ``(n_samples, n_channels)``.

    Parameters
    ----------
    samples
        Channel samples, time on axis 0 (a 1-D array is one sample of every channel).
    channel
        ``(n_afferents,)`` channel index of each afferent.
    gain
        ``(n_afferents,)`` current per unit of sample (mV/ms per sample unit).
    rectify
        One of :data:`RECTIFY`, or one per afferent.
    threshold
        ``None`` (no gate), or per afferent the sample below which its current is 0 (``nan``:
        no gate for that afferent).
    """
    s = finite_array(samples, "samples", ndim=(1, 2), nonempty=True)
    s2 = s[None, :] if s.ndim == 1 else s
    c = np.asarray(channel, dtype=np.int64)
    if c.ndim != 1 or c.size == 0 or c.min() < 0 or c.max() >= s2.shape[1]:
        raise ValueError(f"channel must index the {s2.shape[1]} channels, one per afferent")
    g = finite_array(gain, "gain", ndim=(1,))
    if g.shape != c.shape:
        raise ValueError(f"gain has {g.size} entries for {c.size} afferents")
    modes = [rectify] * c.size if isinstance(rectify, str) else list(rectify)
    if len(modes) != c.size or any(m not in RECTIFY for m in modes):
        raise ValueError(f"rectify must be one of {RECTIFY} (or one per afferent)")
    x = s2[:, c]
    m = np.asarray(modes)
    r = np.where(m == "positive", np.maximum(x, 0.0), np.where(m == "abs", np.abs(x), x))
    out = g * r
    if threshold is not None:
        th = np.asarray(threshold, dtype=np.float64)
        if th.shape != c.shape:
            raise ValueError(f"threshold has {th.size} entries for {c.size} afferents")
        gated = ~np.isnan(th)
        out = np.where(gated & (x < np.where(gated, th, 0.0)), 0.0, out)
    return out[0] if s.ndim == 1 else out
