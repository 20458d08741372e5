"""``cuneate simulate lif``, ``cuneate generate lif`` and the LIF experiments
(``cuneate lif skin``, ``cuneate lif quantization``).

``simulate`` and ``generate`` take the core's options through one parser
(:func:`add_lif_options`) and build the configuration through one function
(:func:`lif_kwargs` + :func:`lif_from_kwargs`), so they accept and refuse the same
configurations with the same one-line message.
"""

from __future__ import annotations

import json

import numpy as np

from ...hdl.lif import ConfigError, LifConfig, generate_lif
from ..cli.options import (CliError, CommandGroups, add_block_commands, add_max_minutes,
                           add_rate_options, clamp_summary, engine_choices, finite_float,
                           generate_faced, input_file, nonneg_int, output_dir, positive_float, positive_int,
                           print_run, probability, run_ticks, seed_int)

__all__ = ["register", "add_lif_options", "lif_kwargs", "lif_from_kwargs"]



def add_lif_options(p, *, neurons_default: int) -> None:
    g = p.add_argument_group("core configuration")
    g.add_argument("--neurons", type=positive_int, default=neurons_default)
    g.add_argument("--form", choices=("continuous", "discrete"), default="continuous")
    add_rate_options(g, None, "core clock (generate: default 40e6; simulate: the engines' own)")
    g.add_argument("--decay", choices=("multiply", "shift"), default="multiply",
                   help="leak by a multiplier or by shift-and-subtract (k = 2**-s)")
    g.add_argument("--tau-m-ms", type=positive_float, default=20.0)
    g.add_argument("--v-th", type=finite_float, default=None,
                   help="threshold (default 18 mV continuous, 0.65 discrete)")
    g.add_argument("--v-reset", type=finite_float, default=None,
                   help="reset (default 11 mV continuous, 0 discrete)")
    g.add_argument("--v-rest", type=finite_float, default=0.0)
    g.add_argument("--t-ref-ms", type=finite_float, default=2.0)
    g.add_argument("--alpha", type=finite_float, default=0.389, help="discrete decay")
    g.add_argument("--refractory-steps", type=nonneg_int, default=0)
    g.add_argument("--v-frac-bits", type=positive_int, default=16)
    g.add_argument("--v-int-bits", type=positive_int, default=None)
    g.add_argument("--operand-width", type=positive_int, default=18)
    g.add_argument("--current-format", type=positive_int, nargs=2, default=None,
                   metavar=("INT", "FRAC"),
                   help="host current format (default 8 8 continuous, 4 12 discrete)")
    g.add_argument("--weights", default=None, metavar="CSV",
                   help="weights of the input spikes, one row per neuron (n_neurons x n_inputs)")
    g.add_argument("--weight-bits", type=positive_int, default=8)
    g.add_argument("--synapses", action="store_true",
                   help="AMPA/GABA difference-of-exponentials currents from the input spikes "
                        "(continuous form; weights >= 0 are peak currents in mV)")
    g.add_argument("--input-types", default=None, metavar="exc,inh,...",
                   help="type of every input source with --synapses (default all exc)")
    g.add_argument("--saturation", choices=("refuse", "flag"), default="refuse")
    g.add_argument("--rounding", choices=("nearest", "truncate"), default="nearest")
    g.add_argument("--max-decay-error", type=positive_float, default=1e-2)


