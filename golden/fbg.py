"""Float64 reference of the FBG (Fiber Bragg Grating) host-side front end.

Physics (design brief, section 3)
---------------------------------
Bragg condition ``lambda_B = 2 n_eff Lambda``; a strain ``eps`` (dimensionless, 1e-6 = 1 ue) and a
temperature change ``dT`` (K) shift the reflected wavelength by::

    d_lambda = lambda_B [ (1 - p_e) eps + (alpha + xi) dT ]          (nm, like lambda_B)

with effective photo-elastic coefficient ``p_e ~= 0.22`` (strain sensitivity
``lambda_B (1 - p_e) ~= 1.21 pm/ue`` at 1550 nm) and thermal coefficient
``thermo = alpha + xi = 6.5e-6 /K`` (thermal expansion + thermo-optic; ``~= 10.1 pm/K`` at
1550 nm). The brief neglects the thermal term at room temperature (``delta_T_K = 0``).

Pre-processing: ``d_lambda`` sampled at ``fs = 1 kHz`` per grating is band-pass filtered by a
causal IIR filter (direct form, :func:`scipy.signal.lfilter`, zero initial state)::

    y[n] = sum_k b[k] x[n-k] - sum_{k>=1} a[k] y[n-k]           (a[0] normalized to 1)

and multiplied by a gain ``S`` (180) to give the input current (mV/ms) of a fast-adapting neuron.
The unit of ``d_lambda`` in the published chain is not stated; this module uses nm throughout.

Stability
---------
A filter is accepted only if every pole (root of ``z^N + a1 z^(N-1) + ... + aN``) lies *strictly*
inside the unit circle. Two independent tests must both agree: the largest root radius from
:func:`numpy.roots` must be below ``1 - STABILITY_TOL`` and the Schur-Cohn (step-down) recursion
must give reflection coefficients all of magnitude < 1. A pole on the circle (``a = [1, -1]``) is
refused. :meth:`IIRFilter.apply` raises :class:`UnstableFilterError` (a :class:`ValueError`) that
names each offending pole and its radius.

The published coefficients are unstable
---------------------------------------
``PUBLISHED_BANDPASS`` keeps the coefficients exactly as published, ``b = [0.045, 0, -0.045]``,
``a = [1, -1.919, 0.91]``. Their discriminant ``1.919^2 - 4 * 0.91 = 0.042561`` is positive, so the
poles are real, ``(1.919 +- 0.2063) / 2 = 1.0627`` and ``0.8563``: one pole lies outside the unit
circle (equivalently ``|a1| = 1.919 > 1 + a2 = 1.91`` violates the second-order stability
triangle), and :meth:`IIRFilter.apply` refuses it. An order-1 Butterworth band-pass of
1-16 Hz at 1 kHz has ``b = [0.04504, 0, -0.04504]``, ``a = [1, -1.9093, 0.9099]``, which matches the
published ``b`` and ``a[2]`` to every printed digit and ``a[1]`` up to one digit (``-1.909`` vs
``-1.919``); the published ``a[1]`` may be a transcription error, but that is a conjecture.
``DEFAULT_BANDPASS`` is that stable filter and is the default of :class:`FbgFrontEnd`.

Validation: :class:`ValueError` for empty, non-finite or non-1-D coefficients, ``a[0] == 0``, bad
band edges, and non-finite traces (the message names the first bad sample index and grating).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import scipy.signal

from .validate import finite_array, number

__all__ = [
    "LAMBDA_B_NM", "P_E", "THERMO_PER_K", "FS_HZ", "DEFAULT_GAIN_S", "STABILITY_TOL",
    "FILTER_KINDS", "bragg_shift_nm", "strain_sensitivity_pm_per_microstrain",
    "temperature_sensitivity_pm_per_K",
    "UnstableFilterError", "FilterReport", "IIRFilter", "PUBLISHED_BANDPASS", "DEFAULT_BANDPASS",
    "design_bandpass", "FbgFrontEnd", "filter_check_report", "schur_cohn_reflection",
]

LAMBDA_B_NM = 1550.0
P_E = 0.22
THERMO_PER_K = 6.5e-6
FS_HZ = 1000.0
DEFAULT_GAIN_S = 180.0
#: Poles with radius >= 1 - STABILITY_TOL are treated as on/outside the unit circle.
STABILITY_TOL = 1e-12
FILTER_KINDS = ("butter", "bessel", "cheby1", "cheby2", "ellip")


# ------------------------------------------------------------------------------- physics

def bragg_shift_nm(strain, delta_T_K=0.0, lambda_B_nm: float = LAMBDA_B_NM, p_e: float = P_E,
                   thermo: float = THERMO_PER_K) -> np.ndarray:
    """Bragg wavelength shift ``lambda_B [(1 - p_e) strain + thermo delta_T]`` in nm.

    Parameters
    ----------
    strain
        Axial strain, dimensionless (1e-6 = 1 microstrain); array-like.
    delta_T_K
        Temperature change in K (broadcast against ``strain``).
    lambda_B_nm
        Unstrained Bragg wavelength in nm (> 0).
    p_e
        Effective photo-elastic coefficient, ``0 <= p_e < 1`` (0.22 for silica fibre).
    thermo
        ``alpha + xi``, thermal expansion plus thermo-optic coefficient in 1/K (6.5e-6 gives
        ~10 pm/K at 1550 nm).
    """
    eps = finite_array(strain, "strain")
    dT = finite_array(delta_T_K, "delta_T_K")
    lam = number(lambda_B_nm, "lambda_B_nm", positive=True)
    pe = number(p_e, "p_e")
    if not 0 <= pe < 1:
        raise ValueError(f"p_e must lie in [0, 1), got {p_e!r}")
    th = number(thermo, "thermo")
    try:
        out = lam * ((1.0 - pe) * eps + th * dT)
    except ValueError as exc:
        raise ValueError(f"strain and delta_T_K do not broadcast: {exc}") from None
    if not np.all(np.isfinite(out)):
        raise ValueError("Bragg shift overflowed float64")
    return out


def strain_sensitivity_pm_per_microstrain(lambda_B_nm: float = LAMBDA_B_NM,
                                          p_e: float = P_E) -> float:
    """``lambda_B (1 - p_e)`` expressed in pm per microstrain (1.209 at 1550 nm, p_e 0.22)."""
    return float(bragg_shift_nm(1e-6, 0.0, lambda_B_nm, p_e)) * 1e3


def temperature_sensitivity_pm_per_K(lambda_B_nm: float = LAMBDA_B_NM,
                                     thermo: float = THERMO_PER_K) -> float:
    """``lambda_B thermo`` in pm/K (10.075 at 1550 nm with the default coefficient)."""
    return float(bragg_shift_nm(0.0, 1.0, lambda_B_nm, P_E, thermo)) * 1e3


# ------------------------------------------------------------------------------- filters

def schur_cohn_reflection(a) -> list[float]:
    """Reflection coefficients of the Schur-Cohn step-down recursion for monic ``a``.

    The polynomial ``z^N + a1 z^(N-1) + ... + aN`` has all roots strictly inside the unit circle
    iff every returned coefficient has magnitude < 1. The recursion stops (returning the
    coefficients found so far) at the first ``|k| >= 1``.
    """
    p = np.asarray(a, dtype=np.float64) / float(a[0])
    ks: list[float] = []
    while p.size > 1:
        k = float(p[-1])
        ks.append(k)
        if not abs(k) < 1.0:
            break
        p = (p[:-1] - k * p[::-1][:-1]) / (1.0 - k * k)
    return ks


def _fmt_c(z: complex) -> str:
    return f"{z.real:.10g}{'+' if z.imag >= 0 else '-'}{abs(z.imag):.10g}j"


@dataclass(frozen=True)
class FilterReport:
    """Stability report of an IIR filter (see :meth:`IIRFilter.check`)."""

    b: tuple
    a: tuple
    poles: tuple
    radii: tuple
    max_radius: float
    stable: bool
    message: str

    @property
    def verdict(self) -> str:
        return "stable" if self.stable else "UNSTABLE"

    def to_text(self) -> str:
        """Human-readable report: coefficients, one line per pole with its radius, verdict."""
        lines = [f"IIR filter  b = [{', '.join(f'{x:.10g}' for x in self.b)}]  "
                 f"a = [{', '.join(f'{x:.10g}' for x in self.a)}]"]
        if not self.poles:
            lines.append("no poles (FIR filter)")
        for i, (z, r) in enumerate(zip(self.poles, self.radii), 1):
            if r < 1.0 - STABILITY_TOL:
                where = "inside"
            elif abs(r - 1.0) <= STABILITY_TOL:
                where = "ON the unit circle"
            else:
                where = "OUTSIDE the unit circle"
            lines.append(f"pole {i}: z = {_fmt_c(z)}  |z| = {r:.10g}  ({where})")
        lines.append(f"verdict: {self.verdict} - {self.message}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-serializable dictionary."""
        return {
            "b": [float(x) for x in self.b],
            "a": [float(x) for x in self.a],
            "poles": [{"real": float(z.real), "imag": float(z.imag), "radius": float(r)}
                      for z, r in zip(self.poles, self.radii)],
            "max_radius": float(self.max_radius),
            "stable": bool(self.stable),
            "verdict": self.verdict,
            "message": self.message,
        }


