"""``cuneate simulate izhikevich`` and ``cuneate generate izhikevich``.

Both commands take the core's options through one parser (:func:`add_core_options`) and build
the configuration through one function (:func:`core_from_args`), so they accept and refuse the
same configurations with the same message. ``simulate`` also estimates the memory and time of a
run before starting it: a run that would not fit in memory is refused, one that would take
longer than ``--max-minutes`` is refused unless ``--force`` is given (it then shows a progress
bar).
"""

from __future__ import annotations

import json

import numpy as np

from ...golden import izhikevich as gz
from ...golden.budget import fmt_count
from ...golden.izhikevich import PRESETS, SCHEMES, to_params
from ...hdl.izhikevich import IzhikevichConfig, generate_izhikevich
from ...hdl.izhikevich.config import PIPELINE_DEPTH, PIPELINE_STAGES
from ...hdl.lib.config import MIN_NEURONS
from ..cli.options import (CliError, CommandGroups, add_block_commands, add_rate_options,
                           add_waves_options, build_config, finite_float, fmt_time, generate_faced, output_dir,
                           positive_float, positive_int, run_budget, start_progress,
                           waves_from_args, write_simulate_spikes)
from ..engines.registry import estimate_seconds
from ..engines.waves import FORMATS, time_axis

__all__ = ["register", "add_core_options", "add_pipeline_option", "core_from_args",
           "parse_param_set", "estimate_run"]

#: Memory per neuron (bytes) of each engine, used to estimate a run before starting it (the
#: speeds are the engine registry's).
_BYTES_PER_NEURON = {"golden": 400, "fixed": 1200, "amaranth": 4000, "icarus": 200,
                     "verilator": 200, "verilator-fast": 200}
_BYTES_PER_SPIKE_OUT = 24           # a spike time in the JSON output and its Python list


# --------------------------------------------------------------------------------------------
# parameter sets and core options
def parse_param_set(text: str):
    """A parameter set from the command line: a preset (``RS``), a published behaviour
    (``behaviour:Q`` or ``behaviour:"depolarizing after-potential"``), or numbers
    ``a,b,c,d`` optionally followed by ``A,B,C`` and ``u_leak,v_u``."""
    t = text.strip()
    if t.lower().startswith("behaviour:"):
        from ...golden.behaviours import behaviour
        try:
            return behaviour(t.split(":", 1)[1]).params
        except ValueError as exc:
            raise CliError(f"--param-set {text!r}: {exc}") from None
    if t.upper() in gz.PRESETS:
        return gz.PRESETS[t.upper()]
    parts = [x for x in t.replace(" ", "").split(",") if x]
    try:
        nums = [float(x) for x in parts]
    except ValueError:
        raise CliError(f"--param-set {text!r}: not a preset ({', '.join(gz.PRESETS)}), "
                       f"'behaviour:LETTER' or numbers a,b,c,d[,A,B,C[,u_leak,v_u]]") from None
    if len(nums) not in (4, 7, 9):
        raise CliError(f"--param-set {text!r}: give 4 (a,b,c,d), 7 (+A,B,C) or 9 "
                       f"(+u_leak,v_u) numbers, got {len(nums)}")
    keys = ("a", "b", "c", "d", "A", "B", "C", "u_leak", "v_u")
    try:
        return gz.to_params(dict(zip(keys, nums)))
    except ValueError as exc:
        raise CliError(f"--param-set {text!r}: {exc}") from None


#: the state variables' default fraction bits
STATE_FRAC_BITS = {"v": 18, "u": 20}


def add_core_options(p, *, neurons_default: int) -> None:
    """The options that define a core, shared by ``simulate`` and ``generate``."""
    g = p.add_argument_group("core configuration")
    g.add_argument("--neurons", type=positive_int, default=neurons_default,
                   help=f"neurons on the core (default {neurons_default})")
    add_rate_options(g, 40e6)
    g.add_argument("--param-set", action="append", default=None, metavar="SPEC",
                   help="a parameter set (repeatable): preset name, behaviour:LETTER, or "
                        "a,b,c,d[,A,B,C[,u_leak,v_u]]")
    g.add_argument("--neuron-sets", default="cycle", metavar="cycle|LIST",
                   help="set index of each neuron: 'cycle' (round robin, default) or a comma "
                        "list with one index per neuron")
    g.add_argument("--current-range", type=finite_float, nargs=2, default=None,
                   metavar=("LO", "HI"),
                   help="accepted input currents in mV/ms (default: the current format, "
                        "+-512); the state formats are sized for it")
    g.add_argument("--saturation", choices=("refuse", "flag"), default="refuse",
                   help="formats narrower than the proven state range: refuse (default) or "
                        "accept with flagged, counted clamps")
    for s, frac in STATE_FRAC_BITS.items():          # each state variable's format
        g.add_argument(f"--{s}-int-bits", type=positive_int, default=None,
                       help=f"integer bits of {s} (default: derived from the proven range)")
        g.add_argument(f"--{s}-frac-bits", type=positive_int, default=frac)
    g.add_argument("--operand-width", type=positive_int, default=18,
                   help="multiplier operand width (default 18)")
    g.add_argument("--y-frac-bits", type=positive_int, default=None,
                   help="fewest fraction bits of the b v - u operand (default width - 9)")
    g.add_argument("--y-int-bits", type=positive_int, default=None,
                   help="integer bits of b v - u (default: proven; fewer add a flagged clamp)")
    g.add_argument("--rounding", choices=("nearest", "truncate"), default="nearest")
    add_pipeline_option(g)