def lif_kwargs(args, n: int) -> dict:
    """Constructor keywords of :class:`~cuneate.hdl.lif.LifConfig` from the shared options."""
    if args.form == "continuous":
        ps = {"tau_m_ms": args.tau_m_ms, "v_rest": args.v_rest, "t_ref_ms": args.t_ref_ms,
              "v_th": 18.0 if args.v_th is None else args.v_th,
              "v_reset": 11.0 if args.v_reset is None else args.v_reset}
    else:
        ps = {"alpha": args.alpha, "refractory_steps": args.refractory_steps,
              "v_th": 0.65 if args.v_th is None else args.v_th,
              "v_reset": 0.0 if args.v_reset is None else args.v_reset}
    cf = args.current_format or ((8, 8) if args.form == "continuous" else (4, 12))
    kw = {"n_neurons": n, "update_hz": args.update_hz, "form": args.form,
          "param_sets": [ps], "decay": args.decay, "v_frac_bits": args.v_frac_bits,
          "v_int_bits": args.v_int_bits, "operand_width": args.operand_width,
          "current_format": tuple(cf), "weight_bits": args.weight_bits,
          "saturation": args.saturation, "rounding": args.rounding,
          "max_decay_error": args.max_decay_error, "synapses": args.synapses}
    if args.input_types:
        kw["input_types"] = [t.strip() for t in args.input_types.split(",")]
    if args.clock_hz is not None:
        kw["clock_hz"] = args.clock_hz
    if args.weights:
        path = input_file(args.weights, "--weights")
        try:
            w = np.loadtxt(path, delimiter=",", ndmin=2)
        except ValueError as exc:
            raise CliError(f"--weights {args.weights!r}: not a numeric CSV: {exc}") from None
        if w.shape[0] != n:
            raise CliError(f"--weights {args.weights!r}: {w.shape[0]} rows for {n} neurons")
        kw["weights"] = w
    return kw


def lif_from_kwargs(kw: dict, engine_n: int | None = None):
    """The configuration (or, with ``engine_n``, the engine's), or a one-line refusal."""
    from .engines import engine_config
    try:
        return engine_config(kw, engine_n) if engine_n is not None else LifConfig(**kw)
    except (ConfigError, ValueError) as exc:
        raise CliError(f"cuneate: {exc}") from None


# --------------------------------------------------------------------------------------------
def cmd_simulate(args) -> int:
    from .engines import LifProgram, run_lif
    n = args.neurons
    kw = lif_kwargs(args, n)
    kw.pop("clock_hz", None)
    cfg = lif_from_kwargs(kw, n)
    cur = args.current
    if len(cur) not in (1, n):
        raise CliError(f"--current takes one value or one per neuron ({n}), got {len(cur)}")
    cur = [cur[0]] * n if len(cur) == 1 else list(cur)
    n_sweeps = run_ticks("cuneate simulate lif", "lif", args, cfg.dt_ms, cfg.n_neurons,
                         cfg.n_neurons, unit="sweep")
    if args.engine != "golden":
        for x in cur:
            if not cfg.I.contains(x):
                raise CliError(f"cuneate simulate lif: current {x:g} is outside the core's "
                               f"input format {cfg.I} [{cfg.I.min_value:g}, "
                               f"{cfg.I.max_value:g}]")
    inputs = None
    if cfg.n_inputs:
        rng = np.random.default_rng(args.seed)
        inputs = rng.random((n_sweeps, cfg.n_inputs)) < args.input_rate
    build_dir = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    program = LifProgram(np.tile(np.asarray(cur + [0.0] * (cfg.n_neurons - n)),
                                 (n_sweeps, 1)), inputs)
    try:
        run = run_lif(args.engine, cfg, program, n=n, build_dir=build_dir)
    except ValueError as exc:
        raise CliError(f"cuneate simulate lif: {exc}") from None
    out = {"engine": args.engine, "model": "lif", "form": cfg.form, "dt_ms": cfg.dt_ms,
           "scheme": "exact" if cfg.form == "continuous" else "discrete",
           "decay": cfg.decay, "duration_ms": n_sweeps * cfg.dt_ms, "neurons": n,
           "params": dict(cfg.param_sets[0]), "current": cur, "spikes_ms": run.spikes_ms,
           "accepted_current_range": [cfg.i_lo, cfg.i_hi],
           "formats": {"V": str(cfg.V), "I": str(cfg.I), "W": str(cfg.W),
                       "X": str(cfg.X) if cfg.X else None},
           "saturation": clamp_summary(run, args.engine)}
    print_run(args, out, f"LIF ({cfg.form}, decay {cfg.decay}) on {args.engine}, dt = "
                         f"{cfg.dt_ms:g} ms, {n_sweeps * cfg.dt_ms:g} ms",
              [(f"neuron {i}: I = {cur[i]:g}", s) for i, s in enumerate(run.spikes_ms)])
    return 0


