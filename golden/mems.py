"""The biomimetic MEMS fingertip: a 2 x 2 array of cross-shaped MEMS sensors, four
piezoresistive tethers each (16 channels), under a soft viscoelastic cover.

Equations
---------
Layout: sensor ``s`` sits at ``(x_s, y_s) = (+-p/2, +-p/2)`` (pitch ``p``, ``x`` along the
sliding direction; ``s = 0, 1`` the row at ``+p/2``, ``s = 2, 3`` the row at ``-p/2``, the
lower ``x`` first), mounted turned by ``phi_s``. Its tether ``k`` (channel ``4 s + k``) points
along ``theta_sk = phi_s + k 90 deg``.

Cover, in space: a traction pattern of spatial frequency ``f`` (cycles/mm) at the cover's
surface reaches the sensors at depth ``d`` attenuated by the normal-stress transfer of an
elastic half-space (Johnson, *Contact Mechanics*, ch. 2), applied to the surface profile the
cover rests on::

    T(f) = (1 + 2 pi f d) exp(-2 pi f d)

Cover, in time: a standard linear solid. A height change ``h(t)`` under a sensor loads it with
``k_inf h + k_1 HP[h]``, ``HP`` the first-order high-pass of relaxation time ``tau``
(``y_n = a (y_{n-1} + h_n - h_{n-1})``, ``a = tau / (tau + dt)``): fast changes meet the
stiffer instantaneous modulus ``k_inf + k_1``, slow ones the relaxed ``k_inf``.

Tethers: with ``n_s`` the normal load on sensor ``s`` and ``(t_x, t_y)_s`` its shear (N)::

    V_sk = g_sk [ G_n n_s + G_t (t_x cos theta_sk + t_y sin theta_sk) ]        (V)

``g_sk`` is the tether's gain mismatch (``1 + mismatch N(0, 1)``, drawn once from the device's
own seed: one fingertip in every trial). Opponent tethers subtracted along an axis give the
shear, the normal load cancelling but for the mismatch::

    S_s,x = V_s,+x - V_s,-x = 2 G_t t_x,s + (mismatch) G_n n_s

With the default rotations ``phi = (270, 0, 90, 180) deg`` the four sliding-direction pairs are
the seeds' channels 2-4, 5-7, 12-10 and 15-13 (1-based): each is the tether facing ``+x``
minus the one facing ``-x``.

Effects (each only when listed, in :data:`~cuneate.golden.tactile.EFFECT_ORDER`): electronic
noise ``sigma_mV``, ADC resolution ``step_mV``, ADC range ``min_mV .. max_mV`` (saturation),
dropped samples, cross-talk between the 16 channels; parameters in mV (:data:`EFFECT_UNITS`),
applied by the effect functions of :mod:`cuneate.golden.tactile` on the tethers' volts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .validate import number

__all__ = ["Fingertip", "FINGERTIP", "cover_transfer", "cover_filter", "viscoelastic",
           "tether_outputs", "opponent_pairs", "opponent_signals", "pair_names",
           "EFFECT_UNITS", "EFFECTS_ALLOWED", "N_CHANNELS", "sensor_effects"]

#: Tethers of the fingertip: 4 sensors x 4 tethers.
N_CHANNELS = 16
#: The effects a MEMS fingertip has (no strain, no temperature term: those are a grating's).
EFFECTS_ALLOWED = ("noise", "resolution", "saturation", "dropped_samples", "crosstalk")
#: Each effect's parameters in the scene's units (mV) -> the effect function's, in volts:
#: ``{effect: {parameter: (scene key, scale, default)}}``.
EFFECT_UNITS = {
    "noise": {"sigma": ("sigma_mV", 1e-3, 0.01)},
    "resolution": {"step": ("step_mV", 1e-3, 0.005)},
    "saturation": {"lo": ("min_mV", 1e-3, -50.0), "hi": ("max_mV", 1e-3, 50.0)},
    "dropped_samples": {"probability": ("probability", 1.0, 0.001)},
    "crosstalk": {"fraction": ("fraction", 1.0, 0.02)},
}


@dataclass(frozen=True)
class Fingertip:
    """The fingertip's parameters (see the module docstring): pitch (mm), sensor rotations
    (deg), cover depth (mm), the cover's relaxed and extra instantaneous stiffness per sensor
    (N per µm of height), its relaxation time (ms), tether sensitivities (V/N), the tethers'
    gain mismatch and the device seed it is drawn from."""

    pitch_mm: float = 2.2
    rotations_deg: tuple = (270.0, 0.0, 90.0, 180.0)
    cover_depth_mm: float = 0.45
    k_relaxed_N_per_um: float = 0.25e-3
    k_extra_N_per_um: float = 0.75e-3
    relax_ms: float = 25.0
    G_n_V_per_N: float = 5e-3
    G_t_V_per_N: float = 15e-3
    mismatch: float = 0.03
    device_seed: int = 2011

    def __post_init__(self):
        number(self.pitch_mm, "pitch_mm", positive=True)
        number(self.cover_depth_mm, "cover_depth_mm", nonneg=True)
        number(self.k_relaxed_N_per_um, "k_relaxed_N_per_um", nonneg=True)
        number(self.k_extra_N_per_um, "k_extra_N_per_um", nonneg=True)
        number(self.relax_ms, "relax_ms", positive=True)
        number(self.mismatch, "mismatch", nonneg=True)
        if len(self.rotations_deg) != 4:
            raise ValueError(f"rotations_deg: one per sensor (4), got {len(self.rotations_deg)}")

    @property
    def positions_mm(self) -> np.ndarray:
        """``(4, 2)``: each sensor's ``(x, y)`` in mm."""
        h = self.pitch_mm / 2.0
        return np.array([[-h, h], [h, h], [-h, -h], [h, -h]])

    @property
    def tether_angles_deg(self) -> np.ndarray:
        """``(4, 4)``: the direction of tether ``k`` of sensor ``s`` (deg, in [0, 360))."""
        return (np.asarray(self.rotations_deg)[:, None] + 90.0 * np.arange(4)[None, :]) % 360.0

    def gains(self) -> np.ndarray:
        """``(4, 4)``: each tether's gain (1 + mismatch), the device's own."""
        rng = np.random.default_rng(self.device_seed)
        return 1.0 + self.mismatch * rng.standard_normal((4, 4))