def add_pipeline_option(g) -> None:
    """``--pipeline-stages``: the core's pipeline depth (generate, simulate, build)."""
    g.add_argument("--pipeline-stages", type=int, choices=PIPELINE_STAGES,
                   default=PIPELINE_DEPTH,
                   help=f"pipeline depth of the core (default {PIPELINE_DEPTH}; deeper "
                        f"registers more of the datapath for a faster clock, same arithmetic)")


def _neuron_sets(spec: str, n: int, n_sets: int) -> list[int]:
    if spec == "cycle":
        return [i % n_sets for i in range(n)]
    try:
        vals = [int(x) for x in spec.split(",") if x.strip()]
    except ValueError:
        raise CliError(f"--neuron-sets {spec!r}: 'cycle' or a comma list of integers") from None
    if len(vals) != n:
        raise CliError(f"--neuron-sets needs one index per neuron ({n}), got {len(vals)}")
    if any(not 0 <= v < n_sets for v in vals):
        raise CliError(f"--neuron-sets: indices must be in [0, {n_sets}) for {n_sets} "
                       f"parameter set(s)")
    return vals


def core_kwargs(args, param_sets, n_core: int, n: int | None = None) -> dict:
    """Constructor keywords of the core described by the shared options; ``--neuron-sets``
    gives the set of each of the ``n`` neurons asked for (default ``n_core``), and the neurons
    that pad the core to ``n_core`` use set 0."""
    if n_core * args.update_hz > args.clock_hz:     # refuse before building per-neuron lists
        core_from_args({"n_neurons": n_core, "clock_hz": args.clock_hz,
                        "update_hz": args.update_hz, "param_sets": tuple(param_sets)})
    n = n_core if n is None else n
    kw = {"n_neurons": n_core, "clock_hz": args.clock_hz, "update_hz": args.update_hz,
          "param_sets": tuple(param_sets),
          "neuron_sets": (_neuron_sets(args.neuron_sets, n, len(param_sets))
                          + [0] * (n_core - n)),
          "v_int_bits": args.v_int_bits, "u_int_bits": args.u_int_bits,
          "v_frac_bits": args.v_frac_bits, "u_frac_bits": args.u_frac_bits,
          "operand_width": args.operand_width, "y_frac_bits": args.y_frac_bits,
          "y_int_bits": args.y_int_bits, "rounding": args.rounding,
          "saturation": args.saturation, "pipeline_stages": args.pipeline_stages,
          "current_range": tuple(args.current_range) if args.current_range else None}
    return kw


def core_from_args(kwargs: dict):
    """The configuration, or the one-line refusal shared by every command."""
    return build_config(IzhikevichConfig, kwargs)


# --------------------------------------------------------------------------------------------
# simulate
def _param_sets(args) -> list:
    """``--param-set`` (repeatable) or the single set of ``--preset`` and ``--a/b/c/d``."""
    overrides = {k: getattr(args, k) for k in "abcd" if getattr(args, k, None) is not None}
    if args.param_set:
        if overrides or args.preset != "RS":
            raise CliError("give either --param-set or --preset/--a/--b/--c/--d, not both")
        return [parse_param_set(s) for s in args.param_set]
    base = PRESETS[args.preset]
    if not overrides:
        return [base]
    vals = {k: getattr(base, k) for k in "abcd"} | overrides
    try:
        return [to_params(vals)]
    except ValueError as exc:
        raise CliError(f"cuneate simulate: {exc}") from None


def _currents(args, n):
    cur = args.current
    if len(cur) == 1:
        return [cur[0]] * n
    if len(cur) != n:
        raise CliError(f"--current takes one value or one per neuron ({n}), got {len(cur)}")
    return list(cur)


