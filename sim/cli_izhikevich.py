"""``cuneate simulate izhikevich`` and ``cuneate generate izhikevich``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .cliutil import (CliError, CommandGroups, finite_float, positive_float, positive_int)

__all__ = ["register", "ENGINES"]

ENGINES = ("golden", "fixed", "amaranth", "icarus", "verilator")


def _neuron_params(args):
    from ..golden.izhikevich import PRESETS
    base = PRESETS[args.preset]
    vals = {k: getattr(base, k) for k in "abcd"}
    for k in "abcd":
        if getattr(args, k) is not None:
            vals[k] = getattr(args, k)
    return vals


def _currents(args, n):
    cur = args.current
    if len(cur) == 1:
        return [cur[0]] * n
    if len(cur) != n:
        raise CliError(f"--current takes one value or one per neuron ({n}), got {len(cur)}")
    return list(cur)


def cmd_simulate(args) -> int:
    import numpy as np
    from ..golden import izhikevich as gz

    n = args.neurons
    params = _neuron_params(args)
    currents = _currents(args, n)
    if args.engine == "golden":
        dt_ms = args.dt_ms if args.dt_ms is not None else (
            1000.0 / args.update_hz if args.update_hz else gz.DEFAULT_DT_MS)
        try:
            cur = np.asarray(currents, dtype=float)
            res = gz.simulate((params["a"], params["b"], params["c"], params["d"]),
                              (lambda t_ms: cur) if n > 1 else float(cur[0]),
                              duration_ms=args.duration_ms, n_neurons=n, dt_ms=dt_ms,
                              scheme=args.scheme)
        except gz.DivergenceError as exc:
            print(f"cuneate simulate: {exc}", file=sys.stderr)
            return 1
        spikes = [s.tolist() for s in res.spikes_ms]
    else:
        if args.scheme != "euler":
            raise CliError(f"engine {args.engine!r} implements forward Euler only "
                           f"(--scheme {args.scheme} is a golden-engine option)")
        if args.dt_ms is not None:
            raise CliError(f"engine {args.engine!r} takes its dt from --update-hz "
                           f"(dt = 1000/update_hz ms), not --dt-ms")
        from .engines import run_hardware_engine
        try:
            dt_ms, spikes = run_hardware_engine(
                args.engine, params=params, currents=currents, duration_ms=args.duration_ms,
                update_hz=args.update_hz or 16e3, clock_hz=args.clock_hz,
                build_dir=Path(args.build_dir) if args.build_dir else None)
        except ValueError as exc:
            raise CliError(f"cuneate simulate: {exc}") from None
    out = {"engine": args.engine, "model": "izhikevich", "dt_ms": dt_ms,
           "scheme": args.scheme, "duration_ms": args.duration_ms, "neurons": n,
           "params": params, "current": currents, "spikes_ms": spikes}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"engine {args.engine}, dt = {dt_ms:g} ms, {args.duration_ms:g} ms, "
              f"a={params['a']:g} b={params['b']:g} c={params['c']:g} d={params['d']:g}")
        for i, s in enumerate(spikes):
            rate = 1000.0 * len(s) / args.duration_ms if args.duration_ms else 0.0
            head = ", ".join(f"{t:g}" for t in s[:6]) + (" ..." if len(s) > 6 else "")
            print(f"  neuron {i}: I = {currents[i]:g}, {len(s)} spikes ({rate:.1f} Hz): {head}")
    return 0


def cmd_generate(args) -> int:
    from ..hdl.generate import generate_izhikevich
    try:
        files = generate_izhikevich(Path(args.out), n_neurons=args.neurons,
                                    clock_hz=args.clock_hz, update_hz=args.update_hz)
    except ValueError as exc:
        raise CliError(f"cuneate generate: {exc}") from None
    for f in files:
        print(f)
    return 0


def register(groups: CommandGroups) -> None:
    from ..golden.izhikevich import PRESETS, SCHEMES
    s = groups.simulate.add_parser("izhikevich", help="the Izhikevich core")
    s.add_argument("--engine", choices=ENGINES, default="golden")
    s.add_argument("--preset", choices=list(PRESETS), default="RS", type=str.upper)
    for k in "abcd":
        s.add_argument(f"--{k}", type=finite_float, default=None,
                       help=f"override the preset's {k}")
    s.add_argument("--current", type=finite_float, nargs="+", default=[10.0],
                   help="input current (mV/ms): one value, or one per neuron")
    s.add_argument("--duration-ms", type=positive_float, default=1000.0)
    s.add_argument("--neurons", type=positive_int, default=1)
    s.add_argument("--dt-ms", type=positive_float, default=None,
                   help="golden engine step (default 1/16 ms)")
    s.add_argument("--update-hz", type=positive_float, default=None,
                   help="per-neuron update rate of the hardware engines (default 16e3)")
    s.add_argument("--clock-hz", type=positive_float, default=40e6)
    s.add_argument("--scheme", choices=SCHEMES, default="euler")
    s.add_argument("--build-dir", default=None, help="HDL simulator build directory")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_simulate)

    g = groups.generate.add_parser("izhikevich", help="the Izhikevich core")
    g.add_argument("--neurons", type=positive_int, default=2500)
    g.add_argument("--clock-hz", type=positive_float, default=40e6)
    g.add_argument("--update-hz", type=positive_float, default=16e3)
    g.add_argument("--out", required=True)
    g.set_defaults(func=cmd_generate)
