"""``cuneate simulate coincidence``, ``cuneate generate coincidence`` and the ridge-angle
experiment (``cuneate coincidence ridge``).

``simulate`` and ``generate`` take the detector's options through one parser
(:func:`add_coincidence_options`) and build the configuration through one function
(:func:`coincidence_from_args`), so they accept and refuse the same configurations with the
same one-line message.

Matrices on the command line (delays, weights) are rows separated by ``;`` and values by ``,``:
``--delays-ms "0,0,20,20;0,0,0,0;20,20,0,0"`` is three targets of four sources. Input spikes
(``simulate``) are one ``--input`` per source, a comma list of times in ms; each time is
stamped with the tick ``round(t / dt)`` (the engines all see the stamped times, reported as
``input_ms``), or, without ``--input``, Poisson trains of ``--input-rate-hz``.
"""

from __future__ import annotations

import json

import numpy as np

from ...golden.izhikevich import PRESETS, to_params
from ...hdl.coincidence import CoincidenceConfig, generate_coincidence, synth_resources
from ...hdl.flow.synth import format_resources
from ..cli.options import (CliError, CommandGroups, add_block_commands, add_max_minutes,
                           add_rate_options, build_config, check_estimate, clamp_summary,
                           engine_choices, finite_float, output_dir, positive_float, positive_int,
                           print_run, run_ticks, seed_int)
from ..izhikevich.cli import parse_param_set

__all__ = ["register", "add_coincidence_options", "coincidence_kwargs",
           "coincidence_from_args", "parse_matrix", "print_resources"]


def parse_matrix(text: str, what: str) -> np.ndarray:
    """``"a,b;c,d"`` -> a 2-D float array (rows by ``;``), or a one-line refusal."""
    rows = [r for r in text.replace(" ", "").split(";") if r]
    try:
        vals = [[float(x) for x in r.split(",") if x] for r in rows]
    except ValueError:
        raise CliError(f"{what} {text!r}: numbers separated by ',' with rows separated by "
                       f"';'") from None
    if not vals or len({len(r) for r in vals}) != 1 or not vals[0]:
        raise CliError(f"{what} {text!r}: every row needs the same number of values")
    m = np.asarray(vals, dtype=np.float64)
    if not np.all(np.isfinite(m)):
        raise CliError(f"{what} {text!r}: values must be finite")
    return m


def add_coincidence_options(p) -> None:
    """The options that define a detector, shared by ``simulate`` and ``generate``."""
    g = p.add_argument_group("detector configuration")
    g.add_argument("--sources", type=positive_int, default=None,
                   help="afferents (default: the columns of --delays-ms, else 4)")
    g.add_argument("--targets", type=positive_int, default=None,
                   help="cuneate neurons (default: the rows of --delays-ms, else 3)")
    g.add_argument("--delays-ms", default=None, metavar="MATRIX",
                   help="conduction delays, one row per target (e.g. '0,2;2,0'); whole ticks; "
                        "default all 0")
    g.add_argument("--weights", default=None, metavar="MATRIX|VALUE",
                   help="PSP amplitudes J w in mV/ms: one value for all pairs or one row per "
                        "target (default 8, the brief's J)")
    g.add_argument("--max-delay-ticks", type=positive_int, default=512,
                   help="depth of the spike history (default 512 = 32 ms at 16 kHz)")
    g.add_argument("--tau-rise-ms", type=positive_float, default=0.5)
    g.add_argument("--tau-decay-ms", type=positive_float, default=2.0)
    g.add_argument("--param-set", action="append", default=None, metavar="SPEC",
                   help="Izhikevich parameter set of the targets (repeatable; preset, "
                        "behaviour:LETTER or a,b,c,d...; default RS)")
    g.add_argument("--target-sets", default=None, metavar="LIST",
                   help="set index of each target (comma list; default 0 for all)")
    add_rate_options(g, None, "clock (generate: default 40e6; simulate: the engines' own)")
    g.add_argument("--weight-bits", type=positive_int, default=12)
    g.add_argument("--trace-frac-bits", type=positive_int, default=16)
    g.add_argument("--operand-width", type=positive_int, default=18)
    g.add_argument("--rounding", choices=("nearest", "truncate"), default="nearest")