def estimate_run(engine: str, n: int, n_sweeps: int, rate_hz: float = 50.0) -> dict:
    """Memory (bytes) and time (s) a run will take, from conservative per-engine figures;
    ``rate_hz`` is the spike rate assumed for the size of the output."""
    n_core = max(n, MIN_NEURONS)
    work = n_core * n_sweeps                        # updates (= cycles on HDL simulators)
    seconds = estimate_seconds("izhikevich", engine, work)
    spikes = n * n_sweeps * rate_hz / 16e3
    mem = n_core * _BYTES_PER_NEURON.get(engine, 200) + spikes * _BYTES_PER_SPIKE_OUT
    return {"updates": work, "seconds": seconds, "bytes": mem}


def cmd_simulate(args) -> int:
    start_progress(args)
    from .engines import run_engine

    n = args.neurons
    sets = _param_sets(args)
    n_core = max(n, MIN_NEURONS)
    kw = core_kwargs(args, sets, n_core, n)   # idle neurons pad the core to its minimum
    currents = _currents(args, n)
    cfg = core_from_args(kw)                  # the same refusals as `generate`
    golden_run = args.engine == "golden"
    if not golden_run:
        if args.scheme != "euler":
            raise CliError(f"engine {args.engine!r} implements forward Euler only "
                           f"(--scheme {args.scheme} is a golden-engine option)")
        if args.dt_ms is not None:
            raise CliError(f"engine {args.engine!r} takes its dt from --update-hz "
                           f"(dt = 1000/update_hz ms), not --dt-ms")
        for x in currents:
            if not cfg.i_lo <= x <= cfg.i_hi:
                raise CliError(f"cuneate simulate: current {x:g} is outside the core's "
                               f"accepted range [{cfg.i_lo:g}, {cfg.i_hi:g}] mV/ms (format "
                               f"{cfg.I}; see --current-range)")
    dt_ms = args.dt_ms if (golden_run and args.dt_ms is not None) else cfg.dt_ms
    n_sweeps = int(round(args.duration_ms / dt_ms))
    if n_sweeps < 1:
        raise CliError(f"--duration-ms {args.duration_ms:g} is shorter than one update "
                       f"(dt = {dt_ms:g} ms)")
    est = estimate_run(args.engine, n, n_sweeps)
    run_budget("cuneate simulate izhikevich", "izhikevich", args.engine, est["updates"],
               est["bytes"], f"{n} neuron(s) x {fmt_count(n_sweeps)} updates",
               "reduce --neurons or --duration-ms, pick a faster engine, or pass --force to "
               "run it anyway with a progress bar")
    waves = waves_from_args(args)
    if waves is not None and args.engine not in FORMATS:
        raise CliError(f"--waves: engine {args.engine!r} writes no waveforms (those that do: "
                       f"{', '.join(FORMATS)})")
    if waves is not None:
        try:
            waves = waves.within(n_sweeps)
        except ValueError as exc:
            raise CliError(f"--waves-start {waves.start}: {exc}") from None
    build_dir = None
    if not golden_run and args.build_dir:
        build_dir = output_dir(args.build_dir, "--build-dir")
    from .. import progress as prog
    saturation = None
    with prog.step(f"simulating {n} neuron(s) on {args.engine} (~{fmt_time(est['seconds'])} "
                   f"estimated)", total=n_sweeps, unit="sweep") as st:
        progress = st.set
        if golden_run:
            try:
                cur = np.asarray(currents, dtype=float)
                res = gz.simulate([sets[s] for s in cfg.neuron_sets[:n]],
                                  (lambda t_ms: cur) if n > 1 else float(cur[0]),
                                  n_steps=n_sweeps, n_neurons=n, dt_ms=dt_ms,
                                  scheme=args.scheme, progress=progress)
            except gz.DivergenceError as exc:
                raise CliError(f"cuneate simulate izhikevich: {exc}") from None
            except ValueError as exc:
                raise CliError(f"cuneate simulate: {exc}") from None
            spikes = [s.tolist() for s in res.spikes_ms]
        else:
            try:
                run = run_engine(args.engine, kw, currents, n_sweeps * dt_ms, build_dir,
                                 progress, waves)
            except ValueError as exc:
                raise CliError(f"cuneate simulate: {exc}") from None
            spikes = run.spikes_ms
            # the board's link carries no clamp counters
            saturation = None if run.clamp_counts is None else \
                {"counts": run.clamp_counts, "sticky": run.clamp_sticky}
    write_simulate_spikes(args, spikes, "izhikevich", n_sweeps * dt_ms, dt_ms)
    params = sets[0].to_dict() if len(sets) == 1 else [s.to_dict() for s in sets]
    if isinstance(params, dict):
        params = {k: v for k, v in params.items() if k in "abcd"} | \
            {k: v for k, v in params.items() if k not in "abcd" and k != "name"}
    out = {"engine": args.engine, "model": "izhikevich", "dt_ms": dt_ms,
           "scheme": args.scheme, "duration_ms": n_sweeps * dt_ms, "neurons": n,
           "params": params, "current": currents, "spikes_ms": spikes,
           "accepted_current_range": [cfg.i_lo, cfg.i_hi],
           "formats": {k: str(getattr(cfg, k)) for k in ("V", "U", "I", "W", "VQ", "Q", "Y")},
           "saturation": saturation}
    if waves is not None:
        dump = waves.path(args.engine)
        out["waves"] = waves.to_dict() | {"dump": str(dump),
                                          "gtkw": str(dump.with_suffix(".gtkw")),
                                          "time_axis": time_axis(args.engine, cfg.clock_hz)}
    if args.spikes:
        out["spike_file"] = str(args.spikes)
    if args.json:
        print(json.dumps(out))
    else:
        p0 = sets[0]
        print(f"engine {args.engine}, dt = {dt_ms:g} ms, {n_sweeps * dt_ms:g} ms, "
              + (f"a={p0.a:g} b={p0.b:g} c={p0.c:g} d={p0.d:g}" if len(sets) == 1 else
                 f"{len(sets)} parameter sets"))
        for i, s in enumerate(spikes):
            rate = 1000.0 * len(s) / (n_sweeps * dt_ms)
            head = ", ".join(f"{t:g}" for t in s[:6]) + (" ..." if len(s) > 6 else "")
            print(f"  neuron {i}: I = {currents[i]:g}, {len(s)} spikes ({rate:.1f} Hz): {head}")
        if saturation is not None:
            acted = {k: c for k, c in saturation["counts"].items() if c}
            print("  clamps: " + (", ".join(f"{k} {c}" for k, c in acted.items())
                                  if acted else "none acted"))
        if waves is not None:
            print(f"  waves: {out['waves']['dump']} (ticks {waves.start}.."
                  f"{waves.start + waves.ticks - 1}; GTKWave: {out['waves']['gtkw']}; "
                  f"{out['waves']['time_axis']})")
        if args.spikes:
            print(f"  spikes: {args.spikes}")
    return 0


