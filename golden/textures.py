"""Ten synthetic naturalistic textures: height maps and friction, seeded and parameterized.

Nothing here is measured: every surface is computed from the stated model below, from its
parameters and a synthesis seed (one seed, one set of ten specimens; another seed, ten other
specimens of the same materials).

Equations
---------
A texture is a height map ``h(x, y)`` (µm) on a square grid of step ``dx`` (mm), ``x`` along the
sliding direction, and Coulomb friction coefficients ``mu_s`` (static) >= ``mu_k`` (kinetic).

Textiles (woven): in coordinates turned by the weave's orientation ``theta``,
``u = x cos theta + y sin theta``, ``v = -x sin theta + y cos theta``::

    h = A [ sum_n a_n cos(2 pi n u / P_u)                 yarns across u (harmonics a_n)
            + c_v sum_n a_n cos(2 pi n v / P_v)           yarns across v
            + c_i cos(2 pi u / P_u) cos(2 pi v / P_v) ]    interlacing
        + A_m cos(2 pi (u / P_m + phi))                   the weave's motif (ribs, twill lines)
        + r(x, y)                                         yarn irregularity

The weave's phases (``u``, ``v`` offsets, ``phi``) are the specimen's, drawn once. Glass, paper
and polymers are random surfaces ``r(x, y)`` alone. ``r`` is a Gaussian random
field with the power spectrum of a self-affine (fractal) surface, ``P(k) ~ k^-(2 + 2 H)``
(Hurst exponent ``H``, Persson's form for a 2-D isotropic surface) between the wavelengths
``lambda_hi`` (shortest) and ``lambda_lo`` (longest), zero outside, scaled to the root mean
square ``rms``; drawn by filtering white noise in the Fourier domain from the texture's own
generator (seeded with the synthesis seed and the texture's specimen, so each specimen is the
same in every trial and run). A texture made ``like`` another (:func:`texture`) is a variant of
the same specimen: the same random draws (weave phases, roughness), some parameters changed -
two such textiles of close periods are nearly the same surface.

The ten: five textiles of different periods, orientations, harmonics and motifs; glass (nearly
flat, fine roughness of nanometres: the ridges seen through it lie below its surface); paper
(a fractal of about ten micrometres); three polymers differing by friction - latex (high, static
well above kinetic: stick-slip), bioskin (medium), the low-friction cover of a game controller
(a fine matte roughness).

Shapes (:data:`SHAPES`, family ``shape``): raised features of height ``A`` on a flat plastic
plate, each with a plateau and smooth edges (``e`` = 0.2 mm): at a distance ``d`` from a
feature's centre line (bars) or centre (dots) of half-width ``r = f/2`` (``f`` =
``feature_mm``)::

    h = A s((r + e/2 - d) / e),    s(x) = smoothstep(clip(x, 0, 1))

``bars``: parallel bars across ``u`` (the ``angle_deg`` coordinates as for textiles) every
``period_u_mm``; ``dots``: a square lattice of pitches ``period_u_mm`` x ``period_v_mm`` in
``(u, v)``. The specimen draws the pattern's phase and its roughness as for textiles.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field, replace

import numpy as np

from .validate import number, numbers

__all__ = ["Texture", "TEXTURES", "SHAPES", "Surface", "surface", "fractal_field", "texture"]


@dataclass(frozen=True)
class Texture:
    """One texture's parameters (see the module docstring). Lengths in mm, heights in µm."""

    name: str
    family: str                         # textile, glass, paper or polymer
    mu_static: float
    mu_kinetic: float
    amplitude_um: float = 0.0           # A (textiles)
    period_u_mm: float = 1.0            # P_u
    period_v_mm: float = 1.0            # P_v
    angle_deg: float = 0.0              # theta: 0 = yarns across the sliding direction
    harmonics: tuple = (1.0,)           # a_1, a_2, ...
    cross: float = 0.0                  # c_v
    interlace: float = 0.0              # c_i
    motif_period_mm: float = 0.0        # P_m (0: no motif)
    motif_um: float = 0.0               # A_m
    rough_rms_um: float = 0.0           # rms of r
    hurst: float = 0.8                  # H
    rough_hi_mm: float = 0.05           # lambda_hi, shortest wavelength of r
    rough_lo_mm: float = 4.0            # lambda_lo, longest wavelength of r
    specimen: str = ""                  # whose random draws it takes ("": its own name)
    shape: str = ""                     # shapes: "bars" or "dots"
    feature_mm: float = 1.0             # f: a bar's width or a dot's diameter

    def __post_init__(self):
        if self.family not in ("textile", "glass", "paper", "polymer", "shape"):
            raise ValueError(f"{self.name}: family must be textile, glass, paper, polymer or "
                             f"shape, got {self.family!r}")
        if (self.family == "shape") != (self.shape in ("bars", "dots")):
            raise ValueError(f"{self.name}: a shape is bars or dots (and only a shape has one), "
                             f"got family {self.family!r}, shape {self.shape!r}")
        number(self.mu_static, f"{self.name}: mu_static", positive=True)
        number(self.mu_kinetic, f"{self.name}: mu_kinetic", positive=True)
        if self.mu_kinetic > self.mu_static:
            raise ValueError(f"{self.name}: mu_kinetic ({self.mu_kinetic:g}) exceeds mu_static "
                             f"({self.mu_static:g})")
        numbers(self, f"{self.name}: ", positive=("period_u_mm", "period_v_mm", "rough_hi_mm",
                                                  "rough_lo_mm", "feature_mm"),
                nonneg=("amplitude_um", "motif_um", "rough_rms_um", "motif_period_mm"))
        if not 0.0 < self.hurst <= 1.0:
            raise ValueError(f"{self.name}: hurst must lie in (0, 1], got {self.hurst!r}")
        if self.rough_hi_mm >= self.rough_lo_mm:
            raise ValueError(f"{self.name}: rough_hi_mm ({self.rough_hi_mm:g}) must be below "
                             f"rough_lo_mm ({self.rough_lo_mm:g})")


