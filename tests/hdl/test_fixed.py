"""cuneate.hdl.lib.fixed: the RTL (Amaranth) and twin (NumPy) paths of every fixed-point operation
agree bit for bit, the twin agrees with exact rational arithmetic, and QFormat / FixedConstant /
check_int64 keep their contracts."""

import math
from fractions import Fraction

import numpy as np
import pytest
from amaranth.hdl import Module, Signal, Value, signed, unsigned
from amaranth.sim import Simulator

from cuneate.hdl.lib.fixed import (FixedConstant, FixedPointError, QFormat, check_int64, is_hdl,
                               round_shift, round_shift_select, saturate, select)

SEED = 20240611


# ---------------------------------------------------------------------------------------------
# helpers
def _simulate(inputs, outputs, vectors):
    """Drive the combinational ``outputs`` (name -> Amaranth expression of ``inputs``) with each
    tuple of ``vectors`` in ONE simulation; return name -> np.int64 array of observed values
    (and name -> output shape)."""
    m = Module()
    sigs = {}
    for name, expr in outputs.items():
        sig = Signal(Value.cast(expr).shape(), name=f"o_{name}")
        m.d.comb += sig.eq(expr)
        sigs[name] = sig
    got = {name: [] for name in outputs}

    async def testbench(ctx):
        for vec in vectors:
            for sig, val in zip(inputs, vec):
                ctx.set(sig, int(val))
            for name, sig in sigs.items():
                got[name].append(ctx.get(sig))

    sim = Simulator(m)
    sim.add_testbench(testbench)
    sim.run()
    return ({k: np.array(v, dtype=np.int64) for k, v in got.items()},
            {k: s.shape() for k, s in sigs.items()})


def _edge_and_random(width, n_random, rng, extra=()):
    """Signed operands of ``width`` bits: min, max, neighbours, -1 LSB, 0, powers of two and
    half-LSB ties for every shift 1..6 (positive and negative), then seeded random values."""
    lo, hi = -(1 << (width - 1)), (1 << (width - 1)) - 1
    edges = {lo, lo + 1, hi, hi - 1, -1, 0, 1, -2, 2}
    for s in range(1, 7):
        half = 1 << (s - 1)
        for k in (-5, -3, -1, 0, 1, 2, 7):
            edges |= {k * (1 << s) + half, k * (1 << s) - half, k * (1 << s),
                      k * (1 << s) + half - 1, k * (1 << s) + half + 1}
    edges |= set(extra)
    edges = [e for e in edges if lo <= e <= hi]
    rand = rng.integers(lo, hi, size=n_random, endpoint=True, dtype=np.int64)
    return np.concatenate([np.array(sorted(edges), dtype=np.int64), rand])


def _exact_round_shift(x: int, shift: int, rounding: str) -> int:
    """Reference: nearest = floor(x / 2**s + 1/2) (ties toward +inf), truncate = floor(x / 2**s),
    negative shift = exact multiplication; computed with Fractions."""
    q = Fraction(x, 1) / Fraction(2) ** shift
    if shift <= 0:                      # adding fraction bits is exact: nothing to round
        assert q.denominator == 1
        return int(q)
    return math.floor(q + Fraction(1, 2)) if rounding == "nearest" else math.floor(q)


def _clamp(x: int, fmt: QFormat) -> int:
    return max(fmt.min_raw, min(fmt.max_raw, x))


# ---------------------------------------------------------------------------------------------
# 1. RTL (Amaranth simulator) vs twin (NumPy)
@pytest.mark.parametrize("width", [8, 18])
def test_round_shift_rtl_matches_twin_and_exact(width):
    rng = np.random.default_rng(SEED + width)
    xs = _edge_and_random(width, 600, rng)
    x = Signal(signed(width), name="x")
    shifts = [-3, -2, -1, 0, 1, 2, 3, 4, 5, 6]
    outs = {(s, r): round_shift(x, s, r) for s in shifts for r in ("nearest", "truncate")}
    for expr in outs.values():
        assert is_hdl(expr)
    got, _ = _simulate([x], {f"{s}_{r}": e for (s, r), e in outs.items()}, [(v,) for v in xs])
    for (s, r) in outs:
        twin = round_shift(xs, s, r)
        assert twin.dtype == np.int64
        np.testing.assert_array_equal(got[f"{s}_{r}"], twin, err_msg=f"shift={s} {r}")
        exact = np.array([_exact_round_shift(int(v), s, r) for v in xs], dtype=np.int64)
        np.testing.assert_array_equal(twin, exact, err_msg=f"shift={s} {r}")


