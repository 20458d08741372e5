"""``cuneate sweep``: what accuracy costs, over each block's knobs (update rate, operand width,
fraction bits, rounding, the golden model's scheme; see :mod:`cuneate.sim.sweep`)."""

from __future__ import annotations

import math

from ...golden import budget
from ..izhikevich.cli import add_pipeline_option
from .options import (CliError, CommandGroups, add_max_minutes, add_quiet_option, claim_output,
                      output_dir, positive_float, positive_int, start_progress)

__all__ = ["register", "cmd_sweep"]


def _list(text: str, conv, what: str) -> list:
    try:
        out = [conv(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CliError(f"{what}: expected a comma-separated list, got {text!r}") from None
    if not out:
        raise CliError(f"{what}: empty list")
    for x in out:
        if isinstance(x, float) and not math.isfinite(x):
            raise CliError(f"{what}: not a finite number: {x!r} (in {text!r})")
    return out


def cmd_sweep(args) -> int:
    from .. import progress
    from ..sweep import SweepSpec, battery_module, estimate_sweep, run_sweep, write_sweep
    try:
        block = battery_module(args.battery)
        duration = args.duration_ms or block.default_duration_ms(args.battery) or 1000.0
    except ValueError as exc:
        raise CliError(f"--battery: {exc}") from None
    rates = _list(args.update_hz, float, "--update-hz")
    if any(r <= 0 for r in rates):
        raise CliError("--update-hz: rates must be > 0")
    widths = _list(args.operand_width, int, "--operand-width")
    if any(not 8 <= w <= 32 for w in widths):
        raise CliError("--operand-width: widths must lie in 8..32")
    rnd = _list(args.rounding, str, "--rounding")
    if set(rnd) - {"nearest", "truncate"}:
        raise CliError("--rounding: nearest and/or truncate")
    floats = [] if args.no_float else ["float64", "float32"]
    seeds = _list(args.seeds, int, "--seeds")
    if any(s < 1 for s in seeds):
        raise CliError("--seeds: placement seeds must be >= 1")
    if args.pack_registers and not args.fmax:
        raise CliError("--pack-registers: packs the netlist that --fmax places and routes; "
                       "add --fmax")
    spec = SweepSpec(battery=args.battery, duration_ms=duration,
                     reference_hz=args.reference_hz, clock_hz=args.clock_hz, synth=args.synth,
                     fmax=args.fmax, pipeline_stages=args.pipeline_stages, seeds=tuple(seeds),
                     pack_registers=args.pack_registers)
    try:
        pts, columns = block.points_from_args(args, rates, widths, rnd, floats, _list)
    except ValueError as exc:
        raise CliError(f"cuneate sweep: {exc}") from None
    if args.reference_hz < max(p.update_hz for p in pts):
        raise CliError(f"--reference-hz {args.reference_hz:g} is coarser than the point at "
                       f"{max(p.update_hz for p in pts):g} Hz: the reference must be at least "
                       f"as fine as every point")
    try:
        est = estimate_sweep(pts, spec, 1 if args.scheduler == "sync" else args.workers)
        budget.check(est["what"], est["bytes"], est["seconds"],
                     "shorten --duration-ms, lower --reference-hz or sweep fewer points")
    except ValueError as exc:
        raise CliError(f"cuneate sweep: {exc}") from None
    izhikevich = block.__name__.endswith(".izhikevich.sweep")
    out = output_dir(args.out)
    start_progress(args)
    with claim_output(out, "cuneate sweep"):
        try:
            rows = run_sweep(pts, spec, out / "cache", scheduler=args.scheduler,
                             workers=args.workers, repeats=args.repeat,
                             scheduler_timeout_s=args.scheduler_timeout_s)
        except ValueError as exc:
            raise CliError(f"cuneate sweep: {exc}") from None
        with progress.step("writing the sweep report"):
            page = write_sweep(rows, spec, out, columns)
    print(f"error against the reference (spike-count error, mean VP at q = 5/s); within one tick "
          f"of {'Euler' if izhikevich else 'float64'} at the same dt; costs")
    for r in rows:
        ve = r.get("vs_euler_fraction_within_tick", r.get("vs_float64_fraction_within_tick"))
        if r.get("status") != "ok":
            print(f"  {r['label']:44s} {r.get('reason', '')[:70]}")
            continue
        costs = ", ".join(f"{v} {k}" for k, v in (
            ("neurons/core", r.get("neurons_per_core")), ("mult", r.get("multipliers")),
            ("state bits", r.get("state_bits"))) if v is not None)
        host = r.get("host_s_per_bio_s")
        print(f"  {r['label']:44s} count error {r.get('count_error')}, VP "
              f"{r.get('mean_vp', 0):.3f}"
              + (f", same-dt {ve:.4f}" if ve is not None else "")
              + (f"; {costs}" if costs else "")
              + (f"; fmax {r['fmax_mhz']:.1f} MHz" if r.get("fmax_mhz") else "")
              + (f"; host {host:.2f} s/bio s"
                 + (" (parallel)" if str(r.get("host_time", "")).startswith("alongside")
                    else "") if host else ""))
    print(f"report: {page}")
    return 0


#: the sweep's axes, each a comma-separated list of values: option, default, help
AXES = (
    ("--update-hz", "16000",
     "comma-separated update rates (e.g. 4000,8000,16000,20000,32000,64000)"),
    ("--operand-width", "18", "comma-separated (e.g. 16,18,20,25)"),
    ("--frac-bits", "18:20", "comma-separated V:U state fraction bits (e.g. 16:18,18:20,20:22)"),
    ("--current-frac-bits", "",
     "comma-separated fraction bits of the core's current format (default: the battery's, "
     "sQ10.8 unless a scene says otherwise; e.g. 8,10,12)"),
    ("--rounding", "nearest", "nearest,truncate"),
    ("--v-frac-bits", "16", "LIF: comma-separated state fraction bits (e.g. 8,12,16,20)"),
    ("--weight-bits", None,
     "LIF / coincidence: comma-separated weight widths (default 8 / 12; e.g. 2,4,6,8,10,12,16)"),
    ("--decay", "multiply",
     "LIF: multiply and/or shift (no multiplier; only where 1-exp(-dt/tau) is a power of two "
     "within --max-decay-error, e.g. lif-pow2)"),
    ("--max-decay-error", "0.01",
     "LIF: comma-separated largest accepted relative error of the decay"),
    ("--trace-frac-bits", "16",
     "coincidence: comma-separated PSP trace fraction bits (e.g. 8,12,16)"),
    ("--schemes", "euler", "golden schemes: euler,izhikevich,rk4"),
)


def register(groups: CommandGroups) -> None:
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
    for flag, default, text in AXES:
        p.add_argument(flag, default=default, help=text)
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
    p.add_argument("--seeds", default="1",
                   help="with --fmax: comma-separated nextpnr placement seeds; the lowest fmax "
                        "is reported (e.g. 1,2,3)")
    p.add_argument("--pack-registers", action="store_true",
                   help="with --fmax: move the flip-flops around each multiplier and after "
                        "each block RAM into the MULT18X18D's input/output and the DP16KD's "
                        "output registers before place and route")
    add_pipeline_option(p)
    p.add_argument("--scheduler", default=None,
                   help="dask.distributed address; 'sync' runs in this process (default: a "
                        "local cluster)")
    p.add_argument("--workers", type=positive_int, default=2,
                   help="local cluster processes (host seconds of points run in parallel are "
                        "marked: not comparable between runs; --workers 1 or --scheduler sync "
                        "for comparable ones)")
    p.add_argument("--repeat", type=positive_int, default=1, metavar="N",
                   help="run each point N times and keep the fastest host time (with "
                        "--scheduler sync: the host cost measured in isolation)")
    add_quiet_option(p)
    p.add_argument("--scheduler-timeout-s", type=positive_float, default=10.0,
                   help="how long to wait for --scheduler to answer")
    add_max_minutes(p, 60.0)
    p.set_defaults(func=cmd_sweep)