#: The ten textures of the texture experiment (brief section 4b), parameters chosen to be
#: physically plausible and distinct: periods of fabrics 0.6-3 mm, weave heights 40-150 µm,
#: friction of a silicone fingertip cover on each.
TEXTURES: dict[str, Texture] = {t.name: t for t in (
    Texture("plain_weave", "textile", 0.60, 0.57, amplitude_um=80, period_u_mm=1.0,
            period_v_mm=1.0, harmonics=(1.0, 0.25), cross=0.9, interlace=0.5,
            rough_rms_um=4, rough_hi_mm=0.1, rough_lo_mm=2.0),
    Texture("twill", "textile", 0.61, 0.58, amplitude_um=80, period_u_mm=1.3,
            period_v_mm=0.8, angle_deg=35, harmonics=(1.0, 0.4, 0.15), cross=0.5,
            interlace=0.3, motif_period_mm=3.2, motif_um=30, rough_rms_um=4,
            rough_hi_mm=0.1, rough_lo_mm=2.0),
    Texture("corduroy", "textile", 0.58, 0.55, amplitude_um=90, period_u_mm=2.6,
            period_v_mm=0.7, harmonics=(1.0, 0.5, 0.2), cross=0.15, interlace=0.0,
            rough_rms_um=5, rough_hi_mm=0.1, rough_lo_mm=2.0),
    Texture("ribbed_knit", "textile", 0.60, 0.57, amplitude_um=85, period_u_mm=1.7,
            period_v_mm=2.2, angle_deg=90, harmonics=(1.0, 0.35), cross=0.6,
            interlace=0.4, motif_period_mm=6.0, motif_um=25, rough_rms_um=5,
            rough_hi_mm=0.1, rough_lo_mm=2.0),
    Texture("canvas", "textile", 0.62, 0.59, amplitude_um=85, period_u_mm=1.9,
            period_v_mm=1.5, angle_deg=-20, harmonics=(1.0, 0.2, 0.3), cross=0.9,
            interlace=0.8, motif_period_mm=4.5, motif_um=40, rough_rms_um=6,
            rough_hi_mm=0.1, rough_lo_mm=2.0),
    Texture("glass", "glass", 0.80, 0.78, rough_rms_um=0.02, hurst=0.9, rough_hi_mm=0.02,
            rough_lo_mm=1.0),
    Texture("paper", "paper", 0.45, 0.42, rough_rms_um=12.0, hurst=0.7, rough_hi_mm=0.03,
            rough_lo_mm=5.0),
    Texture("latex", "polymer", 1.30, 0.95, rough_rms_um=0.4, hurst=0.9, rough_hi_mm=0.05,
            rough_lo_mm=2.0),
    Texture("bioskin", "polymer", 0.76, 0.68, rough_rms_um=15.0, hurst=0.7,
            rough_hi_mm=0.2, rough_lo_mm=3.0),
    Texture("controller", "polymer", 0.30, 0.28, rough_rms_um=2.0, hurst=0.5,
            rough_hi_mm=0.03, rough_lo_mm=0.5),
)}


