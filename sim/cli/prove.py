"""``cuneate prove``: SymbiYosys checks of the Izhikevich datapath
(:mod:`cuneate.hdl.izhikevich.formal`) and ``cuneate prove core|lif``: the pipelined Izhikevich or LIF core
against its one-step datapath (:mod:`cuneate.hdl.izhikevich.formal_core`,
:mod:`cuneate.hdl.lif.formal_core`; k-induction with ``--unbounded``)."""

from __future__ import annotations

from pathlib import Path

from .options import CliError, CommandGroups, positive_float, positive_int

__all__ = ["register", "cmd_prove"]


def cmd_prove_core(args) -> int:
    """``cuneate prove core|lif``: bounded (``--depth``, default the induction depth) or, with
    ``--unbounded``, k-induction; PASS/FAIL with mode, depth, solver and time."""
    import json
    import tempfile
    from ...hdl.izhikevich import ConfigError
    from ...hdl.izhikevich.formal import FormalError
    from ...hdl.izhikevich.formal_core import proof_config, prove_core
    from ...hdl.lif.formal_core import lif_proof_config, prove_lif
    configure, prove = ((proof_config, prove_core) if args.target == "core"
                        else (lif_proof_config, prove_lif))
    try:
        if args.default_config:
            from ...hdl.izhikevich import IzhikevichConfig
            from ...hdl.lif import LifConfig
            cfg = IzhikevichConfig() if args.target == "core" else LifConfig()
        else:
            cfg = configure(args.neurons) if args.neurons else configure()
    except ConfigError as exc:
        raise CliError(f"cuneate prove {args.target}: {exc}") from None
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        try:
            r = prove(cfg, Path(args.work_dir) if args.work_dir else Path(d),
                           mode="prove" if args.unbounded else "bmc", depth=args.depth,
                           mutant=args.mutant, timeout_s=args.timeout_s, solver=args.solver)
        except FormalError as exc:
            raise CliError(f"cuneate prove {args.target}: {exc}") from None
    out = r.to_dict() | {"n_neurons": cfg.n_neurons, "mutant": args.mutant}
    if args.json:
        print(json.dumps(out))
    else:
        what = "k-induction" if r.mode == "prove" else "bounded from the initial state"
        print(f"{r.property}: {r.status.upper()} ({what}, depth {r.depth}, {r.engine} "
              f"{r.solver}, {r.seconds:.1f} s, N = {cfg.n_neurons}"
              + (f", mutant {args.mutant}" if args.mutant else "") + ")")
        if r.failed:
            print(f"  failed in step {r.step} ({r.phase}): {', '.join(r.failed)}")
        for a in r.abstractions:
            print(f"  abstraction: {a}")
    return 0 if r.passed else 1


def cmd_prove(args) -> int:
    if args.target in ("core", "lif"):
        return cmd_prove_core(args)
    import json
    import tempfile
    from ...hdl.izhikevich import ConfigError, IzhikevichConfig
    from ...hdl.izhikevich.formal import FormalError, prove
    args.preset = args.preset or ["RS"]
    try:
        cfg = IzhikevichConfig(n_neurons=8, clock_hz=args.update_hz * 8,
                               update_hz=args.update_hz, param_sets=tuple(args.preset),
                               operand_width=args.operand_width, rounding=args.rounding)
    except ConfigError as exc:
        raise CliError(f"cuneate prove: {exc}") from None
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        try:
            r = prove(cfg, Path(args.work_dir) if args.work_dir else Path(d), args.property,
                      timeout_s=args.timeout_s, solver=args.solver)
        except FormalError as exc:
            raise CliError(f"cuneate prove: {exc}") from None
    r |= {"param_sets": list(args.preset), "update_hz": args.update_hz,
          "operand_width": args.operand_width, "rounding": args.rounding}
    if args.json:
        print(json.dumps(r))
    else:
        what = {"datapath": "no narrowing of the datapath wraps and the y clamp never acts",
                "state_box": "one update keeps every state of the box in the box, no clamp",
                "steps": "the core's pipelined steps compute the four-stage update"}
        print(f"{r['property']}: {what[r['property']]} - {r['status'].upper()} "
              f"({args.solver}, {r['seconds']:.1f} s)")
        if "products" in r:
            t = r["products"]
            print(f"  q w product: {t['states']} states compared, {t['mismatches']} "
                  f"mismatches ({t['seconds']:.1f} s)")
        if r["counterexample"]:
            c = r["counterexample"]
            print(f"  counterexample: v = {cfg.V.to_float(c['v']):.6g} mV, "
                  f"u = {cfg.U.to_float(c['u']):.6g}, I = {cfg.I.to_float(c['I']):.6g} mV/ms, "
                  f"set {c.get('sel', 0)}")
    return 0 if r["status"] == "pass" else 1


def register(groups: CommandGroups) -> None:
    from ...hdl.flow.sby import SOLVER, SOLVERS
    from ...hdl.lib.core_proof import MUTANTS
    f = groups.root.add_parser("prove", help="SymbiYosys checks of the one-update datapath "
                               "and of the pipelined core")
    f.add_argument("target", nargs="?", choices=("datapath", "core", "lif"),
                   default="datapath",
                   help="datapath (default): one update's range properties; core, lif: the "
                   "pipelined Izhikevich or LIF core equals its one-step datapath")
    f.add_argument("--unbounded", action="store_true",
                   help="core: k-induction (every input sequence of every length)")
    f.add_argument("--depth", type=positive_int, default=None,
                   help="core: steps (default the core's latency + 2)")
    f.add_argument("--neurons", type=positive_int, default=None,
                   help="core: neurons (default the fewest accepted, one per stage)")
    f.add_argument("--default-config", action="store_true",
                   help="core, lif: the block's default configuration (e.g. 2500 neurons, "
                   "internal tick) instead of the smallest core")
    f.add_argument("--mutant", choices=MUTANTS, default=None,
                   help="core: build this fault into the core (the proof must fail)")
    f.add_argument("--solver", choices=SOLVERS, default=SOLVER)
    f.add_argument("--preset", action="append", default=None,
                   help="parameter set(s) (repeat for a mix; default RS)")
    f.add_argument("--property", choices=("datapath", "state_box", "steps"),
                   default="datapath", help="datapath: no narrowing wraps; state_box: the box "
                   "is closed (it is not: a counterexample); steps: the core's pipelined steps "
                   "equal the four-stage update")
    f.add_argument("--update-hz", type=positive_float, default=16e3)
    f.add_argument("--operand-width", type=positive_int, default=18)
    f.add_argument("--rounding", choices=("nearest", "truncate"), default="nearest")
    f.add_argument("--timeout-s", type=positive_float, default=1800.0)
    f.add_argument("--work-dir", default=None, help="keep the SymbiYosys files here")
    f.add_argument("--json", action="store_true")
    f.set_defaults(func=cmd_prove, preset=None)
