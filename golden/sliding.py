"""A texture slid under the MEMS fingertip (passive touch): the protocol's phases and the loads
on each sensor, normal and tangential.

Equations
---------
Protocol (the seeds' 2-DoF platform): rest ``t_r``, indentation ``t_i`` (normal force from 0
to ``F`` along a smoothstep ``3 s^2 - 2 s^3``), hold ``t_h``, slide of ``L`` mm at ``v``
(displacement ``D(t) = v (t - t_s)``), hold ``t_h``, retraction ``t_o`` (``F`` back to 0 along
the same smoothstep). The commanded phases are the same in every trial; each trial draws its
own force ``F (1 + s_F N)``, velocity ``v (1 + s_v N)``, friction ``mu (1 + s_mu N)`` and
start position (``x_0, y_0`` each ``j N``, mm) from the scene's seeded generator.

Under sensor ``s`` at ``(x_s, y_s)`` lies the surface point ``X_s = x_s + x_0 - D(t)``,
``Y_s = y_s + y_0`` (the stimulus moves towards ``+x``). The cover sees the height map through
its depth (:func:`cuneate.golden.mems.cover_filter`: ``h_f``); the sensor's normal load is its
share of the force plus what the height under it adds through the viscoelastic cover
(:func:`cuneate.golden.mems.viscoelastic`), never below zero (contact lost)::

    n_s = max(0, F(t)/4 + (F(t)/F) VE[h_f(X_s, Y_s) - h_f(X_s(0), Y_s)])

Friction (whole contact, Coulomb with stick-slip): the contact's tangential force ``F_t``
follows the platform through the cover's tangential stiffness ``k_t`` while it sticks,
``dF_t = k_t dD``; when ``F_t`` reaches ``mu_s,i F`` the contact slips and ``F_t`` drops to
``(2 mu_k - mu_s,i) F`` (an undamped slip overshoots the kinetic level as far as the static
level stood above it), then sticks again. Each event draws its own static level
``mu_s,i = mu_k + (mu_s - mu_k)(1 + 0.3 N)`` (clipped at ``mu_k``): high-friction materials
whose ``mu_s`` exceeds ``mu_k`` stick and slip irregularly; where the sawtooth would be faster
than two samples it is sliding at ``mu_k F``. After the slide ``F_t`` stays (static friction),
bounded by ``mu_k F(t)`` as the force is withdrawn. With ``r = F_t / F``, each sensor's shear
is its friction share plus the tangential component of the load on the local slope of the
profile (heights in µm, positions in mm)::

    t_x,s = n_s (r - 1e-3 dh_f/dX)        t_y,s = -n_s 1e-3 dh_f/dY
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .mems import FINGERTIP, Fingertip, cover_filter, viscoelastic
from .textures import Surface, Texture
from .validate import number, numbers

__all__ = ["Protocol", "Contact", "CONTACT", "smoothstep", "surface_extent", "prepare",
           "slide_loads", "Prepared"]


@dataclass(frozen=True)
class Protocol:
    """The platform's protocol and its trial-to-trial spreads (see the module docstring)."""

    force_N: float = 0.4
    velocity_mm_per_s: float = 15.0
    slide_mm: float = 12.0
    rest_ms: float = 50.0
    indent_ms: float = 200.0
    hold_ms: float = 100.0
    retract_ms: float = 150.0
    spread_force: float = 0.03
    spread_velocity: float = 0.01
    spread_friction: float = 0.02
    jitter_mm: float = 0.05

    def __post_init__(self):
        numbers(self, positive=("force_N", "velocity_mm_per_s", "slide_mm", "indent_ms",
                                "retract_ms"),
                nonneg=("rest_ms", "hold_ms", "spread_force", "spread_velocity",
                        "spread_friction", "jitter_mm"))

    @property
    def slide_ms(self) -> float:
        return 1000.0 * self.slide_mm / self.velocity_mm_per_s

    def phases_ms(self) -> dict:
        """Start and end (ms) of each phase: rest, indentation, hold, slide, hold after,
        retraction."""
        out, t = {}, 0.0
        for name, d in (("rest", self.rest_ms), ("indentation", self.indent_ms),
                        ("hold", self.hold_ms), ("slide", self.slide_ms),
                        ("hold_after", self.hold_ms), ("retraction", self.retract_ms)):
            out[name] = (t, t + d)
            t += d
        return out

    @property
    def duration_ms(self) -> float:
        return self.phases_ms()["retraction"][1]


@dataclass(frozen=True)
class Contact:
    """The contact's tangential stiffness (N/mm) and the spread of each stick's static level."""

    k_t_N_per_mm: float = 2.0
    stick_spread: float = 0.3


#: The default contact.
CONTACT = Contact()


def smoothstep(s):
    """``3 s^2 - 2 s^3`` on ``s`` clipped to [0, 1]."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


def surface_extent(protocol: Protocol, tip: Fingertip = FINGERTIP,
                   margin_mm: float = 1.5) -> tuple[tuple, tuple]:
    """The ``(x, y)`` ranges (mm) of the surface any trial of ``protocol`` can put under a
    sensor (the slide, the array, the start jitter and the velocity spread, with a margin)."""
    h = tip.pitch_mm / 2.0
    reach = protocol.slide_mm * (1.0 + 5 * protocol.spread_velocity) + 5 * protocol.jitter_mm
    return ((-h - reach - margin_mm, h + 5 * protocol.jitter_mm + margin_mm),
            (-h - 5 * protocol.jitter_mm - margin_mm, h + 5 * protocol.jitter_mm + margin_mm))


@dataclass
class Prepared:
    """A surface as the fingertip's cover sees it: the filtered heights and their slopes on
    the surface's grid (what every trial on this texture samples)."""

    surface: Surface
    h_f: np.ndarray
    dhdx: np.ndarray
    dhdy: np.ndarray