def coincidence_kwargs(args) -> dict:
    """Constructor keywords of :class:`~cuneate.hdl.coincidence.CoincidenceConfig` from the
    shared options (delays converted to ticks, refused when not whole)."""
    delays = parse_matrix(args.delays_ms, "--delays-ms") if args.delays_ms else None
    w = None
    if args.weights:
        w = parse_matrix(args.weights, "--weights")
    M = args.targets or (delays.shape[0] if delays is not None else
                         (w.shape[0] if w is not None and w.size > 1 else 3))
    S = args.sources or (delays.shape[1] if delays is not None else
                         (w.shape[1] if w is not None and w.size > 1 else 4))
    dt = 1000.0 / args.update_hz
    kw = {"n_sources": S, "n_targets": M, "max_delay_ticks": args.max_delay_ticks,
          "tau_rise_ms": args.tau_rise_ms, "tau_decay_ms": args.tau_decay_ms,
          "update_hz": args.update_hz, "weight_bits": args.weight_bits,
          "trace_frac_bits": args.trace_frac_bits, "operand_width": args.operand_width,
          "rounding": args.rounding}
    if delays is not None:
        if delays.shape != (M, S):
            raise CliError(f"--delays-ms has shape {delays.shape[0]}x{delays.shape[1]}, the "
                           f"detector {M} targets x {S} sources")
        ticks = delays / dt
        far = ~(np.abs(ticks) < 2.0 ** 53)         # beyond exact integers: never cast them
        if far.any():
            raise CliError(f"--delays-ms: {delays[far][0]:g} ms is out of range (dt = {dt:g} ms)")
        bad = np.abs(ticks - np.round(ticks)) > 1e-9
        if bad.any():
            raise CliError(f"--delays-ms: {delays[bad][0]:g} ms is not a whole number of ticks "
                           f"(dt = {dt:g} ms)")
        kw["delays_ticks"] = np.round(ticks).astype(np.int64).tolist()
    if w is not None:
        if w.size == 1:
            w = np.full((M, S), float(w.ravel()[0]))
        if w.shape != (M, S):
            raise CliError(f"--weights has shape {w.shape[0]}x{w.shape[1]}, the detector "
                           f"{M} targets x {S} sources")
        kw["weights"] = w.tolist()
    if args.param_set:
        kw["param_sets"] = [parse_param_set(s).to_dict() for s in args.param_set]
    if args.target_sets:
        try:
            kw["target_sets"] = [int(x) for x in args.target_sets.split(",") if x.strip()]
        except ValueError:
            raise CliError(f"--target-sets {args.target_sets!r}: a comma list of "
                           f"integers") from None
    if args.clock_hz is not None:
        kw["clock_hz"] = args.clock_hz
    return kw


def coincidence_from_args(kw: dict):
    """The configuration, or the one-line refusal shared by every command."""
    return build_config(CoincidenceConfig, kw, "coincidence detector")


def _param_dicts(cfg) -> list:
    out = []
    for p in cfg.param_sets:
        q = PRESETS[p.upper()] if isinstance(p, str) else to_params(p)
        out.append({k: v for k, v in q.to_dict().items() if k != "name"})
    return out


# --------------------------------------------------------------------------------------------
def _input_ticks(args, S: int, dt: float, n_ticks: int) -> list[np.ndarray]:
    if args.input:
        if len(args.input) != S:
            raise CliError(f"--input is given {len(args.input)} times; the detector has {S} "
                           f"sources (one --input per source, '' for none)")
        out = []
        for s, text in enumerate(args.input):
            try:
                ts = np.array([float(x) for x in text.replace(" ", "").split(",") if x])
            except ValueError:
                raise CliError(f"--input {text!r} (source {s}): a comma list of times in "
                               f"ms") from None
            if ts.size and (not np.all(np.isfinite(ts)) or ts.min() < 0):
                raise CliError(f"--input {text!r} (source {s}): times must be finite and "
                               f">= 0 ms")
            k = np.round(ts / dt)
            late = ts[k >= n_ticks]
            if late.size:
                raise CliError(f"--input {text!r} (source {s}): a spike at {late.min():g} ms "
                               f"falls after the run's last tick ({(n_ticks - 1) * dt:g} ms); "
                               f"lengthen --duration-ms or leave it out")
            out.append(np.unique(k.astype(np.int64)))
        return out
    rng = np.random.default_rng(args.seed)
    p = args.input_rate_hz * dt / 1000.0
    if p < 0:
        raise CliError(f"--input-rate-hz {args.input_rate_hz:g}: a rate must be >= 0 Hz")
    if p > 1:
        raise CliError(f"--input-rate-hz {args.input_rate_hz:g} exceeds one spike per tick "
                       f"({1000 / dt:g} Hz)")
    return [np.flatnonzero(rng.random(n_ticks) < p) for _ in range(S)]


