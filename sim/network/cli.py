"""``cuneate simulate network`` and ``cuneate generate network``: the on-chip afferent ->
cuneate network (:mod:`cuneate.hdl.network`), with the coincidence detector's options plus
``--afferents``, ``--first-source`` and the afferents' currents."""

from __future__ import annotations

import json

import numpy as np

from ..cli.options import (CliError, CommandGroups, engine_choices, finite_float, nonneg_int,
                           output_dir, positive_float, positive_int, refuse_long_run)
from ..coincidence.cli import (add_coincidence_options, add_resources_option, coincidence_kwargs,
                               print_resources)
from ..engines.registry import ENGINES as ENGINE_TRAITS

__all__ = ["register"]


def _network_from_args(args, clock_default=None):
    from ...hdl.network import SWEEP_EXTRA, ConfigError, NetworkConfig
    from ..izhikevich.cli import parse_param_set
    det = coincidence_kwargs(args)
    det.pop("update_hz")
    clock = det.pop("clock_hz", None)
    if clock is None:
        if clock_default is not None:
            clock = clock_default
        else:
            from ...hdl.coincidence.config import CYCLES_PER_TARGET_EXTRA
            need = max(args.afferents + SWEEP_EXTRA, det["n_targets"] *
                       (det["n_sources"] + CYCLES_PER_TARGET_EXTRA) + 2) + 2
            clock = args.update_hz * max(need, 64)
    kw = {"n_afferents": args.afferents, "detector": det, "first_source": args.first_source,
          "clock_hz": clock, "update_hz": args.update_hz}
    if args.afferent_param_set:
        kw["afferent_param_sets"] = tuple(parse_param_set(x).to_dict()
                                          for x in args.afferent_param_set)
        kw["afferent_sets"] = [i % len(args.afferent_param_set) for i in range(args.afferents)]
    kw["tick_source"] = getattr(args, "tick_source", None) or "external"   # engines: external
    try:
        return NetworkConfig(**kw)
    except ConfigError as exc:
        raise CliError(f"cuneate: {exc}") from None


def cmd_simulate_network(args) -> int:
    from .engines import run_network
    cfg = _network_from_args(args)
    n_ticks = int(round(args.duration_ms / cfg.dt_ms))
    if n_ticks < 1:
        raise CliError(f"--duration-ms {args.duration_ms:g} is shorter than one tick "
                       f"(dt = {cfg.dt_ms:g} ms)")
    hdl = ENGINE_TRAITS[args.engine].hdl
    refuse_long_run("cuneate simulate network", "network", args.engine,
                    n_ticks * (cfg.cycles_needed if hdl else cfg.n_afferents), args.max_minutes,
                    f"{n_ticks} ticks")
    N = cfg.n_afferents
    cur = list(args.current)
    if len(cur) not in (1, N):
        raise CliError(f"--current takes one value or one per afferent ({N}), got {len(cur)}")
    cur = cur * N if len(cur) == 1 else cur
    if args.engine != "golden":
        for x in cur:
            if not cfg.core.i_lo <= x <= cfg.core.i_hi:
                raise CliError(f"cuneate simulate network: current {x:g} is outside the core's "
                               f"accepted range [{cfg.core.i_lo:g}, {cfg.core.i_hi:g}] mV/ms")
    build_dir = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    try:
        run = run_network(args.engine, cfg, np.tile(cur, (n_ticks, 1)), build_dir=build_dir)
    except ValueError as exc:
        raise CliError(f"cuneate simulate network: {exc}") from None
    spikes = [[float(t) for t in s] for s in run.afferent_ms + run.cuneate_ms]
    out = {"engine": args.engine, "model": "network", "dt_ms": cfg.dt_ms, "scheme": "euler",
           "duration_ms": n_ticks * cfg.dt_ms, "neurons": N + cfg.n_targets,
           "populations": [{"name": "afferent", "first": 0, "count": N},
                           {"name": "cuneate", "first": N, "count": cfg.n_targets}],
           "first_source": cfg.first_source, "sources": cfg.n_sources,
           "delays_ms": (cfg.det.delays * cfg.dt_ms).tolist(),
           "weights": cfg.det.weights_real.tolist(), "current": cur, "spikes_ms": spikes,
           "latency": cfg.latency()["text"], "counters": run.counters}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"afferent -> cuneate network on {args.engine}: {N} afferents (sources "
              f"{cfg.first_source} .. {cfg.first_source + cfg.n_sources - 1}) -> "
              f"{cfg.n_targets} cuneate neurons, dt = {cfg.dt_ms:g} ms, "
              f"{n_ticks * cfg.dt_ms:g} ms")
        for j, s in enumerate(spikes):
            name = f"afferent {j}" if j < N else f"cuneate {j - N}"
            head = ", ".join(f"{x:g}" for x in s[:6]) + (" ..." if len(s) > 6 else "")
            print(f"  {name}: {len(s)} spikes: {head}")
    return 0


def cmd_generate_network(args) -> int:
    from ...hdl.network import generate_network, synth_resources
    cfg = _network_from_args(args, clock_default=40e6)
    files = generate_network(output_dir(args.out), cfg, name=args.name)
    for f in files:
        print(f)
    print_resources(args, cfg, files[1], synth_resources)
    print(f"afferent -> cuneate network: {cfg.n_afferents} afferents, {cfg.n_sources} sources "
          f"-> {cfg.n_targets} cuneate neurons, {cfg.clock_hz / 1e6:g} MHz, "
          f"{cfg.cycles_needed} of {cfg.cycles_per_tick} cycles per tick; latency: "
          f"{cfg.latency()['text']}")
    return 0


def _add_network_options(p) -> None:
    add_coincidence_options(p)
    g = p.add_argument_group("afferents")
    g.add_argument("--afferents", type=positive_int, default=8,
                   help="afferent neurons on the core (default 8)")
    g.add_argument("--first-source", type=nonneg_int, default=0,
                   help="detector source s is afferent first_source + s (default 0)")
    g.add_argument("--afferent-param-set", action="append", default=None, metavar="SPEC",
                   help="parameter set of the afferents (repeatable, assigned round robin; "
                        "default RS)")


def register(groups: CommandGroups) -> None:
    sn = groups.simulate.add_parser("network", help="the afferent -> cuneate network")
    sn.add_argument("--engine", choices=engine_choices("network"), default="golden")
    sn.add_argument("--current", type=finite_float, nargs="+", default=[20.0],
                    help="afferent currents (mV/ms): one value or one per afferent")
    sn.add_argument("--duration-ms", type=positive_float, default=100.0)
    sn.add_argument("--build-dir", default=None, help="HDL simulator build directory")
    sn.add_argument("--max-minutes", type=positive_float, default=10.0,
                    help="refuse runs estimated to take longer (default 10)")
    sn.add_argument("--json", action="store_true")
    _add_network_options(sn)
    sn.set_defaults(func=cmd_simulate_network)

    gn = groups.generate.add_parser("network", help="the afferent -> cuneate network")
    _add_network_options(gn)
    gn.add_argument("--tick-source", choices=("internal", "external"), default="internal")
    gn.add_argument("--name", default="afferent_cuneate_network", help="Verilog module name")
    add_resources_option(gn, 15)
    gn.add_argument("--out", required=True)
    gn.set_defaults(func=cmd_generate_network)