def prepare(surface: Surface, tip: Fingertip = FINGERTIP) -> Prepared:
    """Filter ``surface`` through the cover (:func:`~cuneate.golden.mems.cover_filter`) and
    take its slopes (µm per mm)."""
    h_f = cover_filter(surface.h_um, surface.dx_mm, tip.cover_depth_mm)
    dy, dx = np.gradient(h_f, surface.dx_mm)
    return Prepared(surface, h_f, dx, dy)


def _sample(prep: Prepared, grid, X, Y):
    from scipy.ndimage import map_coordinates
    s = prep.surface
    ix = (X - s.x0_mm) / s.dx_mm
    iy = (Y - s.y0_mm) / s.dx_mm
    ny, nx = grid.shape
    if ix.min() < 0 or ix.max() > nx - 1 or iy.min() < 0 or iy.max() > ny - 1:
        raise ValueError("the trial leaves the synthesized surface (surface_extent too small)")
    return map_coordinates(grid, [iy, ix], order=1)


def _friction(F_t0, D, Fn, texture: Texture, mu_scale: float, k_t: float, spread: float,
              rng: np.random.Generator, dt_s: float, v: float):
    """The contact's tangential force ``F_t`` per sample (module docstring) and the number of
    slips."""
    mu_k = texture.mu_kinetic * mu_scale
    mu_s = texture.mu_static * mu_scale
    n = D.size
    Ft = np.empty(n)
    f = F_t0
    slips = 0

    def level():
        return max(mu_k, mu_k + (mu_s - mu_k) * (1.0 + spread * rng.standard_normal()))
    top = level()
    step_max = k_t * v * dt_s                        # shear gained a sample while sticking
    dD = np.diff(D, prepend=D[0])
    for j in range(n):
        F = Fn[j]
        if dD[j] > 0:
            if 2.0 * (top - mu_k) * F < 2.0 * step_max:     # faster than two samples: sliding
                f = min(f + k_t * dD[j], mu_k * F)
            else:
                f += k_t * dD[j]
                if f >= top * F:
                    f = (2.0 * mu_k - top) * F
                    slips += 1
                    top = level()
        else:                                       # standing: static friction holds
            f = min(f, mu_k * F)
        Ft[j] = f
    return Ft, slips


def slide_loads(prep: Prepared, protocol: Protocol, rng: np.random.Generator, fs_hz: float,
                tip: Fingertip = FINGERTIP, contact: Contact = CONTACT):
    """One trial: ``(n, t_x, t_y, info)``, each load ``(n_samples, 4)`` in N per sensor (see
    the module docstring), ``info`` the trial's drawn parameters and its phases."""
    tex = prep.surface.texture
    fs = number(fs_hz, "fs_hz", positive=True)
    n_s = int(round(protocol.duration_ms * fs / 1000.0))
    t = np.arange(n_s) * 1000.0 / fs                           # ms
    ph = protocol.phases_ms()

    def draw(spread):
        return max(0.2, 1.0 + spread * rng.standard_normal())
    F = protocol.force_N * draw(protocol.spread_force)
    v = protocol.velocity_mm_per_s * draw(protocol.spread_velocity)
    mu_scale = draw(protocol.spread_friction)
    x0, y0 = protocol.jitter_mm * rng.standard_normal(2)
    up = smoothstep((t - ph["indentation"][0]) / protocol.indent_ms)
    down = 1.0 - smoothstep((t - ph["retraction"][0]) / protocol.retract_ms)
    Fn = F * up * down
    t0, t1 = ph["slide"]
    D = v * np.clip(t - t0, 0.0, t1 - t0) / 1000.0              # mm
    pos = tip.positions_mm
    X = pos[None, :, 0] + x0 - D[:, None]
    Y = np.broadcast_to(pos[None, :, 1] + y0, X.shape)
    h = _sample(prep, prep.h_f, X, Y)
    gx = _sample(prep, prep.dhdx, X, Y)
    gy = _sample(prep, prep.dhdy, X, Y)
    load = viscoelastic(h - h[:1], fs, tip)
    n = np.maximum(0.0, Fn[:, None] / 4.0 + (Fn / F)[:, None] * load)
    Ft, slips = _friction(0.0, D, Fn, tex, mu_scale, contact.k_t_N_per_mm,
                          contact.stick_spread, rng, 1.0 / fs, v)
    r = np.divide(Ft, Fn, out=np.zeros_like(Ft), where=Fn > 1e-9)
    tx = n * (r[:, None] - 1e-3 * gx)
    ty = -n * 1e-3 * gy
    info = {"texture": tex.name, "force_N": F, "velocity_mm_per_s": v, "mu_scale": mu_scale,
            "x0_mm": float(x0), "y0_mm": float(y0), "slips": int(slips), "phases_ms": ph,
            "slide_start_ms": float(t0)}
    return n, tx, ty, info
