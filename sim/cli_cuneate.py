"""``cuneate generate coincidence``, ``cuneate simulate coincidence`` and the ridge-angle
experiment (``cuneate coincidence ridge``).

``simulate`` and ``generate`` take the detector's options through one parser
(:func:`add_coincidence_options`) and build the configuration through one function
(:func:`coincidence_config`), so they accept and refuse the same configurations with the same
one-line message.
"""

from __future__ import annotations

import json

import numpy as np

from .cliutil import (CliError, CommandGroups, nonneg_int, output_dir, positive_float,
                      positive_int)

__all__ = ["register", "add_coincidence_options", "coincidence_config", "parse_matrix",
           "parse_spikes"]


def parse_matrix(text: str, what: str) -> np.ndarray:
    """``"a,b;c,d"`` -> 2x2 float matrix (rows by ``;``); a one-line error otherwise."""
    try:
        rows = [[float(x) for x in r.split(",")] for r in text.split(";")]
    except ValueError:
        raise CliError(f"{what}: expected numbers as 'a,b;c,d' (rows separated by ';'), got "
                       f"{text!r}") from None
    if len({len(r) for r in rows}) != 1:
        raise CliError(f"{what}: every row needs the same number of values, got {text!r}")
    m = np.array(rows)
    if not np.all(np.isfinite(m)):
        raise CliError(f"{what}: values must be finite, got {text!r}")
    return m


def parse_spikes(text: str, n_sources: int, dt_ms: float) -> list[np.ndarray]:
    """``"0:1,2.5;3:4"`` (source: spike times in ms) -> input ticks per source; every time must
    be on the tick grid (a multiple of dt)."""
    out = [[] for _ in range(n_sources)]
    for part in filter(None, (p.strip() for p in text.split(";"))):
        src, _, times = part.partition(":")
        try:
            s = int(src)
            ts = [float(t) for t in times.split(",") if t.strip()]
        except ValueError:
            raise CliError(f"--spikes: expected 'SOURCE:t1,t2;...' (ms), got {part!r}") from None
        if not 0 <= s < n_sources:
            raise CliError(f"--spikes: source {s} is outside 0 .. {n_sources - 1}")
        for t in ts:
            k = t / dt_ms
            if not np.isfinite(t) or t < 0 or abs(k - round(k)) > 1e-9:
                raise CliError(f"--spikes: source {s}: {t:g} ms is not a tick time >= 0 (a "
                               f"multiple of dt = {dt_ms:g} ms)")
            out[s].append(int(round(k)))
    return [np.array(sorted(x), dtype=np.int64) for x in out]


def add_coincidence_options(p) -> None:
    g = p.add_argument_group("detector configuration")
    g.add_argument("--sources", type=positive_int, default=4, help="afferents (default 4)")
    g.add_argument("--targets", type=positive_int, default=3,
                   help="cuneate neurons (default 3)")
    g.add_argument("--delays-ms", default=None, metavar="D",
                   help="conduction delays, one row per target: 'a,b;c,d' (default all 0)")
    g.add_argument("--weights", default=None, metavar="W",
                   help="PSP amplitudes J w in mV/ms, one row per target (default J = 8)")
    g.add_argument("--max-delay-ms", type=positive_float, default=32.0,
                   help="spike history depth (default 32 ms)")
    g.add_argument("--tau-rise-ms", type=positive_float, default=0.5)
    g.add_argument("--tau-decay-ms", type=positive_float, default=2.0)
    g.add_argument("--param-set", action="append", default=None,
                   help="Izhikevich preset of the targets (repeat for several sets)")
    g.add_argument("--target-sets", default=None, metavar="i,j,...",
                   help="parameter-set index of every target")
    g.add_argument("--update-hz", type=positive_float, default=16e3)
    g.add_argument("--clock-hz", type=positive_float, default=40e6)
    g.add_argument("--weight-bits", type=positive_int, default=12)
    g.add_argument("--trace-frac-bits", type=positive_int, default=16)
    g.add_argument("--operand-width", type=positive_int, default=18)
    g.add_argument("--rounding", choices=("nearest", "truncate"), default="nearest")


def coincidence_config(args, tick_source: str = "external"):
    """The configuration of ``args``; any refusal becomes a one-line :class:`CliError`."""
    from ..hdl.cuneate import CoincidenceConfig, ConfigError
    S, M = args.sources, args.targets
    dt = 1000.0 / args.update_hz
    kw = {}
    try:
        if args.delays_ms is not None:
            d = parse_matrix(args.delays_ms, "--delays-ms")
            if d.shape != (M, S):
                raise CliError(f"--delays-ms: needs {M} rows (targets) of {S} values (sources),"
                               f" got {d.shape[0]} x {d.shape[1]}")
            ticks = d / dt
            if not np.allclose(ticks, np.round(ticks), atol=1e-9):
                raise CliError(f"--delays-ms: every delay must be a multiple of dt = {dt:g} ms")
            kw["delays_ticks"] = np.round(ticks).astype(np.int64)
        if args.weights is not None:
            w = parse_matrix(args.weights, "--weights")
            if w.shape == (1, 1):
                w = np.full((M, S), w[0, 0])
            if w.shape != (M, S):
                raise CliError(f"--weights: needs one value or {M} rows of {S}, got "
                               f"{w.shape[0]} x {w.shape[1]}")
            kw["weights"] = w
        if args.target_sets is not None:
            try:
                kw["target_sets"] = [int(x) for x in args.target_sets.split(",")]
            except ValueError:
                raise CliError(f"--target-sets: expected integers 'i,j,...', got "
                               f"{args.target_sets!r}") from None
        return CoincidenceConfig(
            n_sources=S, n_targets=M, max_delay_ticks=int(np.floor(args.max_delay_ms / dt
                                                                   + 1e-9)) + 1,
            tau_rise_ms=args.tau_rise_ms, tau_decay_ms=args.tau_decay_ms,
            param_sets=tuple(args.param_set or ("RS",)), clock_hz=args.clock_hz,
            update_hz=args.update_hz, weight_bits=args.weight_bits,
            trace_frac_bits=args.trace_frac_bits, operand_width=args.operand_width,
            rounding=args.rounding, tick_source=tick_source, **kw)
    except ConfigError as exc:
        raise CliError(f"coincidence detector: {exc}") from None


