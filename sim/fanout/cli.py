"""``cuneate simulate fanout`` and ``cuneate generate fanout``: the channel fan-out
(:mod:`cuneate.hdl.fanout`), its table from the command line or from a JSON file.

Both commands build the table through one function (:func:`fanout_from_args`), so they accept
and refuse the same tables with the same one-line message naming the option. On the command
line a table is ``--channels`` channels and ``--afferents`` afferents, afferent ``i`` listening
to channel ``i % channels`` (or to its ``--channel``), with a ``--gain``, a ``--rectify`` and a
``--threshold`` each: one value for every afferent or one per afferent. ``--table FILE.json``
is the whole configuration instead (:meth:`FanoutConfig.to_kwargs` as JSON, as ``generate``
writes it beside the Verilog in ``NAME.table.json``).

``simulate`` runs the fan-out once per sample period (``duration_ms * sample_hz / 1000`` runs)
on constant channel samples (``--sample``) or on a sine per channel (``--sine``), and reports
each afferent's currents and the clamps the engine counted (golden has none: float64 currents).
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import fields

import numpy as np

from ...golden.fanout import RECTIFY
from ...hdl.fanout import ConfigError, FanoutConfig, generate_fanout
from ...hdl.fanout.config import check_table_size
from ...hdl.lib.fixed import FixedPointError, QFormat
from ..cli.options import (CliError, CommandGroups, add_block_commands, build_config,
                           finite_float, generate_faced, input_file, output_dir, positive_float,
                           positive_int, run_ticks)

__all__ = ["register", "add_fanout_options", "fanout_from_args", "threshold_value"]

#: the table's options (``args`` attribute, option): none of them goes with ``--table``
TABLE_OPTIONS = (("channels", "--channels"), ("afferents", "--afferents"),
                 ("channel", "--channel"), ("gain", "--gain"), ("rectify", "--rectify"),
                 ("threshold", "--threshold"), ("sample_width", "--sample-width"),
                 ("sample_max", "--sample-max"), ("current_format", "--current-format"),
                 ("gain_width", "--gain-width"), ("max_gain_error", "--max-gain-error"),
                 ("rounding", "--rounding"), ("clock_hz", "--clock-hz"),
                 ("sample_hz", "--sample-hz"))

#: per-afferent options: one value for every afferent or one per afferent
PER_AFFERENT = (("channel", "--channel"), ("gain", "--gain"), ("rectify", "--rectify"),
                ("threshold", "--threshold"))

#: the option a refusal of :class:`FanoutConfig` concerns, by a phrase of its message (first
#: match wins)
REFUSAL_OPTIONS = (("listens to channel", "--channel"), ("channel must list", "--channel"),
                   ("n_channels", "--channels"), ("rectify", "--rectify"),
                   ("threshold", "--threshold"), ("rounding", "--rounding"),
                   ("sample_width", "--sample-width"), ("gain_width", "--gain-width"),
                   ("sample_max", "--sample-max"),
                   ("-bit signed format holds", "--sample-width/--sample-max"),
                   ("every current would round to 0", "--gain"), ("gain", "--gain"),
                   ("fan-out table of", "--afferents"),
                   ("fan-out run of", "--clock-hz/--sample-hz"))

DEFAULT_CHANNELS = 4
DEFAULT_AFFERENTS = 16


def threshold_value(text: str) -> float | None:
    """A ``--threshold`` value: a finite number (sample units), or ``none`` (no gate)."""
    if text.strip().lower() == "none":
        return None
    return finite_float(text)


def add_fanout_options(p) -> None:
    """The options that define a fan-out table, shared by ``simulate`` and ``generate``."""
    g = p.add_argument_group("fan-out table (FanoutConfig; or --table)")
    g.add_argument("--table", default=None, metavar="FILE.json",
                   help="the whole configuration as JSON (FanoutConfig.to_kwargs(), as "
                        "generate writes in NAME.table.json); excludes the options below")
    g.add_argument("--channels", type=positive_int, default=None, metavar="C",
                   help=f"channels the host streams (n_channels; default {DEFAULT_CHANNELS})")
    g.add_argument("--afferents", type=positive_int, default=None, metavar="N",
                   help="afferents (default: the longest list of --channel, --gain, "
                        f"--rectify, --threshold, else {DEFAULT_AFFERENTS})")
    g.add_argument("--channel", type=int, nargs="+", default=None, metavar="CH",
                   help="channel of each afferent: one for all or one per afferent (default "
                        "afferent i listens to channel i %% channels)")
    g.add_argument("--gain", type=finite_float, nargs="+", default=None, metavar="G",
                   help="mV/ms per sample unit: one for all or one per afferent (default 1)")
    g.add_argument("--rectify", choices=("none", "positive", "abs"), nargs="+", default=None,
                   help="rectification of the sample: one for all or one per afferent "
                        "(default none)")
    g.add_argument("--threshold", type=threshold_value, nargs="+", default=None, metavar="X",
                   help="SA gate (sample units; the current is 0 below it) or 'none': one for "
                        "all or one per afferent (default none)")
    g.add_argument("--sample-width", type=positive_int, default=None, metavar="BITS",
                   help="bits of a channel sample (default 16)")
    g.add_argument("--sample-max", type=positive_float, default=None,
                   help="samples span [-sample_max, sample_max] (default 512)")
    g.add_argument("--current-format", type=positive_int, nargs=2, default=None,
                   metavar=("INT", "FRAC"),
                   help="the fed core's current format (default 10 8, the Izhikevich core's)")
    g.add_argument("--gain-width", type=positive_int, default=None, metavar="BITS",
                   help="bits of a gain constant, one exponent shared (default 18)")
    g.add_argument("--max-gain-error", type=positive_float, default=None,
                   help="largest relative error of a non-zero gain (default 1e-3)")
    g.add_argument("--rounding", choices=("nearest", "truncate"), default=None,
                   help="rounding of the product to the current (default nearest)")
    g.add_argument("--clock-hz", type=positive_float, default=None,
                   help="clock (default 40e6); a run of afferents + 5 cycles must fit one "
                        "sample period")
    g.add_argument("--sample-hz", type=positive_float, default=None,
                   help="channel sample rate: one run per sample (default 1e3)")


def _per_afferent(args, n: int) -> dict:
    """The per-afferent options given, each as ``n`` values (one value repeated), or a
    one-line refusal naming the option."""
    out = {}
    for attr, opt in PER_AFFERENT:
        vals = getattr(args, attr)
        if vals is None:
            continue
        if len(vals) not in (1, n):
            raise CliError(f"{opt} takes one value or one per afferent ({n}), got {len(vals)}")
        out[attr] = list(vals) * n if len(vals) == 1 else list(vals)
    return out


def _refusal(exc: Exception, where: str | None = None) -> CliError:
    """A refusal of the configuration as one line naming the option it concerns (``where``:
    the table file)."""
    msg = str(exc).removeprefix("channel fan-out refused: ")
    if where is not None:
        return CliError(f"cuneate: --table {where!r}: {msg}")
    opt = next((o for phrase, o in REFUSAL_OPTIONS if phrase in msg), None)
    return CliError(f"cuneate: {opt}: {msg}" if opt else f"cuneate: fan-out refused: {msg}")


def _table_config(path_text: str):

    path = input_file(path_text, "--table")
    what = ("not a fan-out table (a JSON object of FanoutConfig's arguments, as cuneate "
            "generate fanout writes in NAME.table.json)")
    try:
        kw = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise CliError(f"--table {path_text!r}: not JSON: {exc}") from None
    if not isinstance(kw, dict):
        raise CliError(f"--table {path_text!r}: {what}")
    unknown = sorted(set(kw) - {f.name for f in fields(FanoutConfig) if f.init})
    if unknown:
        raise CliError(f"--table {path_text!r}: {what}: unknown key {unknown[0]!r}")
    cf = kw.get("current_format")
    if cf is not None and not (isinstance(cf, list) and len(cf) == 2
                               and all(isinstance(x, int) for x in cf)):
        raise CliError(f"--table {path_text!r}: current_format must be [int_bits, frac_bits]")
    try:
        return FanoutConfig.from_kwargs(kw)
    except ConfigError as exc:
        raise _refusal(exc, path_text) from None
    except (TypeError, ValueError) as exc:
        raise CliError(f"--table {path_text!r}: {what}: {exc}") from None


def fanout_from_args(args):
    """The :class:`~cuneate.hdl.fanout.FanoutConfig` of the table options (or ``--table``),
    or a one-line refusal naming the option."""
    given = [opt for attr, opt in TABLE_OPTIONS if getattr(args, attr) is not None]
    if args.table is not None:
        if given:
            raise CliError(f"--table and {given[0]} exclude each other (the table file holds "
                           f"the whole configuration)")
        return _table_config(args.table)
    C = args.channels or DEFAULT_CHANNELS
    lists = [len(getattr(args, a)) for a, _ in PER_AFFERENT if getattr(args, a) is not None]
    longest = max(lists, default=1)
    N = args.afferents or (longest if longest > 1 else DEFAULT_AFFERENTS)
    try:         # before the table's lists are built: refused by its size, not by memory
        check_table_size(N, C, args.gain_width or 18, args.sample_width or 16)
    except ConfigError as exc:
        raise _refusal(exc) from None
    kw = {"n_channels": C, "channel": [i % C for i in range(N)], "gain": [1.0] * N}
    kw |= _per_afferent(args, N)
    for attr in ("rectify", "sample_width", "sample_max", "gain_width", "max_gain_error",
                 "rounding", "clock_hz", "sample_hz"):
        if attr not in kw and getattr(args, attr) is not None:
            kw[attr] = getattr(args, attr)
    if args.current_format is not None:
        try:
            kw["current_format"] = QFormat(*args.current_format)
        except FixedPointError as exc:
            raise CliError(f"cuneate: --current-format: {exc}") from None
    try:
        return FanoutConfig(**kw)
    except ConfigError as exc:
        raise _refusal(exc) from None


# --------------------------------------------------------------------------------------------
def _samples(args, cfg, n_runs: int) -> np.ndarray:
    """The channel samples ``(n_runs, n_channels)`` of ``--sample`` or ``--sine``, refused in
    one line (naming the option) where an engine other than golden would saturate them."""
    C = cfg.n_channels
    fmt = (f"the sample format {cfg.S} [{cfg.S.min_value:g}, {cfg.S.max_value:g}]; the "
           f"{args.engine} engine would saturate it")
    if args.sine is not None:
        a = abs(args.sine)
        if args.engine != "golden" and not (cfg.S.contains(a) and cfg.S.contains(-a)):
            raise CliError(f"--sine {args.sine:g}: the samples reach +-{a:g}, outside {fmt}")
        f = args.sine_hz if args.sine_hz is not None else cfg.sample_hz / n_runs
        t = np.arange(n_runs)[:, None] / cfg.sample_hz
        return args.sine * np.sin(2 * math.pi * (f * t + np.arange(C)[None, :] / C))
    if args.sine_hz is not None:
        raise CliError("--sine-hz needs --sine")
    s = list(args.sample)
    if len(s) not in (1, C):
        raise CliError(f"--sample takes one value or one per channel ({C}), got {len(s)}")
    if args.engine != "golden":
        for x in s:
            if not cfg.S.contains(x):
                raise CliError(f"--sample {x:g} is outside {fmt}")
    return np.tile(s * C if len(s) == 1 else s, (n_runs, 1)).astype(np.float64)


def _afferent_label(cfg, i: int) -> str:
    th = cfg.thresholds_[i]
    return (f"afferent {i} (channel {cfg.channels_[i]}, gain {float(cfg.gain[i]):g}, "
            f"{RECTIFY[cfg.modes_[i]]}" + ("" if th is None else f", gated below {th:g}") + ")")


def cmd_simulate(args) -> int:
    from .engines import run_fanout
    if getattr(args, "spikes", None):
        raise CliError("--spikes: the fan-out writes currents, not spikes")
    cfg = fanout_from_args(args)
    period_ms = 1000.0 / cfg.sample_hz
    n_runs = run_ticks("cuneate simulate fanout", "fanout", args, period_ms,
                       cfg.cycles_per_run + cfg.n_channels, cfg.n_neurons, unit="run")
    x = _samples(args, cfg, n_runs)
    build_dir = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    try:
        run = run_fanout(args.engine, cfg, x, build_dir=build_dir)
    except ValueError as exc:
        raise CliError(f"cuneate simulate fanout: {exc}") from None
    cur = np.asarray(run.values, dtype=np.float64)
    lo, hi = cur.min(axis=0), cur.max(axis=0)
    out = {"engine": args.engine, "model": "fanout", "dt_ms": period_ms,
           "duration_ms": n_runs * period_ms, "runs": n_runs, "channels": cfg.n_channels,
           "afferents": cfg.n_neurons, "table": cfg.to_kwargs(),
           "formats": {"sample": str(cfg.S), "current": str(cfg.I),
                       "gain_frac_bits": cfg.gain_frac},
           "samples": x.tolist(), "currents": cur.tolist(),
           "current_range": np.stack([lo, hi], axis=1).tolist(),
           "saturation": None if run.clamp_counts is None else {"counts": run.clamp_counts},
           "figures": run.counters}
    if args.engine != "golden":
        out["quantized_samples"] = cfg.S.to_float(cfg.S.to_raw(x)).tolist()
    if args.json:
        print(json.dumps(out))
        return 0
    source = (f"sine of amplitude {args.sine:g}" if args.sine is not None
              else "constant samples " + ", ".join(f"{v:g}" for v in x[0]))
    print(f"channel fan-out on {args.engine}: {cfg.n_channels} channels -> {cfg.n_neurons} "
          f"afferents, {n_runs} runs (one per sample at {cfg.sample_hz:g} Hz, "
          f"{n_runs * period_ms:g} ms), {source}; samples {cfg.S}, currents "
          + ("float64" if args.engine == "golden" else str(cfg.I)))
    for i in range(cfg.n_neurons):
        rng = f"{lo[i]:g}" if lo[i] == hi[i] else f"{lo[i]:g} .. {hi[i]:g}"
        print(f"  {_afferent_label(cfg, i)}: I = {rng} mV/ms")
    if run.clamp_counts is None:
        print("clamps: none on golden (float64 currents, no current format)")
    else:
        print("clamps: " + ", ".join(f"{k} {v}" for k, v in run.clamp_counts.items())
              + f" (of {cur.size} currents; the clamp is "
              + ("built" if cfg.can_clamp else "not built: it cannot act") + ")")
    return 0


def cmd_generate(args) -> int:
    if args.tick_source != "internal":
        raise CliError("--tick-source: the fan-out has no tick (it runs once per channel "
                       "frame, on start)")
    cfg = fanout_from_args(args)
    if args.face != "none":              # in front of an Izhikevich core of its afferents
        from ...hdl.izhikevich import IzhikevichConfig
        core = build_config(IzhikevichConfig, {"n_neurons": cfg.n_neurons,
                                               "clock_hz": cfg.clock_hz,
                                               "tick_source": "external"})
        return generate_faced(args, core, "fanout", fanout=cfg)
    out = output_dir(args.out)
    files = generate_fanout(out, cfg, name=args.name)
    table = out / f"{args.name}.table.json"
    table.write_text("{\n" + ",\n".join(f"  {json.dumps(k)}: {json.dumps(v)}"
                                         for k, v in cfg.to_kwargs().items()) + "\n}\n")
    for f in [*files, table]:
        print(f)
    d = cfg.to_dict()
    print(f"channel fan-out: {cfg.n_channels} channels -> {cfg.n_neurons} afferents; samples "
          f"{cfg.S}, currents {cfg.I}, gains {cfg.gain_width} bits with 2^-{cfg.gain_frac} "
          f"(largest relative error {d['max_gain_rel_error']:.3g}); table {cfg.n_neurons} x "
          f"{cfg.entry_width} = {d['table_bits']} bits; {cfg.cycles_per_run} cycles a run of "
          f"{cfg.clock_hz / cfg.sample_hz:g} a sample at {cfg.clock_hz / 1e6:g} MHz; current "
          f"clamp " + ("built" if cfg.can_clamp else "not built (cannot act)"))
    return 0


def _hide(p, dest: str) -> None:
    """Keep a shared option the fan-out has no use for out of its help (it is refused)."""
    for action in p._actions:
        if action.dest == dest:
            action.help = argparse.SUPPRESS


def register(groups: CommandGroups) -> None:
    s, g = add_block_commands(groups, "fanout", "the channel fan-out (channel samples -> "
                                                "afferent currents)", 10.0,
                              add_fanout_options, cmd_simulate, cmd_generate, "channel_fanout",
                              faces=True)
    _hide(s, "spikes")
    _hide(g, "tick_source")
    src = s.add_argument_group("channel samples (one run per sample period)")
    x = src.add_mutually_exclusive_group()
    x.add_argument("--sample", type=finite_float, nargs="+", default=[1.0], metavar="X",
                   help="constant samples: one for every channel or one per channel "
                        "(default 1)")
    x.add_argument("--sine", type=finite_float, default=None, metavar="AMPLITUDE",
                   help="a sine per channel instead, channel c shifted by c/channels of a "
                        "period")
    src.add_argument("--sine-hz", type=positive_float, default=None,
                     help="frequency of --sine (default: one period over the run)")
