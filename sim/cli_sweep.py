"""``cuneate sweep``: what accuracy costs, over update rate, operand width, state fraction bits,
rounding and the golden model's scheme (see :mod:`cuneate.sim.sweep`);
``cuneate hardcases summary``: the hard-case suite's record (:mod:`cuneate.sim.hardcases`); and
``cuneate prove``: SymbiYosys checks of the one-update datapath (:mod:`cuneate.hdl.izhikevich.formal`)."""

from __future__ import annotations

import sys
from pathlib import Path

from .cliutil import CliError, output_dir, positive_float, positive_int

__all__ = ["register", "cmd_sweep"]


def _list(text: str, conv, what: str) -> list:
    try:
        out = [conv(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CliError(f"{what}: expected a comma-separated list, got {text!r}") from None
    if not out:
        raise CliError(f"{what}: empty list")
    return out


def _frac(text: str) -> tuple[int, int]:
    v, _, u = text.partition(":")
    return int(v), int(u or v)


def _block_points(args, rates, widths, rnd, floats):
    """The points of a LIF or coincidence-detector battery, and the report's columns."""
    from .sweep_cuneate import CUNEATE_BATTERIES, CUNEATE_COLUMNS, coincidence_grid
    from .sweep_lif import LIF_BATTERIES, LIF_COLUMNS, lif_battery, lif_grid
    wbits = _list(args.weight_bits, int, "--weight-bits") if args.weight_bits else None
    try:
        if args.battery in LIF_BATTERIES:
            decay = _list(args.decay, str, "--decay")
            return lif_grid(rates, lif_battery(args.battery).form,
                            _list(args.v_frac_bits, int, "--v-frac-bits"), widths,
                            wbits or [8], decay, rnd, floats,
                            _list(args.max_decay_error, float, "--max-decay-error")), \
                LIF_COLUMNS
        if args.battery in CUNEATE_BATTERIES:
            return coincidence_grid(rates, wbits or [12],
                                    _list(args.trace_frac_bits, int, "--trace-frac-bits"),
                                    widths, rnd, floats), CUNEATE_COLUMNS
    except ValueError as exc:
        raise CliError(f"cuneate sweep: {exc}") from None
    return None, None


def cmd_sweep(args) -> int:
    from .sweep import SweepSpec, battery, grid, run_sweep, write_sweep
    from .sweep_cuneate import CUNEATE_BATTERIES
    from .sweep_lif import LIF_BATTERIES
    block = args.battery in LIF_BATTERIES or args.battery in CUNEATE_BATTERIES
    bat = None
    if not block:
        try:
            bat = battery(args.battery)
        except ValueError as exc:
            raise CliError(f"--battery: {exc}; LIF: {', '.join(LIF_BATTERIES)}; coincidence: "
                           f"{', '.join(CUNEATE_BATTERIES)}") from None
    duration = args.duration_ms or (bat and bat.duration_ms) or 1000.0
    rates = _list(args.update_hz, float, "--update-hz")
    if any(r <= 0 for r in rates):
        raise CliError("--update-hz: rates must be > 0")
    widths = _list(args.operand_width, int, "--operand-width")
    if any(not 8 <= w <= 32 for w in widths):
        raise CliError("--operand-width: widths must lie in 8..32")
    fracs = _list(args.frac_bits, _frac, "--frac-bits")
    cfb = (_list(args.current_frac_bits, int, "--current-frac-bits")
           if args.current_frac_bits else [None])
    if any(c is not None and not 0 <= c <= 24 for c in cfb):
        raise CliError("--current-frac-bits: fraction bits must lie in 0..24")
    rnd = _list(args.rounding, str, "--rounding")
    if set(rnd) - {"nearest", "truncate"}:
        raise CliError("--rounding: nearest and/or truncate")
    schemes = _list(args.schemes, str, "--schemes")
    if set(schemes) - {"euler", "izhikevich", "rk4"}:
        raise CliError("--schemes: euler, izhikevich and/or rk4")
    floats = [] if args.no_float else ["float64", "float32"]
    spec = SweepSpec(battery=args.battery, duration_ms=duration,
                     reference_hz=args.reference_hz, clock_hz=args.clock_hz, synth=args.synth,
                     fmax=args.fmax)
    pts, columns = _block_points(args, rates, widths, rnd, floats) if block else \
        (grid(rates, widths, fracs, rnd, schemes, floats, cfb), None)
    out = output_dir(args.out)
    rows = run_sweep(pts, spec, out / "cache", scheduler=args.scheduler, workers=args.workers,
                     progress=sys.stderr.isatty(), log=lambda m: print(m, file=sys.stderr))
    page = write_sweep(rows, spec, out, columns)
    for r in rows:
        acc = r.get("fraction_within_tick")
        ve = r.get("vs_euler_fraction_within_tick", r.get("vs_float64_fraction_within_tick"))
        print(f"  {r['label']:44s} "
              + (f"within 1 tick {acc:.4f}" if acc is not None else r.get("reason", "")[:70])
              + (f", of {'float64' if block else 'Euler'} at its dt {ve:.4f}"
                 if ve is not None else "")
              + (f", {r['host_s_per_bio_s']:.2f} s/bio s" if r.get("host_s_per_bio_s")
                 else "")
              + (f", fmax {r['fmax_mhz']:.1f} MHz" if r.get("fmax_mhz") else ""))
    print(f"report: {page}")
    return 0


def cmd_hardcases(args) -> int:
    from .hardcases import format_summary, summary
    try:
        rows = summary(args.dir)
    except FileNotFoundError as exc:
        raise CliError(f"cuneate hardcases: {exc}") from None
    print(format_summary(rows))
    return 1 if any(r["mismatches"] for r in rows) else 0


def cmd_prove(args) -> int:
    import json
    import tempfile
    from ..hdl.izhikevich.formal import FormalError, prove
    from ..hdl.izhikevich import ConfigError, IzhikevichConfig
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
                      timeout_s=args.timeout_s)
        except FormalError as exc:
            raise CliError(f"cuneate prove: {exc}") from None
    r |= {"param_sets": list(args.preset), "update_hz": args.update_hz,
          "operand_width": args.operand_width, "rounding": args.rounding}
    if args.json:
        print(json.dumps(r))
    else:
        what = {"datapath": "no narrowing of the datapath wraps and the y clamp never acts",
                "state_box": "one update keeps every state of the box in the box, no clamp"}
        print(f"{r['property']}: {what[r['property']]} - {r['status'].upper()} "
              f"({r['seconds']:.1f} s)")
        if r["counterexample"]:
            c = r["counterexample"]
            print(f"  counterexample: v = {cfg.V.to_float(c['v']):.6g} mV, "
                  f"u = {cfg.U.to_float(c['u']):.6g}, I = {cfg.I.to_float(c['I']):.6g} mV/ms, "
                  f"set {c.get('sel', 0)}")
    return 0 if r["status"] == "pass" else 1


def register(groups) -> None:
    f = groups.root.add_parser("prove", help="SymbiYosys checks of the one-update datapath")
    f.add_argument("--preset", action="append", default=None,
                   help="parameter set(s) (repeat for a mix; default RS)")
    f.add_argument("--property", choices=("datapath", "state_box"), default="datapath")
    f.add_argument("--update-hz", type=positive_float, default=16e3)
    f.add_argument("--operand-width", type=positive_int, default=18)
    f.add_argument("--rounding", choices=("nearest", "truncate"), default="nearest")
    f.add_argument("--timeout-s", type=positive_float, default=1800.0)
    f.add_argument("--work-dir", default=None, help="keep the SymbiYosys files here")
    f.add_argument("--json", action="store_true")
    f.set_defaults(func=cmd_prove, preset=None)
    h = groups.root.add_parser("hardcases", help="the hard-case suite's record")
    hs = h.add_subparsers(dest="hardcases_command", required=True, parser_class=type(h))
    s = hs.add_parser("summary", help="cases tried, updates checked and mismatches per case")
    s.add_argument("--dir", default=None, help="records (default build/hardcases)")
    s.set_defaults(func=cmd_hardcases)
    p = groups.root.add_parser("sweep", help="accuracy against cost over the core's knobs")
    p.add_argument("--out", default="out/sweep", help="output directory (cache inside)")
    p.add_argument("--battery", default="yardstick",
                   help="yardstick (16 trains), wide (60), long (48, use --duration-ms), "
                        "behaviours (19 published panels with their stimuli; e.g. "
                        "--duration-ms 300), scene (the default scene's neurons and front-end "
                        "currents), scene:NAME (an example) or scene:PATH (a scene file); LIF: "
                        "lif-currents (24 continuous trains), lif-pow2 (tau_m 8/16/32 ms: decay "
                        "by shift possible), lif-inputs (32 discrete neurons x 64 random "
                        "weights); coincidence detector: cuneate-afferents")
    p.add_argument("--duration-ms", type=positive_float, default=None,
                   help="biological time (default: a scene's length, else 1000)")
    p.add_argument("--update-hz", default="16000",
                   help="comma-separated update rates (e.g. 4000,8000,16000,20000,32000,64000)")
    p.add_argument("--operand-width", default="18", help="comma-separated (e.g. 16,18,20,25)")
    p.add_argument("--frac-bits", default="18:20",
                   help="comma-separated V:U state fraction bits (e.g. 16:18,18:20,20:22)")
    p.add_argument("--current-frac-bits", default="",
                   help="comma-separated fraction bits of the core's current format (default: "
                        "the battery's, sQ10.8 unless a scene says otherwise; e.g. 8,10,12)")
    p.add_argument("--rounding", default="nearest", help="nearest,truncate")
    p.add_argument("--v-frac-bits", default="16",
                   help="LIF: comma-separated state fraction bits (e.g. 8,12,16,20)")
    p.add_argument("--weight-bits", default=None,
                   help="LIF / coincidence: comma-separated weight widths (default 8 / 12; "
                        "e.g. 2,4,6,8,10,12,16)")
    p.add_argument("--decay", default="multiply",
                   help="LIF: multiply and/or shift (no multiplier; only where 1-exp(-dt/tau) "
                        "is a power of two within --max-decay-error, e.g. lif-pow2)")
    p.add_argument("--max-decay-error", default="0.01",
                   help="LIF: comma-separated largest accepted relative error of the decay")
    p.add_argument("--trace-frac-bits", default="16",
                   help="coincidence: comma-separated PSP trace fraction bits (e.g. 8,12,16)")
    p.add_argument("--schemes", default="euler", help="golden schemes: euler,izhikevich,rk4")
    p.add_argument("--no-float", action="store_true", help="skip the float64/float32 points")
    p.add_argument("--reference-hz", type=positive_float, default=256e3,
                   help="rate of the float64 RK4 reference (default 256e3)")
    p.add_argument("--clock-hz", type=positive_float, default=40e6,
                   help="clock for neurons per core (default 40e6)")
    p.add_argument("--synth", action="store_true",
                   help="yosys synth_ecp5 per fixed point (slow: a core per point)")
    p.add_argument("--fmax", action="store_true",
                   help="also nextpnr-ecp5 place and route per fixed point for its fmax on the "
                        "ULX3S's LFE5U-85F (implies --synth; ~35 s a point)")
    p.add_argument("--scheduler", default=None,
                   help="dask.distributed address; 'sync' runs in this process (default: a "
                        "local cluster)")
    p.add_argument("--workers", type=positive_int, default=2)
    p.set_defaults(func=cmd_sweep)
