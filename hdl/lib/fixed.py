"""The one definition of fixed-point arithmetic, shared by the Amaranth RTL and the NumPy twins.

Every operation here is written once and works on two kinds of operand:

* NumPy ``int64`` arrays (or Python ints): the bit-exact twins;
* Amaranth values: the RTL.

Values are raw two's-complement integers ``raw = round(x * 2**frac_bits)`` in a :class:`QFormat`.
Rules:

* **Rounding.** :func:`round_shift` drops fraction bits either by round-to-nearest (ties toward
  +infinity, i.e. add half an LSB then floor) — the default — or by truncation (floor).
* **Saturation, never wrap.** Every narrowing goes through :func:`saturate`, which clamps to the
  target format's range. Products and sums in between are computed at full width (Amaranth grows
  widths; the twins assert that no int64 intermediate comes near 2**62).
* **Constants** are quantized once, with their representation error recorded
  (:class:`FixedConstant`), either in a given format or normalized to use a whole operand
  (mantissa plus shift: the most precise constant an 18-bit multiplier can take).
* **Products** of a datapath are formed by :func:`product`, each named by the multiplier it
  is (its ``site``), and narrowings by :func:`narrow`. :func:`arithmetic_hooks` is the one
  documented hook through which a proof harness sees them: inside its ``with`` block the
  products of Amaranth values are the hook's values (uninterpreted products,
  :class:`cuneate.hdl.lib.formal.UninterpretedProducts`) and each narrowing is reported. The
  hook is a context variable: nothing outside the block (no module, no Amaranth class) is
  changed, the twin's NumPy arithmetic never sees it.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from amaranth.hdl import Const, Mux, Value, ValueCastable, signed, unsigned

__all__ = [
    "ROUNDINGS", "QFormat", "FixedConstant", "FixedPointError", "is_hdl", "round_shift",
    "round_shift_add",
    "round_shift_select", "saturate", "narrow", "clamp_flagged", "round_clamp_flagged", "select",
    "check_int64", "tree_sum",
    "tally_clamps", "clamp_report", "store_raw", "product", "arithmetic_hooks",
]

ROUNDINGS = ("nearest", "truncate")
_INT64_GUARD = 1 << 62


class FixedPointError(ValueError):
    """A format or constant that cannot hold what it is asked to hold."""


@dataclass(frozen=True)
class QFormat:
    """A fixed-point format: ``int_bits`` integer bits (including the sign bit when signed) and
    ``frac_bits`` fraction bits; width ``int_bits + frac_bits``."""

    int_bits: int
    frac_bits: int
    signed: bool = True

    def __post_init__(self):
        if self.width < 1:
            raise FixedPointError(f"format {self} has no bits")
        if self.signed and self.int_bits < 1:
            raise FixedPointError(f"signed format {self} needs at least the sign bit")

    def __str__(self):
        return f"{'s' if self.signed else 'u'}Q{self.int_bits}.{self.frac_bits}"

    @property
    def width(self) -> int:
        return self.int_bits + self.frac_bits

    @property
    def min_raw(self) -> int:
        return -(1 << (self.width - 1)) if self.signed else 0

    @property
    def max_raw(self) -> int:
        return (1 << (self.width - 1)) - 1 if self.signed else (1 << self.width) - 1

    @property
    def lsb(self) -> float:
        return 2.0 ** -self.frac_bits

    @property
    def min_value(self) -> float:
        return self.min_raw * self.lsb

    @property
    def max_value(self) -> float:
        return self.max_raw * self.lsb

    def shape(self):
        return signed(self.width) if self.signed else unsigned(self.width)

    def contains(self, x: float) -> bool:
        return self.min_value <= x <= self.max_value

    def to_raw(self, x, rounding: str = "nearest", clamp: bool = True):
        """Quantize real value(s) to raw integers (saturating when ``clamp``; else refusing)."""
        arr = np.asarray(x, dtype=np.float64)
        if not np.all(np.isfinite(arr)):
            raise FixedPointError(f"cannot represent non-finite value(s) in {self}")
        scaled = np.ldexp(arr, self.frac_bits)          # exact: scaling by a power of two
        raw = np.floor(scaled)
        if rounding == "nearest":                      # exact: scaled - floor(scaled) is exact
            raw = raw + (scaled - raw >= 0.5)
        if not clamp and (np.any(raw < self.min_raw) or np.any(raw > self.max_raw)):
            bad = arr[(raw < self.min_raw) | (raw > self.max_raw)].ravel()[0]
            raise FixedPointError(f"value {bad:g} is outside {self} "
                                  f"[{self.min_value:g}, {self.max_value:g}]")
        raw = np.clip(raw, self.min_raw, self.max_raw).astype(np.int64)
        return int(raw) if raw.ndim == 0 else raw

    def to_float(self, raw):
        return np.asarray(raw, dtype=np.float64) * self.lsb

    def to_dict(self) -> dict:
        return {"format": str(self), "int_bits": self.int_bits, "frac_bits": self.frac_bits,
                "signed": self.signed, "width": self.width, "lsb": self.lsb,
                "min": self.min_value, "max": self.max_value}

    @staticmethod
    def for_range(lo: float, hi: float, width: int, signed_: bool = True) -> "QFormat":
        """The format of ``width`` bits with the most fraction bits that still holds [lo, hi]."""
        for int_bits in range(1, width + 129):   # more int bits than width: negative frac
            fmt = QFormat(int_bits, width - int_bits, signed_)
            if fmt.contains(lo) and fmt.contains(hi):
                return fmt
        raise FixedPointError(f"no {width}-bit {'signed' if signed_ else 'unsigned'} format "
                              f"holds [{lo:g}, {hi:g}]")

    @staticmethod
    def for_raw(lo: int, hi: int, frac_bits: int) -> "QFormat":
        """The narrowest signed format with ``frac_bits`` fraction bits holding the raw
        integers ``lo .. hi`` (at least one integer bit)."""
        width = max(x.bit_length() if x >= 0 else (-x - 1).bit_length() for x in (lo, hi)) + 1
        return QFormat(max(width - frac_bits, 1), frac_bits)


@dataclass(frozen=True)
class FixedConstant:
    """A real constant quantized to ``raw * 2**-frac_bits`` in ``width`` bits."""

    name: str
    value: float
    raw: int
    frac_bits: int
    width: int
    signed: bool = True

    @property
    def quantized(self) -> float:
        return self.raw * 2.0 ** -self.frac_bits

    @property
    def abs_error(self) -> float:
        return self.quantized - self.value

    @property
    def rel_error(self) -> float:
        return self.abs_error / self.value if self.value != 0 else 0.0

    @classmethod
    def in_format(cls, name: str, value: float, fmt: QFormat, max_rel_error: float | None = None,
                  exact: bool = False) -> "FixedConstant":
        """Quantize ``value`` in ``fmt``; refuse if it does not fit, is not exact when ``exact``,
        or misses ``max_rel_error``."""
        if not math.isfinite(value):
            raise FixedPointError(f"constant {name} = {value!r} is not finite")
        if not fmt.contains(value):
            raise FixedPointError(f"constant {name} = {value:g} does not fit {fmt} "
                                  f"[{fmt.min_value:g}, {fmt.max_value:g}]")
        c = cls(name, value, fmt.to_raw(value), fmt.frac_bits, fmt.width, fmt.signed)
        if exact and c.abs_error != 0:
            raise FixedPointError(f"constant {name} = {value:g} is not exactly representable in "
                                  f"{fmt} (error {c.abs_error:.3g})")
        c._check_rel(max_rel_error)
        return c

    @classmethod
    def normalized(cls, name: str, value: float, width: int, signed: bool = True,
                   max_rel_error: float | None = None) -> "FixedConstant":
        """Quantize ``value`` with as many fraction bits as ``width`` allows (mantissa + shift)."""
        if not math.isfinite(value):
            raise FixedPointError(f"constant {name} = {value!r} is not finite")
        if value == 0:
            return cls(name, 0.0, 0, 0, width, signed)
        if value < 0 and not signed:
            raise FixedPointError(f"constant {name} = {value:g} is negative but unsigned")
        mag_bits = width - 1 if signed else width
        frac = mag_bits - 1 - math.floor(math.log2(abs(value)))
        raw = int(math.floor(value * 2.0 ** frac + 0.5))
        if abs(raw) >= (1 << mag_bits):       # rounding carried into a new bit
            frac -= 1
            raw = int(math.floor(value * 2.0 ** frac + 0.5))
        c = cls(name, value, raw, frac, width, signed)
        c._check_rel(max_rel_error)
        return c

    @classmethod
    def scaled(cls, name: str, value: float, frac_bits: int, width: int, signed: bool = True,
               max_rel_error: float | None = None) -> "FixedConstant":
        """Quantize ``value`` as ``raw * 2**-frac_bits`` in ``width`` bits (any ``frac_bits``,
        also more than ``width``, as for a shared exponent); refuse if it does not fit."""
        if not math.isfinite(value):
            raise FixedPointError(f"constant {name} = {value!r} is not finite")
        raw = int(math.floor(math.ldexp(value, frac_bits) + 0.5))
        lo, hi = (-(1 << (width - 1)), (1 << (width - 1)) - 1) if signed else (0, (1 << width) - 1)
        if not lo <= raw <= hi:
            raise FixedPointError(f"constant {name} = {value:g} does not fit {width} bits with "
                                  f"{frac_bits} fraction bits")
        c = cls(name, value, raw, frac_bits, width, signed)
        c._check_rel(max_rel_error)
        return c

    def _check_rel(self, max_rel_error):
        if max_rel_error is not None and abs(self.rel_error) > max_rel_error:
            raise FixedPointError(f"constant {self.name} = {self.value:g} has relative "
                                  f"representation error {self.rel_error:.3g} > "
                                  f"{max_rel_error:g} in {self.width} bits")

    def to_dict(self) -> dict:
        return {"value": self.value, "raw": self.raw, "frac_bits": self.frac_bits,
                "width": self.width, "quantized": self.quantized,
                "abs_error": self.abs_error, "rel_error": self.rel_error}


# ----------------------------------------------------------------------------------------------
# Operations, written once for NumPy ints and Amaranth values.

def is_hdl(x) -> bool:
    return isinstance(x, (Value, ValueCastable))


def select(cond, a, b):
    """``a`` where ``cond`` else ``b`` (``Mux`` for RTL, ``np.where`` for the twin)."""
    if is_hdl(cond) or is_hdl(a) or is_hdl(b):
        return Mux(cond, a, b)
    return np.where(cond, a, b)


def round_shift(x, shift: int, rounding: str = "nearest"):
    """Drop ``shift`` fraction bits (``shift < 0`` adds bits, exactly).

    Round-to-nearest is ``floor(x / 2**shift + 1/2)``, computed as ``(x >> shift) + bit`` where
    ``bit`` is bit ``shift - 1`` of ``x`` (the first dropped bit). That equals
    ``(x + 2**(shift-1)) >> shift`` exactly, but in hardware it is a carry-in of the next adder
    instead of a full-width addition in front of it.
    """
    if rounding not in ROUNDINGS:
        raise FixedPointError(f"unknown rounding {rounding!r}; known: {ROUNDINGS}")
    if shift <= 0:
        return x << -shift if shift else x
    if rounding == "truncate":
        return x >> shift
    if is_hdl(x):
        return (x >> shift) + x[shift - 1]
    return (x >> shift) + ((x >> (shift - 1)) & 1)


def round_shift_add(x, const: int, shift: int, rounding: str = "nearest"):
    """``round_shift(x + const, shift)`` for a ``const`` whose low ``shift`` bits are zero,
    computed as ``(x >> shift) + (const >> shift) + first dropped bit``: one adder, not two."""
    if shift <= 0 or const % (1 << shift):
        return round_shift(x + const, shift, rounding)
    if rounding == "truncate":
        return (x >> shift) + (const >> shift)
    bit = x[shift - 1] if is_hdl(x) else (x >> (shift - 1)) & 1
    return (x >> shift) + (const >> shift) + bit


def round_shift_select(x, shifts: Sequence[int], index, rounding: str = "nearest"):
    """:func:`round_shift` by ``shifts[index]``, where ``index`` varies per element/cycle."""
    if is_hdl(x) or is_hdl(index):
        distinct = sorted(set(int(s) for s in shifts))
        if len(distinct) == 1:
            return round_shift(x, distinct[0], rounding)
        return _mux_tree([round_shift(x, int(s), rounding) for s in shifts], index)
    s = np.asarray(shifts, dtype=np.int64)[np.asarray(index)]
    x = np.asarray(x, dtype=np.int64)
    if np.any(s <= 0):
        raise FixedPointError("variable shifts must be >= 1")
    if rounding == "nearest":
        return (x >> s) + ((x >> (s - 1)) & 1)
    return x >> s


def _mux_tree(options, index):
    out = options[-1]
    for i in range(len(options) - 2, -1, -1):
        out = Mux(index == i, options[i], out)
    return out


def saturate(x, fmt: QFormat, bounds: tuple[int, int] | None = None):
    """Clamp ``x`` into ``fmt`` (the result has ``fmt``'s width in RTL).

    ``bounds`` are proven raw bounds ``(lo, hi)`` of ``x``. When they lie inside ``fmt`` no
    value can overflow, so no clamp logic is built (the result is only resized); otherwise
    the clamp is built as usual. Saturation is never replaced by wrapping.
    """
    fits = bounds is not None and fmt.min_raw <= bounds[0] <= bounds[1] <= fmt.max_raw
    if fits:
        if is_hdl(x):
            return x[:fmt.width].as_signed() if fmt.signed else x[:fmt.width]
        return x
    if is_hdl(x):
        lo = Const(fmt.min_raw, fmt.shape())
        hi = Const(fmt.max_raw, fmt.shape())
        clamped = Mux(x > fmt.max_raw, hi, Mux(x < fmt.min_raw, lo, x))
        return clamped[:fmt.width].as_signed() if fmt.signed else clamped[:fmt.width]
    return np.clip(x, fmt.min_raw, fmt.max_raw)


#: the hooks of :func:`arithmetic_hooks` active in this context (None: plain arithmetic)
_HOOKS: contextvars.ContextVar = contextvars.ContextVar("cuneate_fixed_hooks", default=None)


@contextlib.contextmanager
def arithmetic_hooks(product=None, narrow=None):
    """Inside the ``with`` block, :func:`product` of Amaranth operands returns
    ``product(a, b, site)`` (a value of the product's shape: a harness's uninterpreted product)
    and :func:`narrow` of an Amaranth value calls ``narrow(x, bounds, name)`` before it
    narrows (a harness asserting each narrowing's bounds). Either may be None; an inner block
    replaces an outer one until it ends. NumPy operands are never hooked."""
    token = _HOOKS.set((product, narrow))
    try:
        yield
    finally:
        _HOOKS.reset(token)


def product(a, b, site: str):
    """``a * b`` at full width: every multiplier of a datapath's stage functions, named by
    ``site`` (the same name wherever the same multiplier is formed - the core, its twin and a
    proof's reference call the same stage function). A harness may replace it
    (:func:`arithmetic_hooks`)."""
    hooks = _HOOKS.get()
    if hooks is not None and hooks[0] is not None and (is_hdl(a) or is_hdl(b)):
        return hooks[0](a, b, site)
    return a * b


def narrow(x, fmt: QFormat, bounds: tuple[int, int], name: str = "value"):
    """Resize ``x`` to ``fmt`` where its proven raw ``bounds`` fit: no clamp, no flag. Raises
    :class:`FixedPointError` (at construction, when the RTL or the twin is built) if they do
    not: an unflagged narrowing that could clamp is never built. A harness sees each
    narrowing of an Amaranth value (:func:`arithmetic_hooks`)."""
    lo, hi = bounds
    if not fmt.min_raw <= lo <= hi <= fmt.max_raw:
        raise FixedPointError(f"{name}: proven range [{lo}, {hi}] (raw) does not fit {fmt}; "
                              f"a clamp here would be silent")
    if is_hdl(x):
        hooks = _HOOKS.get()
        if hooks is not None and hooks[1] is not None:
            hooks[1](x, bounds, name)
        v = x[:fmt.width]
        return v.as_signed() if fmt.signed else v
    return x


def clamp_flagged(x, lo: int, hi: int, fmt: QFormat, bounds: tuple[int, int] | None = None):
    """Clamp ``x`` into the raw interval ``[lo, hi]`` (inside ``fmt``) and say when it acted.

    Returns ``(value, below, above)``: ``value`` has ``fmt``'s width in RTL; ``below`` /
    ``above`` are true exactly when ``x < lo`` / ``x > hi`` (the clamp changed the value). When
    the proven ``bounds`` of ``x`` lie inside ``[lo, hi]`` no comparator is built and both flags
    are constant false. This is the one place where a saturation that can act is built, so that
    it is never silent.
    """
    if not fmt.min_raw <= lo <= hi <= fmt.max_raw:
        raise FixedPointError(f"clamp levels [{lo}, {hi}] are outside {fmt}")
    fits = bounds is not None and lo <= bounds[0] <= bounds[1] <= hi
    if is_hdl(x):
        if fits:
            v = x[:fmt.width]
            return (v.as_signed() if fmt.signed else v), Const(0, 1), Const(0, 1)
        below, above = x < lo, x > hi
        clamped = Mux(above, Const(hi, fmt.shape()), Mux(below, Const(lo, fmt.shape()), x))
        v = clamped[:fmt.width]
        return (v.as_signed() if fmt.signed else v), below, above
    arr = np.asarray(x)
    if fits:
        z = np.zeros(arr.shape, dtype=bool)
        return arr, z, z
    below, above = arr < lo, arr > hi
    return np.clip(arr, lo, hi), below, above


def round_clamp_flagged(x, shift: int, rounding: str, lo: int, hi: int, fmt: QFormat,
                        bounds: tuple[int, int] | None = None):
    """``clamp_flagged(round_shift(x, shift, rounding), lo, hi, fmt, bounds)``, exact at every
    ``shift`` on both operands, the twin's int64 included (``bounds``: of the rounded value).

    Where bits are added (``shift < 0``) and the clamp can act, ``x`` itself is compared with the
    levels on its own grid (``x << k > hi`` exactly when ``x > hi >> k``, ``x << k < lo`` when
    ``x < -((-lo) >> k)``) and only a value inside them is shifted, by at most ``fmt``'s width
    (a larger shift leaves 0 as the only such value): no intermediate is wider than ``x`` plus
    that, so nothing can wrap in the twin and no comparator wider than ``x`` is built."""
    if shift >= 0:
        return clamp_flagged(round_shift(x, shift, rounding), lo, hi, fmt, bounds)
    k = -shift
    if bounds is not None and lo <= bounds[0] <= bounds[1] <= hi:
        return clamp_flagged(x << k, lo, hi, fmt, bounds)     # proven to fit: no clamp
    if not fmt.min_raw <= lo <= hi <= fmt.max_raw:
        raise FixedPointError(f"clamp levels [{lo}, {hi}] are outside {fmt}")
    lo_x, hi_x = -((-lo) >> k), hi >> k
    below, above = x < lo_x, x > hi_x
    k = min(k, fmt.width)
    if is_hdl(x):
        inside = Mux(below | above, 0, x) << k
        v = Mux(above, Const(hi, fmt.shape()), Mux(below, Const(lo, fmt.shape()), inside))
        v = v[:fmt.width]
        return (v.as_signed() if fmt.signed else v), below, above
    arr = np.asarray(x)
    inside = np.where(below | above, 0, arr) << k
    return np.where(above, hi, np.where(below, lo, inside)), below, above


def tree_sum(terms, zero=0):
    """The sum of ``terms`` as a balanced tree of two-input adds: exact integers on both kinds
    of operand (Amaranth grows each sum by a bit), an expression ``log2(n)`` deep instead of
    ``n`` (a fan-in of thousands elaborates; a chain that deep exceeds Python's recursion
    limit). ``zero``: the sum of no terms."""
    terms = list(terms)
    if not terms:
        return zero
    while len(terms) > 1:
        terms = [terms[i] + terms[i + 1] if i + 1 < len(terms) else terms[i]
                 for i in range(0, len(terms), 2)]
    return terms[0]


def tally_clamps(twin, kinds, counts) -> None:
    """Add one sweep's (or run's) clamp counts per kind (``counts[i]`` for ``kinds[i]``) to a
    twin's ``clamp_counts`` and set its ``clamp_sticky`` bits, as the RTL's counters and sticky
    flags do: a clamp that acted is never silent."""
    for i, k in enumerate(kinds):
        n = int(counts[i])
        twin.clamp_counts[k] += n
        if n:
            twin.clamp_sticky |= 1 << i



def store_raw(dest, fmt: QFormat, values, index=None):
    """Quantize ``values`` to ``fmt`` (saturating to the format, like the host driver) into the
    int64 array ``dest`` (all of it, or at ``index``); returns the raw values."""
    raw = fmt.to_raw(values)
    if index is None:
        dest[:] = raw
    else:
        dest[index] = raw
    return raw


def clamp_report(twin, kinds) -> dict:
    """A twin's sticky clamp flags (per kind, from its bit mask) and counts per kind, for
    reports and ``simulate --json``."""
    return {"sticky": {k: bool(twin.clamp_sticky >> i & 1) for i, k in enumerate(kinds)},
            "counts": dict(twin.clamp_counts)}


def check_int64(name: str, x) -> None:
    """Twin guard: refuse any int64 intermediate that could have overflowed."""
    arr = np.asarray(x)
    if arr.size and (int(np.max(arr)) >= _INT64_GUARD or int(np.min(arr)) <= -_INT64_GUARD):
        raise OverflowError(f"twin intermediate {name} reached 2**62; the format choice would "
                            f"overflow int64")
