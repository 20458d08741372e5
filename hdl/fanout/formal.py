"""The channel fan-out's one-entry datapath against its specification, for every gain and every
sample, with SymbiYosys (a combinational check of depth 1: a pass covers every input).

The design side is what :class:`~cuneate.hdl.fanout.ChannelFanout` builds for one table entry:
its stages :meth:`~cuneate.hdl.fanout.ChannelFanout.rectify_gate`, ``product`` and
``to_current`` (its documented hooks, taken from the class or, for a mutant, from a subclass
that replaces one), with the core's register widths between them (``r_width``, ``p_width``). The
specification is written here, at unbounded width (Amaranth grows every result): ``r`` = ``s``,
``max(s, 0)`` or ``|s|`` by the mode, 0 where the entry is gated and ``s < theta`` (asserted
equal to the design's rectified sample); ``p = r g`` (formed from that sample, so the solver
compares one product, not two multipliers; asserted equal to the design's product register: its
width holds it); ``x = floor(p / 2**shift + 1/2)`` (nearest) or ``floor(p / 2**shift)``
(truncate) or ``p * 2**-shift`` for a negative shift (bits added: a gain whose exponent is
larger than the current's LSB); the current is ``x`` clamped into the current format, ``below``
/ ``above`` exactly when the clamp acts. Free: the sample ``s`` (the whole sample format), the
gain's raw word ``g`` (every value between the table's smallest and largest raw gain: every gain
of that shared exponent), the threshold (any raw sample), the gate bit, and the mode (any mode
the table uses: the configuration decides from them whether a clamp is built).
:data:`PROOF_TABLES` are the configurations ``cuneate prove fanout`` proves: the rounding both
ways, a positive shift, a zero shift, bits added (a few, and more than the current's width: the
gains of about 1e18 the twin once wrapped in int64), and a table whose clamp is not built.

Mutants (:data:`MUTANTS`, subclasses of the fan-out replacing one stage), each of which the
proof must catch: ``fanout_wrap_int64`` (the shifted product wrapped to 64 bits before the
clamp, as the twin's int64 did), ``fanout_round_bit_dropped`` (the first dropped bit not added
back), ``fanout_abs_passes_negative`` (``abs`` rectification passing a negative sample
through).
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Elaboratable, Module, Mux, Signal, signed
from amaranth.hdl import Assume

from ..flow.sby import SOLVER, FormalError
from ..lib.fixed import clamp_flagged, round_clamp_flagged, round_shift, select
from ..lib.formal import ProofResult, assert_all, harness_rtlil, run_proof
from . import datapath as dp
from .config import FanoutConfig
from .core import ChannelFanout

__all__ = ["PROOF_TABLES", "MUTANTS", "OneEntryProof", "prove_entry", "prove_fanout",
           "proof_tables", "FormalError"]

class _WrapInt64(ChannelFanout):
    @staticmethod
    def to_current(cfg, p):
        """The twin's former arithmetic: the shifted product held in 64 bits, then clamped."""
        x = round_shift(p, cfg.shift, cfg.rounding)
        return clamp_flagged(x[:64].as_signed(), cfg.I.min_raw, cfg.I.max_raw, cfg.I,
                             cfg.i_bounds)


class _RoundBitDropped(ChannelFanout):
    @staticmethod
    def to_current(cfg, p):
        return round_clamp_flagged(p, cfg.shift, "truncate", cfg.I.min_raw, cfg.I.max_raw,
                                   cfg.I, cfg.i_bounds)


class _AbsPassesNegative(ChannelFanout):
    @staticmethod
    def rectify_gate(s, mode, gated, theta):
        r = select(mode == dp.POSITIVE, select(s < 0, 0, s), s)
        return select(gated & (s < theta), 0, r)


#: mutant -> the fan-out with one stage replaced
MUTANTS = {"fanout_wrap_int64": _WrapInt64, "fanout_round_bit_dropped": _RoundBitDropped,
           "fanout_abs_passes_negative": _AbsPassesNegative}

_MIXED = dict(n_channels=1, channel=[0, 0, 0], rectify=["none", "positive", "abs"],
              threshold=[None, 1.0, None])