def test_round_shift_rtl_never_wraps_at_the_extremes():
    """Adding half an LSB to the maximum must not wrap (RTL grows the width)."""
    w = 12
    x = Signal(signed(w))
    vals = [(1 << (w - 1)) - 1, -(1 << (w - 1))]
    got, _ = _simulate([x], {str(s): round_shift(x, s) for s in range(1, 7)},
                       [(v,) for v in vals])
    for s in range(1, 7):
        assert got[str(s)].tolist() == [_exact_round_shift(v, s, "nearest") for v in vals]
        assert got[str(s)][0] == 1 << (w - 1 - s)          # max rounds up to +2**(w-1-s)


SAT_FORMATS = [QFormat(4, 8), QFormat(1, 3), QFormat(2, 16), QFormat(24, 0),
               QFormat(6, 2, signed=False), QFormat(3, 5, signed=False), QFormat(1, 0, False),
               QFormat(1, 0)]


def test_saturate_rtl_matches_twin_and_clamp():
    rng = np.random.default_rng(SEED + 1)
    w = 20
    xs = _edge_and_random(w, 500, rng)
    # values right at / around every format boundary
    extra = []
    for f in SAT_FORMATS:
        for b in (f.min_raw, f.max_raw):
            extra += [b - 1, b, b + 1]
    extra = np.array([e for e in extra if -(1 << (w - 1)) <= e < (1 << (w - 1))], dtype=np.int64)
    xs = np.concatenate([xs, extra])
    ux_vals = rng.integers(0, 1 << 12, size=xs.size, dtype=np.int64)
    ux_vals[:4] = [0, 1, (1 << 12) - 1, 255]
    x = Signal(signed(w))
    ux = Signal(unsigned(12))
    outs = {}
    for i, f in enumerate(SAT_FORMATS):
        outs[f"s{i}"] = saturate(x, f)
        outs[f"u{i}"] = saturate(ux, f)
    got, shapes = _simulate([x, ux], outs, list(zip(xs, ux_vals)))
    for i, f in enumerate(SAT_FORMATS):
        for key, src in ((f"s{i}", xs), (f"u{i}", ux_vals)):
            assert shapes[key].width == f.width and shapes[key].signed == f.signed, (key, f)
            twin = saturate(src, f)
            np.testing.assert_array_equal(got[key], twin, err_msg=f"{key} {f}")
            np.testing.assert_array_equal(
                twin, np.array([_clamp(int(v), f) for v in src]), err_msg=f"{key} {f}")


@pytest.mark.parametrize("rounding", ["nearest", "truncate"])
def test_product_round_saturate_rtl_matches_twin(rounding):
    """The core's pattern: 18x18 signed product, round_shift, saturate to an 18-bit format."""
    rng = np.random.default_rng(SEED + 2)
    w = 18
    lo, hi = -(1 << (w - 1)), (1 << (w - 1)) - 1
    edge = [lo, lo + 1, hi, -1, 0, 1, 1 << 16, -(1 << 16), 3, -3, 1 << 8, -(1 << 8) - 1]
    pairs = [(a, b) for a in edge for b in edge]
    pairs += [(int(a), int(b)) for a, b in rng.integers(lo, hi, size=(500, 2), endpoint=True)]
    # moderate operands whose products land near half-LSB ties after the shift
    small = rng.integers(-600, 600, size=(300, 2))
    pairs += [(int(a), int(b)) for a, b in small]
    av = np.array([p[0] for p in pairs], dtype=np.int64)
    bv = np.array([p[1] for p in pairs], dtype=np.int64)

    a, b = Signal(signed(w)), Signal(signed(w))
    prod = a * b
    cases = [(17, QFormat(2, 16)), (14, QFormat(3, 15)), (20, QFormat(1, 17)),
             (5, QFormat(18, 0)), (1, QFormat(10, 8, signed=False)), (-1, QFormat(12, 6))]
    outs = {f"c{i}": saturate(round_shift(prod, s, rounding), f)
            for i, (s, f) in enumerate(cases)}
    got, shapes = _simulate([a, b], outs, pairs)

    p = av * bv
    check_int64("product", p)
    n_saturated = 0
    for i, (s, f) in enumerate(cases):
        r = round_shift(p, s, rounding)
        check_int64("rounded", r)
        twin = saturate(r, f)
        assert shapes[f"c{i}"].width == f.width
        np.testing.assert_array_equal(got[f"c{i}"], twin, err_msg=f"shift={s} {f}")
        exact = [_clamp(_exact_round_shift(int(x) * int(y), s, rounding), f)
                 for x, y in zip(av, bv)]
        np.testing.assert_array_equal(twin, exact, err_msg=f"shift={s} {f}")
        n_saturated += int(np.sum((twin == f.min_raw) | (twin == f.max_raw)))
    assert n_saturated > 50          # the edge operands really exercised saturation
    # min*min = 2**34 overflows every 18-bit result format: it must clamp to max, never wrap
    k = pairs.index((lo, lo))
    assert got["c0"][k] == QFormat(2, 16).max_raw
    assert got["c3"][k] == QFormat(18, 0).max_raw