def cmd_generate(args) -> int:
    kw = lif_kwargs(args, args.neurons) | {"tick_source": args.tick_source}
    kw.setdefault("clock_hz", 40e6)
    cfg = lif_from_kwargs(kw)
    if args.face != "none":
        return generate_faced(args, cfg, "lif")
    files = generate_lif(output_dir(args.out), cfg)
    for f in files:
        print(f)
    print(f"{cfg.n_neurons} LIF neurons ({cfg.form}, decay {cfg.decay}), "
          f"{cfg.clock_hz / 1e6:g} MHz, dt = {cfg.dt_ms:g} ms; v {cfg.V}, I {cfg.I}, "
          f"{cfg.n_inputs} inputs of {cfg.W}, accumulator {cfg.acc_bits} bits; k = "
          + ", ".join(f"{c.quantized:.6g} (exact {k:.6g})" for c, k in zip(cfg.K, cfg.k_exact)))
    return 0


def cmd_skin(args) -> int:
    from .experiments import format_skin, skin_3x3
    try:
        res = skin_3x3(args.engine, pressed=args.pressed, k1=args.k1, k2=args.k2,
                       update_hz=args.update_hz)
    except ValueError as exc:
        raise CliError(f"cuneate lif skin: {exc}") from None
    if args.json:
        print(json.dumps(res.to_dict()))
    else:
        print(format_skin(res))
    ok = res.width_monotonic and res.amplitude_monotonic and res.pressed_wins
    return 0 if ok else 1


def cmd_quantization(args) -> int:
    from .experiments import format_quantization, quantization_table
    rows = quantization_table(n_inputs=args.inputs, n_neurons=args.neurons_q,
                              n_steps=args.steps, seed=args.seed)
    if args.json:
        print(json.dumps([r.to_dict() for r in rows]))
    else:
        print(f"discrete LIF layer: {args.inputs} inputs -> {args.neurons_q} neurons, "
              f"{args.steps} steps, alpha 0.389, u_th 0.65 (counts and VP against FP32)")
        print(format_quantization(rows))
    return 0


def register(groups: CommandGroups) -> None:
    s, g = add_block_commands(groups, "lif", "the LIF core", 200.0, faces=True)
    s.add_argument("--current", type=finite_float, nargs="+", default=[25.0],
                   help="host current (mV, or u per step for --form discrete): one value or "
                        "one per neuron")
    s.add_argument("--input-rate", type=probability, default=0.1,
                   help="probability per tick of each input spike (with --weights)")
    s.add_argument("--seed", type=seed_int, default=0)
    add_lif_options(s, neurons_default=1)
    s.set_defaults(func=cmd_simulate)

    add_lif_options(g, neurons_default=2500)
    g.set_defaults(func=cmd_generate)

    lif = groups.root.add_parser("lif", help="LIF experiments (3x3 skin, quantization table)")
    sub = lif.add_subparsers(dest="lif_command", required=True, parser_class=type(lif))
    sk = sub.add_parser("skin", help="3x3 skin: pulses of growing width and amplitude")
    sk.add_argument("--engine", choices=engine_choices("lif"), metavar="ENGINE",
                    default="fixed", help="%(choices)s (default fixed)")
    sk.add_argument("--pressed", type=nonneg_int, default=4)
    sk.add_argument("--k1", type=finite_float, default=5.0, help="mV")
    sk.add_argument("--k2", type=finite_float, default=20.0, help="mV per force unit")
    sk.add_argument("--update-hz", type=positive_float, default=1000.0)
    sk.add_argument("--json", action="store_true")
    add_max_minutes(sk, 60.0)
    sk.set_defaults(func=cmd_skin)
    q = sub.add_parser("quantization", help="FP32 vs INT8 vs INT4 weights, discrete LIF")
    q.add_argument("--inputs", type=positive_int, default=64)
    q.add_argument("--neurons", dest="neurons_q", type=positive_int, default=32)
    q.add_argument("--steps", type=positive_int, default=100)
    q.add_argument("--seed", type=seed_int, default=0)
    q.add_argument("--json", action="store_true")
    add_max_minutes(q, 60.0)
    q.set_defaults(func=cmd_quantization)