#: name -> the configuration's keywords (sample sQ11.5, current sQ10.8 unless stated)
PROOF_TABLES = {
    "nearest": _MIXED | {"gain": [180.0, -180.0, 7.25]},                   # shift 10
    "truncate": _MIXED | {"gain": [180.0, -180.0, 7.25], "rounding": "truncate"},
    "shift_zero": _MIXED | {"gain": [10000.0, -10000.0, 0.0]},             # shift 0
    "bits_added": _MIXED | {"gain": [1e5, -1e5, 0.0]},                     # shift -3
    "gain_1e18": _MIXED | {"gain": [1e18, -1e18, 0.0]},                    # shift -44
    "no_clamp": _MIXED | {"gain": [0.5, -0.25, 0.125], "sample_max": 8.0},  # clamp not built
}


def proof_tables() -> dict:
    """:data:`PROOF_TABLES` as configurations."""
    return {name: FanoutConfig(**kw) for name, kw in PROOF_TABLES.items()}


class OneEntryProof(Elaboratable):
    """Harness: one table entry (free, within the table's gains and modes) and one sample
    through the design's stage functions and through the specification."""

    def __init__(self, cfg: FanoutConfig, mutant: str | None = None):
        if mutant is not None and mutant not in MUTANTS:
            raise FormalError(f"unknown fan-out mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.cfg, self.mutant = cfg, mutant
        self.fanout = MUTANTS.get(mutant, ChannelFanout)
        S = cfg.S
        self.s = Signal(S.shape(), name="s")
        self.g = Signal(signed(cfg.gain_width), name="g")
        self.theta = Signal(S.shape(), name="theta")
        self.mode = Signal(2, name="mode")
        self.gated = Signal(name="gated")
        self.ports = [self.s, self.g, self.theta, self.mode, self.gated]

    def elaborate(self, platform):
        cfg, m = self.cfg, Module()
        s, g, theta, mode, gated = self.s, self.g, self.theta, self.mode, self.gated
        fan = self.fanout
        raw = [c.raw for c in cfg.gains_]
        used = False
        for k in set(cfg.modes_):
            used = (mode == k) | used
        m.d.comb += [Assume((g >= min(raw)) & (g <= max(raw))), Assume(used)]
        # the design, with the core's register widths between its stages
        r = Signal(signed(cfg.r_width), name="r")
        p = Signal(signed(cfg.p_width), name="p")
        m.d.comb += [r.eq(fan.rectify_gate(s, mode, gated, theta)), p.eq(fan.product(r, g))]
        cur, below, above = fan.to_current(cfg, p)

        # the specification, at unbounded width
        rect = Mux(mode == dp.POSITIVE, Mux(s > 0, s, 0),
                   Mux(mode == dp.ABS, Mux(s >= 0, s, -s), s))
        spec_r = Mux(gated & (s < theta), 0, rect)
        # r g at unbounded width, formed from the design's r: asserted equal to spec_r below,
        # so this is spec_r g wherever the proof passes, and the solver compares one product
        # (two multipliers of free operands shown equal would be its hardest part)
        spec_p = r * g
        sh = cfg.shift
        if sh <= 0:
            x = spec_p << -sh
        elif cfg.rounding == "nearest":
            x = (spec_p + (1 << (sh - 1))) >> sh
        else:
            x = spec_p >> sh
        lo, hi = cfg.I.min_raw, cfg.I.max_raw
        spec_below, spec_above = x < lo, x > hi
        spec_cur = Mux(spec_above, hi, Mux(spec_below, lo, x))
        assert_all(m, [(r == spec_r, "rectified sample"), (p == spec_p, "product"),
                       (cur == spec_cur, "current"), (below == spec_below, "clamp low flag"),
                       (above == spec_above, "clamp high flag")])
        return m


def prove_entry(cfg: FanoutConfig, workdir: Path, name: str = "entry",
                mutant: str | None = None, timeout_s: float = 600,
                solver: str = SOLVER) -> ProofResult:
    """The one-entry datapath of ``cfg`` against its specification (depth 1: every input)."""
    top = OneEntryProof(cfg, mutant)
    il = harness_rtlil(top, "fanout_entry")
    r = run_proof(f"fanout {name}", il, Path(workdir) / name, "fanout_entry", "bmc", 1,
                  timeout_s, solver=solver)
    r.abstractions = []
    return r


def prove_fanout(workdir: Path, mutant: str | None = None, timeout_s: float = 600,
                 solver: str = SOLVER, tables: dict | None = None) -> list[tuple]:
    """:func:`prove_entry` for each of ``tables`` (default :func:`proof_tables`); returns
    ``[(name, cfg, ProofResult), ...]``."""
    out = []
    for name, cfg in (tables or proof_tables()).items():
        out.append((name, cfg, prove_entry(cfg, workdir, name, mutant, timeout_s, solver)))
    return out