@pytest.mark.parametrize("rounding", ["nearest", "truncate"])
@pytest.mark.parametrize("shifts", [[3, 7, 1, 12], [5, 5], [6], [2, 9, 4]])
def test_round_shift_select_rtl_matches_twin(shifts, rounding):
    rng = np.random.default_rng(SEED + 3 + len(shifts))
    w = 24
    xs = _edge_and_random(w, 400, rng)
    idx = rng.integers(0, len(shifts), size=xs.size)
    idx[: len(shifts)] = np.arange(len(shifts))
    x = Signal(signed(w))
    i = Signal(range(max(2, len(shifts))))
    got, _ = _simulate([x, i], {"y": round_shift_select(x, shifts, i, rounding)},
                       list(zip(xs, idx)))
    twin = round_shift_select(xs, shifts, idx, rounding)
    np.testing.assert_array_equal(got["y"], twin)
    exact = [_exact_round_shift(int(v), shifts[k], rounding) for v, k in zip(xs, idx)]
    np.testing.assert_array_equal(twin, exact)
    # and per element it is round_shift with that element's shift
    for k, s in enumerate(shifts):
        sel = idx == k
        np.testing.assert_array_equal(twin[sel], round_shift(xs[sel], s, rounding))


def test_select_rtl_matches_twin():
    rng = np.random.default_rng(SEED + 4)
    w = 16
    av = _edge_and_random(w, 300, rng)
    bv = rng.permutation(av)
    cv = rng.integers(0, 2, size=av.size)
    a, b, c = Signal(signed(w)), Signal(signed(w)), Signal()
    outs = {"mux": select(c, a, b), "min": select(a < b, a, b),
            "mixed": select(c, round_shift(a, 3), saturate(b, QFormat(1, 7)))}
    got, _ = _simulate([a, b, c], outs, list(zip(av, bv, cv)))
    np.testing.assert_array_equal(got["mux"], select(cv.astype(bool), av, bv))
    np.testing.assert_array_equal(got["mux"], np.where(cv == 1, av, bv))
    np.testing.assert_array_equal(got["min"], select(av < bv, av, bv))
    np.testing.assert_array_equal(got["min"], np.minimum(av, bv))
    np.testing.assert_array_equal(
        got["mixed"], select(cv == 1, round_shift(av, 3), saturate(bv, QFormat(1, 7))))


# ---------------------------------------------------------------------------------------------
# 2. twin vs exact arithmetic, independent of the RTL
def test_round_shift_ties_go_toward_plus_infinity():
    x = np.array([-7, -6, -5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 5, 6, 7], dtype=np.int64)
    # x / 2: -3.5 -3 -2.5 -2 -1.5 -1 -0.5 0 0.5 1 1.5 2 2.5 3 3.5
    assert round_shift(x, 1).tolist() == [-3, -3, -2, -2, -1, -1, 0, 0, 1, 1, 2, 2, 3, 3, 4]
    assert round_shift(x, 1, "truncate").tolist() == \
        [-4, -3, -3, -2, -2, -1, -1, 0, 0, 1, 1, 2, 2, 3, 3]
    # x / 4 ties at +-2, +-6: -1.5 -> -1, -0.5 -> 0, 0.5 -> 1, 1.5 -> 2
    assert round_shift(np.array([-6, -2, 2, 6]), 2).tolist() == [-1, 0, 1, 2]
    assert round_shift(-1, 1) == 0 and round_shift(-1, 1, "truncate") == -1   # -1 LSB
    assert round_shift(-3, 2) == -1 and round_shift(-3, 2, "truncate") == -1