def cmd_simulate(args) -> int:
    from .engines import run_coincidence
    kw = coincidence_kwargs(args)
    # the engines run an external tick; a clock that just fits the schedule unless given
    if args.clock_hz is None:
        from ...hdl.coincidence.config import CYCLES_PER_TARGET_EXTRA
        need = kw["n_targets"] * (kw["n_sources"] + CYCLES_PER_TARGET_EXTRA) + 2
        kw["clock_hz"] = args.update_hz * max(need, 64)
    cfg = coincidence_from_args(kw)
    dt = cfg.dt_ms
    n_ticks = run_ticks("cuneate simulate coincidence", "coincidence", args, dt,
                        cfg.cycles_needed, cfg.n_targets)
    ins = _input_ticks(args, cfg.n_sources, dt, n_ticks)
    build_dir = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    try:
        run = run_coincidence(args.engine, cfg, ins, n_ticks, build_dir=build_dir)
    except ValueError as exc:
        raise CliError(f"cuneate simulate coincidence: {exc}") from None
    spikes = [[float(t) for t in s] for s in run.spikes_ms]
    out = {"engine": args.engine, "model": "coincidence", "dt_ms": dt, "scheme": "euler",
           "duration_ms": n_ticks * dt, "neurons": cfg.n_targets, "sources": cfg.n_sources,
           "params": _param_dicts(cfg), "target_sets": list(cfg.target_sets_),
           "delays_ms": (cfg.delays * dt).tolist(), "weights": cfg.weights_real.tolist(),
           "input_ms": [(np.asarray(k) * dt).tolist() for k in ins],
           "spikes_ms": spikes, "merged_inputs": run.counters.get("merged_count", 0),
           "accepted_current_range": [cfg.i_lo, cfg.i_hi],
           "formats": {"weight": str(cfg.W), "xd": str(cfg.traces[0].T),
                       "xr": str(cfg.traces[1].T), "I": str(cfg.iz.I), "V": str(cfg.iz.V),
                       "U": str(cfg.iz.U)},
           "saturation": clamp_summary(run, args.engine)}
    print_run(args, out, f"coincidence detector on {args.engine}: {cfg.n_sources} sources -> "
                         f"{cfg.n_targets} targets, dt = {dt:g} ms, {n_ticks * dt:g} ms, "
                         f"{sum(map(len, ins))} input spikes",
              [(f"target {t}: delays {', '.join(f'{d:g}' for d in cfg.delays[t] * dt)} ms", s)
               for t, s in enumerate(spikes)])
    return 0


def print_resources(args, cfg, files, synth_resources) -> None:
    """The generated ``files`` (Verilog, JSON), and with ``--resources`` the yosys synth_ecp5
    and synth_xilinx (xc6s) figures of the block (``synth_resources(cfg)``), printed and added
    to its JSON description under ``resources``."""
    for f in files:
        print(f)
    if not args.resources:
        return
    json_path = files[1]
    try:
        res = synth_resources(cfg)
    except (RuntimeError, ValueError) as exc:
        raise CliError(f"cuneate generate: {exc}") from None
    desc = json.loads(json_path.read_text())
    desc["resources"] = {f: {"flow": r["flow"], "summary": r["summary"], "cells": r["cells"]}
                         for f, r in res.items()}
    json_path.write_text(json.dumps(desc, indent=2, sort_keys=True) + "\n")
    print("resources (yosys, synthesis only):")
    print(format_resources(res))


def cmd_generate(args) -> int:
    kw = coincidence_kwargs(args) | {"tick_source": args.tick_source}
    kw.setdefault("clock_hz", 40e6)
    cfg = coincidence_from_args(kw)
    print_resources(args, cfg, generate_coincidence(output_dir(args.out), cfg, name=args.name),
                    synth_resources)
    print(f"coincidence detector: {cfg.n_sources} sources -> {cfg.n_targets} targets, "
          f"{cfg.clock_hz / 1e6:g} MHz, dt = {cfg.dt_ms:g} ms, {cfg.cycles_needed} of "
          f"{cfg.cycles_per_tick} cycles per tick; history {cfg.max_delay_ticks} x "
          f"{cfg.n_sources} bits; weights {cfg.W}, accumulator {cfg.acc_bits} bits; PSP k = "
          + ", ".join(f"{s.K.quantized:.6g} (exact {s.k_exact:.6g})" for s in cfg.traces)
          + f"; current {cfg.iz.I} accepting [{cfg.i_lo:g}, {cfg.i_hi:g}] mV/ms")
    return 0