#: Two shapes (the learning protocol's, brief section 5b: three textures and two shapes): raised
#: bars at 45 degrees to the sliding direction (the ridge experiment's angle) and a lattice of
#: dots (Braille-like), on a smooth plastic plate.
SHAPES: dict[str, Texture] = {t.name: t for t in (
    Texture("bars", "shape", 0.50, 0.46, amplitude_um=150, period_u_mm=4.0, angle_deg=45,
            feature_mm=1.0, rough_rms_um=0.5, rough_hi_mm=0.05, rough_lo_mm=1.0, shape="bars"),
    Texture("dots", "shape", 0.50, 0.46, amplitude_um=200, period_u_mm=3.0, period_v_mm=3.0,
            feature_mm=1.4, rough_rms_um=0.5, rough_hi_mm=0.05, rough_lo_mm=1.0,
            shape="dots"),
)}


def texture(spec) -> Texture:
    """A texture (or shape) from its name (one of :data:`TEXTURES` or :data:`SHAPES`) or from a
    mapping: ``name`` and ``like`` (a texture or shape whose parameters it starts from), then
    any parameter of :class:`Texture` to change."""
    if isinstance(spec, Texture):
        return spec
    if isinstance(spec, str):
        known = TEXTURES | SHAPES
        if spec not in known:
            raise ValueError(f"unknown texture {spec!r} (known: {', '.join(known)})")
        return known[spec]
    spec = dict(spec)
    base = texture(spec.pop("like", "plain_weave"))
    if "harmonics" in spec:
        spec["harmonics"] = tuple(spec["harmonics"])
    spec.setdefault("specimen", base.specimen or base.name)
    return replace(base, **spec)


@dataclass
class Surface:
    """A texture's height map: ``h_um[j, i]`` at ``y = y0 + j dx``, ``x = x0 + i dx`` (mm)."""

    texture: Texture
    h_um: np.ndarray
    dx_mm: float
    x0_mm: float
    y0_mm: float
    info: dict = field(default_factory=dict)

    @property
    def x_mm(self) -> np.ndarray:
        return self.x0_mm + self.dx_mm * np.arange(self.h_um.shape[1])

    @property
    def y_mm(self) -> np.ndarray:
        return self.y0_mm + self.dx_mm * np.arange(self.h_um.shape[0])