def cmd_generate(args) -> int:
    from ..hdl.cuneate import CoincidenceDetector, coincidence_verilog
    from ..hdl.generate import port_table
    cfg = coincidence_config(args, args.tick_source)
    out = output_dir(args.out)
    name = "coincidence_detector"
    top = CoincidenceDetector(cfg)
    (out / f"{name}.v").write_text(coincidence_verilog(cfg, name, top=top))
    desc = cfg.to_dict() | {"module": name, "ports": port_table(top)}
    (out / f"{name}.json").write_text(json.dumps(desc, indent=2, sort_keys=True,
                                                 default=float) + "\n")
    print(f"wrote {out / (name + '.v')} and {out / (name + '.json')}: {cfg.n_targets} targets x "
          f"{cfg.n_sources} sources, {cfg.cycles_needed} of {cfg.cycles_per_tick} cycles per "
          f"tick, history {desc['memories']['history']}, {desc['multipliers']} multipliers")
    return 0


def cmd_simulate(args) -> int:
    from .cuneate_engines import run_coincidence
    cfg = coincidence_config(args)
    n = int(round(args.duration_ms / cfg.dt_ms))
    if n < 1:
        raise CliError(f"--duration-ms {args.duration_ms:g} is shorter than one tick "
                       f"({cfg.dt_ms:g} ms)")
    ins = parse_spikes(args.spikes, cfg.n_sources, cfg.dt_ms)
    if any(len(t) and t.max() >= n for t in ins):
        raise CliError("--spikes: a spike lies at or after the end of the run "
                       f"({n * cfg.dt_ms:g} ms)")
    bd = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    run = run_coincidence(args.engine, cfg, ins, n, build_dir=bd)
    res = {"engine": args.engine, "dt_ms": cfg.dt_ms, "ticks": n,
           "spikes_ms": [np.asarray(s).tolist() for s in run.spikes_ms],
           "spike_counts": [len(s) for s in run.spikes_ms], "merged_inputs": run.merged,
           "config": cfg.to_kwargs(), "wall_s": run.wall_s}
    if args.json:
        print(json.dumps(res))
    else:
        for t, s in enumerate(run.spikes_ms):
            print(f"target {t}: {len(s)} spikes " + " ".join(f"{x:g}" for x in s[:20]))
    return 0


def cmd_ridge(args) -> int:
    from .experiments_cuneate import RidgeSpec, format_ridge, ridge_experiment
    spec = RidgeSpec(trials_per_angle=args.trials_per_angle, seed=args.seed)
    bd = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    results = [ridge_experiment(e, spec, build_dir=bd / e if bd else None)
               for e in args.engine]
    if args.json:
        print(json.dumps([r.to_dict() for r in results]))
    else:
        print("\n".join(format_ridge(r) for r in results))
    return 0


def register(groups: CommandGroups) -> None:
    from .cuneate_engines import COINCIDENCE_ENGINES
    s = groups.simulate.add_parser("coincidence",
                                   help="the coincidence detector (cuneate neurons)")
    s.add_argument("--engine", choices=COINCIDENCE_ENGINES, default="golden")
    s.add_argument("--spikes", default="", metavar="S:t1,t2;...",
                   help="input spikes per source in ms, on the tick grid")
    s.add_argument("--duration-ms", type=positive_float, default=100.0)
    s.add_argument("--build-dir", default=None)
    s.add_argument("--json", action="store_true")
    add_coincidence_options(s)
    s.set_defaults(func=cmd_simulate)

    g = groups.generate.add_parser("coincidence",
                                   help="the coincidence detector (cuneate neurons)")
    add_coincidence_options(g)
    g.add_argument("--tick-source", choices=("internal", "external"), default="external")
    g.add_argument("--out", required=True)
    g.set_defaults(func=cmd_generate)

    c = groups.root.add_parser("coincidence", help="cuneate-neuron experiments (ridge angle)")
    sub = c.add_subparsers(dest="coincidence_command", required=True, parser_class=type(c))
    r = sub.add_parser("ridge", help="decode ridge angle from which cuneate neurons fire")
    r.add_argument("--engine", choices=COINCIDENCE_ENGINES, nargs="+", default=["golden",
                                                                                "fixed"])
    r.add_argument("--trials-per-angle", type=positive_int, default=10)
    r.add_argument("--seed", type=nonneg_int, default=1)
    r.add_argument("--build-dir", default=None)
    r.add_argument("--json", action="store_true")
    r.set_defaults(func=cmd_ridge)