def test_twin_matches_exact_arithmetic_on_wide_values():
    rng = np.random.default_rng(SEED + 5)
    xs = np.concatenate([rng.integers(-(1 << 61), 1 << 61, size=400, dtype=np.int64),
                         np.array([-(1 << 61), (1 << 61) - 1, -1, 0, 1], dtype=np.int64)])
    for s in range(1, 40, 3):
        for r in ("nearest", "truncate"):
            twin = round_shift(xs, s, r)
            assert [int(v) for v in twin] == [_exact_round_shift(int(v), s, r) for v in xs]
            # python-int operands take the same path
            assert round_shift(int(xs[0]), s, r) == _exact_round_shift(int(xs[0]), s, r)
    assert round_shift(xs[:10] >> 20, -7).tolist() == [int(v) * 128 for v in xs[:10] >> 20]
    assert round_shift(5, 0) == 5 and round_shift(-5, 0, "truncate") == -5


def test_round_shift_select_twin_and_refusals():
    xs = np.arange(-40, 41, dtype=np.int64)
    idx = np.arange(xs.size) % 3
    shifts = (1, 2, 3)
    got = round_shift_select(xs, shifts, idx)
    assert [int(v) for v in got] == [_exact_round_shift(int(v), shifts[k], "nearest")
                                     for v, k in zip(xs, idx)]
    with pytest.raises(FixedPointError, match=">= 1"):
        round_shift_select(xs, (0, 2), idx % 2)
    with pytest.raises(FixedPointError, match=">= 1"):
        round_shift_select(xs, (-1, 2), idx % 2)
    with pytest.raises(FixedPointError, match="unknown rounding"):
        round_shift(xs, 2, "up")
    with pytest.raises(FixedPointError, match="unknown rounding"):
        round_shift(Signal(signed(8)), 2, "stochastic")


def test_saturate_twin_is_clamp():
    xs = np.arange(-300, 301, dtype=np.int64)
    for f in SAT_FORMATS:
        assert [int(v) for v in saturate(xs, f)] == [_clamp(int(v), f) for v in xs]
    assert saturate(np.array([-1, 0, 256]), QFormat(8, 0, signed=False)).tolist() == [0, 0, 255]
    assert saturate(np.array([-129, 128]), QFormat(8, 0)).tolist() == [-128, 127]


# ---------------------------------------------------------------------------------------------
# 3. QFormat
def test_qformat_geometry():
    f = QFormat(3, 15)
    assert (f.width, f.min_raw, f.max_raw) == (18, -(1 << 17), (1 << 17) - 1)
    assert f.lsb == 2.0 ** -15 and f.min_value == -4.0 and f.max_value == 4.0 - 2.0 ** -15
    assert str(f) == "sQ3.15" and f.shape() == signed(18)
    u = QFormat(4, 4, signed=False)
    assert (u.width, u.min_raw, u.max_raw, u.min_value, u.max_value) == (8, 0, 255, 0.0, 15.9375)
    assert str(u) == "uQ4.4" and u.shape() == unsigned(8)
    g = QFormat(20, -3)          # negative fraction bits: LSB of 8
    assert g.width == 17 and g.lsb == 8.0 and g.max_value == ((1 << 16) - 1) * 8.0
    assert f.contains(-4.0) and f.contains(f.max_value) and not f.contains(4.0)
    d = f.to_dict()
    assert d["format"] == "sQ3.15" and d["width"] == 18 and d["min"] == -4.0
    with pytest.raises(FixedPointError, match="no bits"):
        QFormat(0, 0)
    with pytest.raises(FixedPointError, match="sign bit"):
        QFormat(0, 8)
    QFormat(0, 8, signed=False)  # fine: uQ0.8