#: The default fingertip.
FINGERTIP = Fingertip()


def cover_transfer(f_per_mm, depth_mm: float) -> np.ndarray:
    """``T(f) = (1 + 2 pi f d) exp(-2 pi f d)`` for spatial frequencies ``f`` (cycles/mm)."""
    kd = 2.0 * np.pi * np.abs(np.asarray(f_per_mm, dtype=np.float64)) * depth_mm
    return (1.0 + kd) * np.exp(-kd)


def cover_filter(h_um: np.ndarray, dx_mm: float, depth_mm: float) -> np.ndarray:
    """A height map ``(ny, nx)`` as the sensors under the cover see it (:func:`cover_transfer`
    applied in the 2-D Fourier domain; the mean passes unchanged)."""
    ny, nx = h_um.shape
    f = np.hypot(np.fft.fftfreq(ny, dx_mm)[:, None], np.fft.rfftfreq(nx, dx_mm)[None, :])
    return np.fft.irfft2(np.fft.rfft2(h_um) * cover_transfer(f, depth_mm), s=h_um.shape)


def viscoelastic(h_um: np.ndarray, fs_hz: float, tip: Fingertip = FINGERTIP) -> np.ndarray:
    """The load (N) of height changes ``h_um`` (samples on axis 0) through the cover's
    standard linear solid: ``k_inf h + k_1 HP[h]``."""
    from scipy.signal import lfilter
    h = np.asarray(h_um, dtype=np.float64)
    a = tip.relax_ms / (tip.relax_ms + 1000.0 / fs_hz)
    hp = lfilter([a, -a], [1.0, -a], h - h[:1], axis=0)
    return tip.k_relaxed_N_per_um * h + tip.k_extra_N_per_um * hp


def tether_outputs(n_N, tx_N, ty_N, tip: Fingertip = FINGERTIP) -> np.ndarray:
    """The 16 tethers' outputs ``(n_samples, 16)`` in V (channel ``4 s + k``) from each
    sensor's normal load and shear, each ``(n_samples, 4)`` in N."""
    th = np.radians(tip.tether_angles_deg)          # (4, 4)
    g = tip.gains()
    n, tx, ty = (np.asarray(a, dtype=np.float64)[:, :, None] for a in (n_N, tx_N, ty_N))
    v = g[None] * (tip.G_n_V_per_N * n + tip.G_t_V_per_N * (tx * np.cos(th)[None]
                                                           + ty * np.sin(th)[None]))
    return v.reshape(v.shape[0], N_CHANNELS)


def opponent_pairs(tip: Fingertip = FINGERTIP) -> list[tuple[int, int]]:
    """The eight opponent pairs ``(plus, minus)`` (0-based channels): the sliding direction's
    (``+x`` minus ``-x``) of sensors 0-3, then the cross direction's (``+y`` minus ``-y``)."""
    ang = tip.tether_angles_deg
    out = []
    for plus, minus in ((0.0, 180.0), (90.0, 270.0)):
        for s in range(4):
            kp = int(np.flatnonzero(np.isclose(ang[s], plus))[0])
            km = int(np.flatnonzero(np.isclose(ang[s], minus))[0])
            out.append((4 * s + kp, 4 * s + km))
    return out


def pair_names(tip: Fingertip = FINGERTIP) -> list[str]:
    """The pairs' names as the seeds number channels (1-based): ``"x s0: 2-4"``, ..."""
    return [f"{'x' if i < 4 else 'y'} s{i % 4}: {p + 1}-{m + 1}"
            for i, (p, m) in enumerate(opponent_pairs(tip))]


def opponent_signals(v, tip: Fingertip = FINGERTIP) -> np.ndarray:
    """``S`` ``(n_samples, 8)``: the opponent differences of :func:`opponent_pairs` of the
    tethers' outputs ``v`` ``(n_samples, 16)`` (a dropped sample, NaN, stays NaN)."""
    v = np.asarray(v, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != N_CHANNELS:
        raise ValueError(f"tether outputs must be (n_samples, {N_CHANNELS}), got {v.shape}")
    pairs = opponent_pairs(tip)
    return v[:, [p for p, _ in pairs]] - v[:, [m for _, m in pairs]]


def sensor_effects(v, effects, params: dict, rng: np.random.Generator,
                   fs_hz: float) -> tuple[np.ndarray, dict]:
    """Exactly the listed ``effects`` (a subset of :data:`EFFECTS_ALLOWED`) on the tethers'
    outputs ``v`` (V), parameters in mV (:data:`EFFECT_UNITS`); returns the outputs and one
    count entry per effect applied."""
    from .tactile import sensor_effects as apply
    for e in effects:
        if e not in EFFECTS_ALLOWED:
            raise ValueError(f"effect {e!r} is not a MEMS fingertip's (it has: "
                             f"{', '.join(EFFECTS_ALLOWED)})")
    return apply(v, effects, params, rng, fs_hz, units=EFFECT_UNITS)