class UnstableFilterError(ValueError):
    """An IIR filter has a pole on or outside the unit circle."""

    def __init__(self, report: FilterReport):
        self.report = report
        super().__init__(f"IIR filter is unstable: {report.message}")


def _coeffs(x, name: str) -> np.ndarray:
    if isinstance(x, str):
        x = _parse_list(x, name)
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} coefficients must be numbers: {exc}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{name} coefficients must be a 1-D sequence, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} coefficients are empty")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{name}[{i}] is not finite ({arr[i]!r})")
    return arr


def _parse_list(s: str, name: str) -> list[float]:
    parts = [p for p in re.split(r"[,\s;]+", s.strip().strip("[]()")) if p]
    try:
        return [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"cannot parse {name} coefficients from {s!r}") from None


@dataclass(frozen=True, eq=False)
class IIRFilter:
    """Causal IIR filter ``H(z) = B(z^-1) / A(z^-1)``, stored normalized so that ``a[0] == 1``.

    ``b``, ``a`` are read-only float64 arrays. Construction refuses empty or non-finite
    coefficients and ``a[0] == 0``; it does *not* refuse unstable filters (so that they can be
    inspected with :meth:`check`), but :meth:`apply` does.
    """

    b: np.ndarray
    a: np.ndarray

    def __post_init__(self):
        b = _coeffs(self.b, "b")
        a = _coeffs(self.a, "a")
        if a[0] == 0.0:
            raise ValueError("a[0] must be non-zero (it is the output's own coefficient; the "
                             "filter is normalized by it)")
        b, a = b / a[0], a / a[0]
        if not (np.all(np.isfinite(b)) and np.all(np.isfinite(a))):
            raise ValueError("normalizing by a[0] overflowed float64 (a[0] is too small)")
        b.setflags(write=False)
        a.setflags(write=False)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "a", a)

    def __repr__(self) -> str:
        return f"IIRFilter(b={self.b.tolist()!r}, a={self.a.tolist()!r})"

    def __eq__(self, other) -> bool:
        return (isinstance(other, IIRFilter) and np.array_equal(self.b, other.b)
                and np.array_equal(self.a, other.a))

    def __hash__(self) -> int:
        return hash((self.b.tobytes(), self.a.tobytes()))

    @property
    def order(self) -> int:
        return max(len(self.a), len(self.b)) - 1

    def poles(self) -> np.ndarray:
        """Roots of ``z^N + a1 z^(N-1) + ... + aN`` (complex array, empty for an FIR filter)."""
        if self.a.size == 1:
            return np.zeros(0, dtype=complex)
        return np.roots(self.a).astype(complex)

    def zeros(self) -> np.ndarray:
        """Roots of the numerator polynomial."""
        nz = np.flatnonzero(self.b)
        if nz.size == 0 or self.b.size == 1:
            return np.zeros(0, dtype=complex)
        return np.roots(self.b[nz[0]:]).astype(complex)

    def pole_radii(self) -> np.ndarray:
        return np.abs(self.poles())

    def is_stable(self) -> bool:
        return self.check().stable

    def check(self) -> FilterReport:
        """Stability report: poles, radii, largest radius, verdict and message."""
        poles = self.poles()
        radii = np.abs(poles)
        order = np.argsort(-radii, kind="stable")
        poles, radii = poles[order], radii[order]
        max_r = float(radii.max()) if radii.size else 0.0
        ks = schur_cohn_reflection(self.a)
        sc_ok = all(abs(k) < 1.0 for k in ks)
        roots_ok = max_r < 1.0 - STABILITY_TOL
        stable = sc_ok and roots_ok
        if stable:
            msg = (f"all {poles.size} pole(s) strictly inside the unit circle (max |z| = "
                   f"{max_r:.10g})" if poles.size else "FIR filter (no poles)")
        else:
            bad = [(z, r) for z, r in zip(poles, radii) if r >= 1.0 - STABILITY_TOL]
            if bad:
                msg = "; ".join(f"pole z = {_fmt_c(z)} has radius |z| = {r:.10g} >= 1"
                                for z, r in bad)
            else:
                z, r = poles[0], radii[0]
                msg = (f"the Schur-Cohn test places a pole on or outside the unit circle; the "
                       f"largest computed pole z = {_fmt_c(z)} has radius |z| = {r:.10g} "
                       f"(numerically on the unit circle)")
            msg += " (poles must lie strictly inside the unit circle)"
        return FilterReport(b=tuple(float(x) for x in self.b), a=tuple(float(x) for x in self.a),
                            poles=tuple(complex(z) for z in poles),
                            radii=tuple(float(r) for r in radii), max_radius=max_r,
                            stable=stable, message=msg)

    def require_stable(self) -> FilterReport:
        """Return the report if stable, else raise :class:`UnstableFilterError`."""
        rep = self.check()
        if not rep.stable:
            raise UnstableFilterError(rep)
        return rep

    def apply(self, x) -> np.ndarray:
        """Filter ``x`` (shape ``(n,)`` or ``(n, channels)``) along axis 0, zero initial state.

        Raises :class:`UnstableFilterError` for an unstable filter and :class:`ValueError` for a
        non-finite sample (naming the first bad sample index and channel).
        """
        self.require_stable()
        arr = _trace(x, "x")
        y = scipy.signal.lfilter(self.b, self.a, arr, axis=0)
        if not np.all(np.isfinite(y)):
            raise ValueError("filter output overflowed float64")
        return y

    def frequency_response(self, fs_hz: float = FS_HZ, n: int = 4096):
        """``(f_hz, H)`` from :func:`scipy.signal.freqz` on ``[0, fs/2)``."""
        return scipy.signal.freqz(self.b, self.a, worN=n, fs=fs_hz)