def test_qformat_to_raw_rounding_and_saturation():
    f = QFormat(4, 4)            # lsb 1/16, range [-8, 8 - 1/16]
    # ties toward +inf for nearest, floor for truncate
    assert f.to_raw(1 / 32) == 1 and f.to_raw(-1 / 32) == 0 and f.to_raw(-3 / 32) == -1
    assert f.to_raw(1 / 32, "truncate") == 0 and f.to_raw(-1 / 32, "truncate") == -1
    assert f.to_raw(0.3) == 5 and f.to_raw(0.3, "truncate") == 4
    # saturation (default) and refusal
    assert f.to_raw(100.0) == f.max_raw and f.to_raw(-100.0) == f.min_raw
    assert f.to_raw(7.99) == f.max_raw           # rounds to 128 -> clamps to 127
    with pytest.raises(FixedPointError, match="outside"):
        f.to_raw(8.0, clamp=False)
    with pytest.raises(FixedPointError, match="outside"):
        f.to_raw([0.0, -8.1], clamp=False)
    assert f.to_raw(-8.0, clamp=False) == f.min_raw
    for bad in (float("nan"), float("inf"), -float("inf"), [1.0, float("nan")]):
        with pytest.raises(FixedPointError, match="non-finite"):
            f.to_raw(bad)
    # scalar in -> int out; array in -> int64 array out
    assert isinstance(f.to_raw(1.0), int)
    arr = f.to_raw(np.array([[0.5, -0.5], [1.0, 2.0]]))
    assert arr.dtype == np.int64 and arr.shape == (2, 2) and arr.tolist() == [[8, -8], [16, 32]]
    u = QFormat(2, 6, signed=False)
    assert u.to_raw(-1.0) == 0 and u.to_raw(5.0) == 255
    with pytest.raises(FixedPointError):
        u.to_raw(-0.01, clamp=False)
    # negative fraction bits
    g = QFormat(12, -2)
    assert g.to_raw(6.0) == 2 and g.to_raw(5.9, "truncate") == 1 and g.to_raw(-6.0) == -1


@pytest.mark.parametrize("fmt", [QFormat(4, 14), QFormat(1, 17), QFormat(8, 10, False),
                                 QFormat(20, -2)])
def test_qformat_to_raw_matches_exact_reference(fmt):
    rng = np.random.default_rng(SEED + 6)
    xs = rng.uniform(fmt.min_value * 1.1 - 1, fmt.max_value * 1.1 + 1, size=2000)
    # exact ties (half-LSB) and exact grid points, both signs
    k = rng.integers(-(1 << 10), 1 << 10, size=200)
    xs = np.concatenate([xs, (k + 0.5) * fmt.lsb, k * fmt.lsb])
    for rounding in ("nearest", "truncate"):
        got = fmt.to_raw(xs, rounding)
        ref = []
        for x in xs:
            q = Fraction(float(x)) * Fraction(2) ** fmt.frac_bits
            if rounding == "nearest":
                q += Fraction(1, 2)
            ref.append(_clamp(math.floor(q), fmt))
        np.testing.assert_array_equal(got, ref)
        assert np.all(np.abs(fmt.to_float(got) - np.clip(xs, fmt.min_value, fmt.max_value))
                      <= fmt.lsb * (0.5 if rounding == "nearest" else 1.0))


@pytest.mark.parametrize("fmt, x, expected", [
    (QFormat(8, 0), 0.49999999999999994, 0),             # 0.5 - 2**-54 -> must round to 0
    (QFormat(8, 4), 0.49999999999999994 / 16, 0),
    (QFormat(60, 0), 2.0 ** 52 + 1, 2 ** 52 + 1),         # exact integer must stay exact
])
def test_qformat_to_raw_float_double_rounding(fmt, x, expected):
    assert fmt.to_raw(x) == expected


def _for_range_reference(lo, hi, width, signed_):
    """Brute force: the format with the most fraction bits (fewest int bits >= 1) holding both."""
    for ib in range(1, 200):
        f = QFormat(ib, width - ib, signed_)
        if f.contains(lo) and f.contains(hi):
            return f
    raise AssertionError("no format")


