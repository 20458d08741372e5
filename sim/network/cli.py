"""``cuneate simulate network`` and ``cuneate generate network``: the on-chip afferent ->
cuneate network (:mod:`cuneate.hdl.network`), with the coincidence detector's options plus
``--afferents``, ``--first-source`` and the afferents' currents."""

from __future__ import annotations

import numpy as np

from ...hdl.network import SWEEP_EXTRA, NetworkConfig, generate_network, synth_resources
from ..cli.options import (CliError, CommandGroups, add_block_commands, build_config,
                           finite_float, generate_faced, nonneg_int, output_dir, positive_int,
                           print_run, run_ticks)
from ..coincidence.cli import add_coincidence_options, coincidence_kwargs, print_resources
from ..izhikevich.cli import parse_param_set

__all__ = ["register"]


def _network_from_args(args, clock_default=None):
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
    return build_config(NetworkConfig, kw)


def cmd_simulate_network(args) -> int:
    from .engines import run_network
    cfg = _network_from_args(args)
    n_ticks = run_ticks("cuneate simulate network", "network", args, cfg.dt_ms,
                        cfg.cycles_needed, cfg.n_afferents)
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
    spikes = [[float(t) for t in s] for s in run.population("afferent") + run.population("cuneate")]
    out = {"engine": args.engine, "model": "network", "dt_ms": cfg.dt_ms, "scheme": "euler",
           "duration_ms": n_ticks * cfg.dt_ms, "neurons": N + cfg.n_targets,
           "populations": [{"name": "afferent", "first": 0, "count": N},
                           {"name": "cuneate", "first": N, "count": cfg.n_targets}],
           "first_source": cfg.first_source, "sources": cfg.n_sources,
           "delays_ms": (cfg.det.delays * cfg.dt_ms).tolist(),
           "weights": cfg.det.weights_real.tolist(), "current": cur, "spikes_ms": spikes,
           "latency": cfg.latency()["text"], "counters": run.counters}
    print_run(args, out, f"afferent -> cuneate network on {args.engine}: {N} afferents "
                         f"(sources {cfg.first_source} .. "
                         f"{cfg.first_source + cfg.n_sources - 1}) -> {cfg.n_targets} cuneate "
                         f"neurons, dt = {cfg.dt_ms:g} ms, {n_ticks * cfg.dt_ms:g} ms",
              [(f"afferent {j}" if j < N else f"cuneate {j - N}", s)
               for j, s in enumerate(spikes)])
    return 0


def cmd_generate_network(args) -> int:
    cfg = _network_from_args(args, clock_default=40e6)
    if args.face != "none":
        return generate_faced(args, cfg, "network")
    print_resources(args, cfg, generate_network(output_dir(args.out), cfg, name=args.name),
                    synth_resources)
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
    sn, _ = add_block_commands(groups, "network", "the afferent -> cuneate network", 100.0,
                               _add_network_options, cmd_simulate_network,
                               cmd_generate_network, "afferent_cuneate_network", 15,
                               faces=True)
    sn.add_argument("--current", type=finite_float, nargs="+", default=[20.0],
                    help="afferent currents (mV/ms): one value or one per afferent")