def _sample_grating(idx: tuple[int, ...]) -> str:
    return f"sample index {idx[0]}" + (f" (grating {idx[1]})" if len(idx) == 2 else "")


def _trace(x, name: str) -> np.ndarray:
    return finite_array(x, name, ndim=(1, 2), nonempty=True,
                        shapes="(n_samples,) or (n_samples, n_gratings)", where=_sample_grating)


#: The band-pass exactly as published (unstable: real pole at 1.0627, see the module docstring).
PUBLISHED_BANDPASS = IIRFilter(b=[0.045, 0.0, -0.045], a=[1.0, -1.919, 0.91])


def design_bandpass(low_hz: float, high_hz: float, fs_hz: float = FS_HZ, order: int = 1,
                    kind: str = "butter", rp_db: float = 1.0, rs_db: float = 40.0) -> IIRFilter:
    """Digital band-pass via :func:`scipy.signal.iirfilter` (bilinear transform, ``ba`` form).

    ``order`` is the prototype order (the band-pass has ``2 * order`` poles); ``kind`` one of
    ``"butter"``, ``"bessel"``, ``"cheby1"`` (ripple ``rp_db``), ``"cheby2"`` (stop-band
    ``rs_db``), ``"ellip"``. Requires ``0 < low_hz < high_hz < fs_hz / 2``. Raises
    :class:`UnstableFilterError` if the designed ``ba`` coefficients are not stable (possible for
    high orders and narrow bands; use a lower order).
    """
    lo, hi = number(low_hz, "low_hz"), number(high_hz, "high_hz")
    fs = number(fs_hz, "fs_hz", positive=True)
    if not 0 < lo < hi < fs / 2:
        raise ValueError(f"band edges must satisfy 0 < low_hz < high_hz < fs_hz/2 = {fs / 2:g}, "
                         f"got low_hz={lo:g}, high_hz={hi:g}")
    if isinstance(order, bool) or int(order) != order or order < 1:
        raise ValueError(f"order must be a positive integer, got {order!r}")
    if kind not in FILTER_KINDS:
        raise ValueError(f"kind must be one of {', '.join(FILTER_KINDS)}, got {kind!r}")
    kw = {}
    if kind in ("cheby1", "ellip"):
        kw["rp"] = number(rp_db, "rp_db")
    if kind in ("cheby2", "ellip"):
        kw["rs"] = number(rs_db, "rs_db")
    b, a = scipy.signal.iirfilter(int(order), [lo, hi], btype="bandpass", ftype=kind, fs=fs,
                                  output="ba", **kw)
    filt = IIRFilter(b=b, a=a)
    filt.require_stable()
    return filt