@pytest.mark.parametrize("lo, hi, width, signed_", [
    (-0.999, 0.999, 18, True), (-0.999, 1.0, 18, True), (-100.0, 30.0, 18, True),
    (-0.3, 0.3, 18, True), (-3e-5, 2e-5, 16, True), (0.0, 4.0, 18, True), (-70.0, 70.0, 18, True),
    (-3.99, 3.99, 18, True), (-1e6, 1e6, 18, True), (0.0, 1.0, 8, False), (0.0, 255.0, 8, False),
    (0.0, 0.99, 8, False), (0.0, 1000.0, 12, False), (-2.0 ** 17 + 1, 2.0 ** 17 - 1, 18, True),
])
def test_qformat_for_range_picks_most_fraction_bits(lo, hi, width, signed_):
    f = QFormat.for_range(lo, hi, width, signed_)
    assert f.width == width and f.signed == signed_
    assert f.contains(lo) and f.contains(hi)
    assert f == _for_range_reference(lo, hi, width, signed_)
    # one more fraction bit would not hold the range
    if f.int_bits > 1:
        tighter = QFormat(f.int_bits - 1, f.frac_bits + 1, signed_)
        assert not (tighter.contains(lo) and tighter.contains(hi))


def test_qformat_for_range_random_against_brute_force():
    rng = np.random.default_rng(SEED + 7)
    for _ in range(300):
        a, b = sorted(rng.uniform(-1, 1, size=2) * 10.0 ** rng.uniform(-4, 6))
        w = int(rng.integers(8, 33))
        assert QFormat.for_range(a, b, w) == _for_range_reference(a, b, w, True), (a, b, w)


@pytest.mark.parametrize("lo, hi, expected", [
    (-1.0, 0.5, QFormat(1, 17)), (-1.0, 0.999, QFormat(1, 17)), (-4.0, 0.0, QFormat(3, 15)),
    (-64.0, 10.0, QFormat(7, 11)), (-2.0 ** 17, 2.0 ** 17 - 1, QFormat(18, 0)),
])
def test_qformat_for_range_negative_power_of_two_bound(lo, hi, expected):
    assert QFormat.for_range(lo, hi, 18) == expected


# ---------------------------------------------------------------------------------------------
# 4. FixedConstant
@pytest.mark.parametrize("width, signed_", [(18, True), (8, True), (25, True), (18, False),
                                            (8, False)])
def test_fixed_constant_normalized_uses_full_width(width, signed_):
    rng = np.random.default_rng(SEED + width)
    mags = 10.0 ** rng.uniform(-8, 8, size=500)
    specials = [1.0, 0.5, 2.0, 3.0, 1 / 3, math.pi, 1e-3, 0.0625, 1000.0,
                math.nextafter(1.0, 0.0), math.nextafter(16.0, 0.0), math.nextafter(2.0, 4.0)]
    values = list(mags) + specials
    if signed_:
        values += [-v for v in values]
    mag_bits = width - 1 if signed_ else width
    for v in values:
        c = FixedConstant.normalized("k", float(v), width, signed_)
        assert c.width == width and c.signed == signed_ and c.value == v
        assert (1 << (mag_bits - 1)) <= abs(c.raw) < (1 << mag_bits), (v, c)
        assert c.quantized == c.raw * 2.0 ** -c.frac_bits
        assert Fraction(c.raw) / Fraction(2) ** c.frac_bits == Fraction(c.quantized)
        # half an LSB at worst, on a mantissa of at least 2**(mag_bits-1)
        assert abs(c.rel_error) <= 2.0 ** -mag_bits * (1 + 1e-12), (v, c.rel_error)
        err = abs(Fraction(c.raw) / Fraction(2) ** c.frac_bits - Fraction(v))
        assert err <= Fraction(1, 2) * Fraction(2) ** -c.frac_bits
        assert abs(c.abs_error) <= 2.0 ** -(c.frac_bits + 1)
    if signed_:
        assert abs(FixedConstant.normalized("k", 0.7, width).rel_error) <= 2.0 ** -(width - 1)