# --------------------------------------------------------------------------------------------
# generate
def cmd_generate(args) -> int:
    sets = [parse_param_set(s) for s in args.param_set] if args.param_set else [PRESETS["RS"]]
    kw = core_kwargs(args, sets, args.neurons) | {"tick_source": args.tick_source}
    cfg = core_from_args(kw)
    if args.face != "none":
        return generate_faced(args, cfg, "izhikevich")
    out = output_dir(args.out)
    files = generate_izhikevich(out, config=cfg)
    for f in files:
        print(f)
    can_act = [k for k, v in cfg.clamp_can_act.items() if v]
    print(f"{cfg.n_neurons} neurons, {cfg.clock_hz / 1e6:g} MHz, dt = {cfg.dt_ms:g} ms; v {cfg.V}, "
          f"u {cfg.U}, I {cfg.I} accepting [{cfg.i_lo:g}, {cfg.i_hi:g}] mV/ms; clamps that can "
          f"act for accepted inputs: {', '.join(can_act) if can_act else 'none'}")
    return 0


def register(groups: CommandGroups) -> None:
    s, g = add_block_commands(groups, "izhikevich", "the Izhikevich core", 1000.0,
                              faces=True)
    s.add_argument("--preset", choices=list(PRESETS), default="RS", type=str.upper)
    for k in "abcd":
        s.add_argument(f"--{k}", type=finite_float, default=None,
                       help=f"override the preset's {k}")
    s.add_argument("--current", type=finite_float, nargs="+", default=[10.0],
                   help="input current (mV/ms): one value, or one per neuron")
    s.add_argument("--dt-ms", type=positive_float, default=None,
                   help="golden engine step (default: the core's, 1000/update_hz)")
    s.add_argument("--scheme", choices=SCHEMES, default="euler")
    s.add_argument("--force", action="store_true",
                   help="run even when estimated to take longer than --max-minutes")
    add_waves_options(s)
    add_core_options(s, neurons_default=1)
    s.set_defaults(func=cmd_simulate)

    add_core_options(g, neurons_default=2500)
    g.set_defaults(func=cmd_generate)