def fractal_field(rng: np.random.Generator, shape: tuple, dx_mm: float, rms_um: float,
                  hurst: float, hi_mm: float, lo_mm: float) -> np.ndarray:
    """A self-affine Gaussian random field ``(ny, nx)`` of root mean square ``rms_um``: white
    noise filtered to the amplitude spectrum ``k^-(1 + H)`` between wavelengths ``hi_mm`` and
    ``lo_mm`` (see the module docstring)."""
    if rms_um == 0:
        return np.zeros(shape)
    ny, nx = shape
    kx = np.fft.rfftfreq(nx, dx_mm)
    ky = np.fft.fftfreq(ny, dx_mm)
    k = np.hypot(ky[:, None], kx[None, :])           # cycles per mm
    band = (k >= 1.0 / lo_mm) & (k <= 1.0 / hi_mm)
    amp = np.zeros_like(k)
    amp[band] = k[band] ** -(1.0 + hurst)
    noise = np.fft.rfft2(rng.standard_normal(shape))
    f = np.fft.irfft2(noise * amp, s=shape)
    sd = float(f.std())
    return f * (rms_um / sd) if sd > 0 else f


def _seed(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


#: a shape's edge width (mm)
SHAPE_EDGE_MM = 0.2


def _features(tex: Texture, x, y, phase) -> np.ndarray:
    """A shape's features ``(ny, nx)`` of unit height (see the module docstring)."""
    th = np.radians(tex.angle_deg)
    X, Y = np.meshgrid(x, y)
    u = X * np.cos(th) + Y * np.sin(th) + phase[0] * tex.period_u_mm
    v = -X * np.sin(th) + Y * np.cos(th) + phase[1] * tex.period_v_mm

    def centred(a, p):                     # distance to the nearest multiple of p
        return np.abs(a - p * np.round(a / p))
    d = centred(u, tex.period_u_mm)
    if tex.shape == "dots":
        d = np.hypot(d, centred(v, tex.period_v_mm))
    e = SHAPE_EDGE_MM
    s = np.clip((tex.feature_mm / 2 + e / 2 - d) / e, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


def surface(tex: Texture, seed: int, x_mm: tuple, y_mm: tuple, dx_mm: float = 0.025) -> Surface:
    """The height map of ``tex`` (its specimen of synthesis ``seed``) over ``x_mm = (lo, hi)``
    by ``y_mm = (lo, hi)`` on a grid of ``dx_mm``."""
    dx = number(dx_mm, "dx_mm", positive=True)
    nx = int(np.ceil((x_mm[1] - x_mm[0]) / dx)) + 1
    ny = int(np.ceil((y_mm[1] - y_mm[0]) / dx)) + 1
    x = x_mm[0] + dx * np.arange(nx)
    y = y_mm[0] + dx * np.arange(ny)
    rng = _seed(seed, tex.specimen or tex.name)
    h = fractal_field(rng, (ny, nx), dx, tex.rough_rms_um, tex.hurst, tex.rough_hi_mm,
                      tex.rough_lo_mm)
    if tex.family == "textile":
        th = np.radians(tex.angle_deg)
        X, Y = np.meshgrid(x, y)
        # each specimen lies on the platform with its own phase of the weave
        ph = rng.uniform(0, 1, 3)
        u = X * np.cos(th) + Y * np.sin(th) + ph[0] * tex.period_u_mm
        v = -X * np.sin(th) + Y * np.cos(th) + ph[1] * tex.period_v_mm
        cu = sum(a * np.cos(2 * np.pi * (n + 1) * u / tex.period_u_mm)
                 for n, a in enumerate(tex.harmonics))
        cv = sum(a * np.cos(2 * np.pi * (n + 1) * v / tex.period_v_mm)
                 for n, a in enumerate(tex.harmonics))
        weave = cu + tex.cross * cv + tex.interlace * np.cos(2 * np.pi * u / tex.period_u_mm) \
            * np.cos(2 * np.pi * v / tex.period_v_mm)
        h = h + tex.amplitude_um * weave
        if tex.motif_period_mm > 0:
            h = h + tex.motif_um * np.cos(2 * np.pi * (u / tex.motif_period_mm + ph[2]))
    elif tex.family == "shape":
        h = h + tex.amplitude_um * _features(tex, x, y, rng.uniform(0, 1, 2))
    return Surface(tex, h, dx, float(x[0]), float(y[0]),
                   {"rms_um": float(h.std()), "seed": int(seed)})