def test_fixed_constant_normalized_rounding_carry():
    # 1 - 2**-20 scaled to 17 fraction bits is 2**17 - 1/8, which rounds to 2**17: one bit too
    # many for an 18-bit signed operand, so the shift drops by one.
    v = 1.0 - 2.0 ** -20
    c = FixedConstant.normalized("carry", v, 18)
    assert (c.raw, c.frac_bits) == (1 << 16, 16)
    assert abs(c.raw) < 1 << 17 and abs(c.rel_error) <= 2.0 ** -17
    n = FixedConstant.normalized("carry", -v, 18)
    assert abs(n.raw) < 1 << 17 and abs(n.raw) >= 1 << 16 and n.raw < 0
    assert abs(n.rel_error) <= 2.0 ** -17
    u = FixedConstant.normalized("carry", v, 8, signed=False)
    assert (u.raw, u.frac_bits) == (1 << 7, 7)
    # the largest value that does NOT carry keeps the extra bit
    ok = FixedConstant.normalized("nocarry", 1.0 - 2.0 ** -16, 18)
    assert (ok.raw, ok.frac_bits) == ((1 << 17) - 2, 17)


def test_fixed_constant_normalized_refusals_and_zero():
    z = FixedConstant.normalized("z", 0.0, 18)
    assert z.raw == 0 and z.quantized == 0.0 and z.rel_error == 0.0
    for bad in (float("nan"), float("inf"), -float("inf")):
        with pytest.raises(FixedPointError, match="not finite"):
            FixedConstant.normalized("bad", bad, 18)
    with pytest.raises(FixedPointError, match="negative but unsigned"):
        FixedConstant.normalized("neg", -0.5, 18, signed=False)
    with pytest.raises(FixedPointError, match="relative"):
        FixedConstant.normalized("third", 1 / 3, 8, max_rel_error=1e-4)
    c = FixedConstant.normalized("third", 1 / 3, 8, max_rel_error=2.0 ** -7)
    assert abs(c.rel_error) <= 2.0 ** -7
    d = c.to_dict()
    assert d["raw"] == c.raw and d["frac_bits"] == c.frac_bits and d["rel_error"] == c.rel_error


def test_fixed_constant_in_format():
    f = QFormat(2, 6)            # lsb 1/64, [-2, 2 - 1/64]
    c = FixedConstant.in_format("q", 0.25, f, exact=True)
    assert (c.raw, c.frac_bits, c.width, c.signed, c.abs_error) == (16, 6, 8, True, 0.0)
    c = FixedConstant.in_format("tenth", 0.1, f)
    assert c.raw == f.to_raw(0.1) == 6 and abs(c.abs_error) <= f.lsb / 2
    assert c.rel_error == pytest.approx((6 / 64 - 0.1) / 0.1)
    with pytest.raises(FixedPointError, match="not exactly representable"):
        FixedConstant.in_format("tenth", 0.1, f, exact=True)
    with pytest.raises(FixedPointError, match="does not fit"):
        FixedConstant.in_format("big", 2.0, f)
    with pytest.raises(FixedPointError, match="does not fit"):
        FixedConstant.in_format("small", -2.01, f)
    assert FixedConstant.in_format("min", -2.0, f, exact=True).raw == -128
    with pytest.raises(FixedPointError, match="does not fit"):
        FixedConstant.in_format("neg", -0.5, QFormat(2, 6, signed=False))
    with pytest.raises(FixedPointError, match="relative"):
        FixedConstant.in_format("tenth", 0.1, f, max_rel_error=0.01)
    assert FixedConstant.in_format("tenth", 0.1, f, max_rel_error=0.07).raw == 6
    for bad in (float("nan"), float("inf"), -float("inf")):
        with pytest.raises(FixedPointError, match="not finite"):
            FixedConstant.in_format("bad", bad, f)


# ---------------------------------------------------------------------------------------------
# 5. check_int64
def test_check_int64_guard():
    check_int64("ok", np.array([(1 << 62) - 1, -((1 << 62) - 1), 0], dtype=np.int64))
    check_int64("empty", np.array([], dtype=np.int64))
    check_int64("scalar", 12345)
    for bad in ([1 << 62], [-(1 << 62)], [0, (1 << 63) - 1], [5, (1 << 62) + 7, -3]):
        with pytest.raises(OverflowError, match="2\\*\\*62"):
            check_int64("bad", np.array(bad, dtype=np.int64))
    # the guard catches a product of two operands that would not fit
    a = np.array([1 << 31], dtype=np.int64)
    with pytest.raises(OverflowError):
        check_int64("p", a * a)
    check_int64("p", (a - 1) * (a - 1))


def test_check_int64_catches_int64_min():
    with pytest.raises(OverflowError):
        check_int64("wrapped", np.array([np.iinfo(np.int64).min, 1], dtype=np.int64))