#: Stable stand-in for the published filter: order-1 Butterworth band-pass 1-16 Hz at 1 kHz.
DEFAULT_BANDPASS = design_bandpass(1.0, 16.0, FS_HZ, order=1)


@dataclass(frozen=True)
class FbgFrontEnd:
    """Host-side FBG chain: ``current = gain * filter(d_lambda)`` per grating.

    Attributes
    ----------
    filter
        A stable :class:`IIRFilter` (refused at construction otherwise). Default
        :data:`DEFAULT_BANDPASS`; :data:`PUBLISHED_BANDPASS` is refused (unstable).
    gain
        ``S``, current per nm of filtered shift (mV/ms per nm; 180 published).
    fs_hz
        Sampling rate of the traces (1 kHz published).
    """

    filter: IIRFilter = DEFAULT_BANDPASS
    gain: float = DEFAULT_GAIN_S
    fs_hz: float = FS_HZ

    def __post_init__(self):
        if not isinstance(self.filter, IIRFilter):
            raise ValueError(f"filter must be an IIRFilter, got {type(self.filter).__name__}")
        number(self.gain, "gain")
        number(self.fs_hz, "fs_hz", positive=True)
        self.filter.require_stable()

    @property
    def dt_ms(self) -> float:
        return 1000.0 / float(self.fs_hz)

    def currents(self, delta_lambda_nm) -> np.ndarray:
        """Input currents for ``d_lambda`` traces of shape ``(n_samples,)`` or
        ``(n_samples, n_gratings)`` sampled at ``fs_hz``; same shape out (filter along axis 0)."""
        x = _trace(delta_lambda_nm, "delta_lambda_nm")
        out = self.filter.apply(x) * float(self.gain)
        if not np.all(np.isfinite(out)):
            raise ValueError("front-end current overflowed float64")
        return out


def filter_check_report(b, a) -> FilterReport:
    """Stability report for coefficients ``b``, ``a`` (sequences or strings like
    ``"1, -1.919, 0.91"``); used by ``cuneate filter check``. Raises :class:`ValueError` for
    empty/non-finite coefficients or ``a[0] == 0``."""
    return IIRFilter(b=b, a=a).check()