def cmd_ridge(args) -> int:
    from .experiments import (RidgeSpec, format_comparison, ridge_comparison, ridge_estimate,
                              ridge_problem)
    if args.jitter_ms < 0 or args.speed_spread < 0:
        raise CliError("cuneate coincidence ridge: --jitter-ms and --speed-spread must be >= 0")
    spec = RidgeSpec(trials_per_angle=args.trials, jitter_ms=args.jitter_ms,
                     spread_speed=args.speed_spread, seed=args.seed,
                     speed_mm_per_s=args.speed)
    bad = ridge_problem(spec)
    if bad is not None:
        option = {"speed_mm_per_s": "--speed", "spread_speed": "--speed-spread"}[bad[0]]
        raise CliError(f"cuneate coincidence ridge: {option}: {bad[1]}")
    est = ridge_estimate(spec, ["golden", "fixed"])
    if args.hdl_engine:
        from dataclasses import replace
        hdl = ridge_estimate(replace(spec, trials_per_angle=args.hdl_trials),
                             ["fixed"] + list(args.hdl_engine))
        est = dict(est, bytes=max(est["bytes"], hdl["bytes"]),
                   seconds=est["seconds"] + hdl["seconds"])
    check_estimate("cuneate coincidence ridge", est, "fewer --trials or --hdl-trials")
    build_dir = str(output_dir(args.build_dir, "--build-dir")) if args.build_dir else None
    try:
        cmp = ridge_comparison(spec, hdl_engines=tuple(args.hdl_engine),
                               hdl_trials_per_angle=args.hdl_trials, build_dir=build_dir,
                               on_chip=args.on_chip)
    except ValueError as exc:
        raise CliError(f"cuneate coincidence ridge: {exc}") from None
    if args.json:
        print(json.dumps({"results": [r.to_dict() for r in cmp["results"]],
                          "golden_fixed_same": cmp["golden_fixed_same"],
                          "hdl_fixed_same": cmp["hdl_fixed_same"],
                          "hdl_trials": cmp["hdl_trials"]}))
    else:
        print(format_comparison(cmp))
    same = cmp["golden_fixed_same"] and all(cmp["hdl_fixed_same"].values())
    return 0 if same else 1


def register(groups: CommandGroups) -> None:
    s, _ = add_block_commands(groups, "coincidence", "the coincidence detector (cuneate "
                                                     "neurons)", 200.0, add_coincidence_options,
                              cmd_simulate, cmd_generate, "coincidence_detector", 10)
    s.add_argument("--input", action="append", default=None, metavar="MS,MS,...",
                   help="spike times (ms) of one source; give it once per source")
    s.add_argument("--input-rate-hz", type=finite_float, default=40.0,
                   help="Poisson rate of every source when no --input is given (default 40)")
    s.add_argument("--seed", type=seed_int, default=0)

    c = groups.root.add_parser("coincidence", help="coincidence-detector experiments "
                                                   "(ridge angle)")
    sub = c.add_subparsers(dest="coincidence_command", required=True, parser_class=type(c))
    r = sub.add_parser("ridge", help="ridge angle (-45, 0, +45 deg) from two sensors' SA/FA "
                                     "afferents through three cuneate neurons")
    r.add_argument("--hdl-engine", metavar="ENGINE",
                   choices=engine_choices("coincidence", hdl=True),
                   nargs="*", default=["verilator"],
                   help="HDL engines run on a few trials beside golden and fixed (default "
                        "verilator; none: give the option without a value)")
    r.add_argument("--hdl-trials", type=positive_int, default=1,
                   help="trials per angle on the HDL engines (default 1)")
    r.add_argument("--build-dir", default=None, help="HDL simulator build directory")
    r.add_argument("--on-chip", action="store_true",
                   help="the HDL engines run the on-chip afferent -> cuneate network (afferents "
                        "on the Izhikevich core) instead of the detector alone")
    r.add_argument("--trials", type=positive_int, default=10, help="trials per angle")
    r.add_argument("--jitter-ms", type=finite_float, default=0.3)
    r.add_argument("--speed", type=positive_float, default=20.0, help="mm/s")
    r.add_argument("--speed-spread", type=finite_float, default=0.05,
                   help="relative s.d. of the speed per trial")
    r.add_argument("--seed", type=seed_int, default=1)
    r.add_argument("--json", action="store_true")
    add_max_minutes(r, 60.0)
    r.set_defaults(func=cmd_ridge)
