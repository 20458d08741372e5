"""``cuneate demo``: the same job as ``make demo`` (``cuneate run --out out/demo``, the default
scene and its report); ``--summary`` generates the hardware and summarizes the models."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ...golden.izhikevich import PRESETS, simulate
from ...hdl.izhikevich import IzhikevichConfig, IzhikevichTwin
from ..engines.waves import DEFAULT_TICKS
from .options import CommandGroups, add_quiet_option, output_dir
from .run import cmd_run

__all__ = ["run_demo", "register"]


def golden_summary() -> list[str]:
    from ...golden.metrics import isi_stats
    lines = ["golden Izhikevich (forward Euler, dt = 1/16 ms, 1 s per neuron):",
             f"  {'preset':6s} {'I':>6s} {'spikes':>7s} {'mean ISI ms':>12s} {'CV':>6s}"]
    presets = list(PRESETS)
    currents = [4.0, 10.0, 30.0]
    names = [(p, i) for p in presets for i in currents]
    t0 = time.perf_counter()
    res = simulate([p for p, _ in names], lambda t: np.array([i for _, i in names]),
                   duration_ms=1000.0)
    elapsed = time.perf_counter() - t0
    for (p, i), s in zip(names, res.spikes_ms):
        st = isi_stats(s)
        mean = f"{st['mean_isi_ms']:.2f}" if st["mean_isi_ms"] is not None else "-"
        cv = f"{st['cv_isi']:.3f}" if st["cv_isi"] is not None else "-"
        lines.append(f"  {p:6s} {i:6.1f} {len(s):7d} {mean:>12s} {cv:>6s}")
    lines.append(f"  ({len(names)} neurons x 16000 updates in {elapsed:.2f} s)")
    return lines


def run_demo(out: Path) -> int:
    out.mkdir(parents=True, exist_ok=True)
    try:
        from ...hdl.izhikevich import generate_izhikevich
    except ImportError:
        generate_izhikevich = None
    if generate_izhikevich is not None:
        files = generate_izhikevich(out)
        print("generated hardware:")
        for f in files:
            print(f"  {f}")
        for line in core_summary():
            print(line)
    for line in golden_summary():
        print(line)
    return 0


def core_summary() -> list[str]:
    from ...golden.metrics import compare_trains
    cfg = IzhikevichConfig()
    d = cfg.to_dict()
    f = d["formats"]
    lines = [f"IzhikevichCore: {cfg.n_neurons} neurons, {cfg.clock_hz / 1e6:g} MHz, "
             f"{cfg.update_hz / 1e3:g} kHz per neuron (dt = {cfg.dt_ms:g} ms), "
             f"{d['pipeline_depth']}-stage pipeline, {d['multipliers']} multipliers "
             f"{cfg.operand_width}x{cfg.operand_width}",
             f"  formats: v {f['V']['format']}, u {f['U']['format']}, I {f['I']['format']}, "
             f"operands w {f['W']['format']}, q {f['Q']['format']}, y {f['Y']['format']}",
             "  worst constant error: " + max(
                 ((f"{k} {abs(c['rel_error']):.2e}", abs(c["rel_error"]))
                  for k, c in d["constants"].items()), key=lambda x: x[1])[0]]
    small = IzhikevichConfig(n_neurons=8, clock_hz=16e3 * 8, tick_source="external")
    t0 = time.perf_counter()
    fixed = IzhikevichTwin(small).run(10.0, 16000)[0]
    tf = time.perf_counter() - t0
    g = simulate("RS", 10.0, duration_ms=1000.0).spikes_ms[0]
    c = compare_trains(g, fixed, cfg.dt_ms, q_per_ms=0.005)
    lines.append(f"  fixed point vs float64 golden, RS, I = 10, 1 s: {c['n_b']} vs {c['n_a']} "
                 f"spikes, {100 * c['fraction_within_tick']:.1f} % within +-1 tick, "
                 f"max |dt| {c['max_abs_error_ms']:g} ms, VP(q = 5/s) {c['vp_distance']:.4f} "
                 f"(twin {tf:.2f} s)")
    return lines


def cmd_demo(args) -> int:
    """``cuneate demo``: what ``make demo`` runs (the default scene into ``--out``); with
    ``--summary`` the hardware's files and a golden-model summary instead."""
    if args.summary:
        return run_demo(output_dir(args.out))

    return cmd_run(argparse.Namespace(
        scene=None, out=args.out, engines=None, list_examples=False, json=False, waves=None,
        waves_start=0, waves_ticks=DEFAULT_TICKS, quiet=getattr(args, "quiet", False),
        verbose=False))


def register(groups: CommandGroups) -> None:
    dm = groups.root.add_parser("demo", help="what make demo runs: the default scene (the "
                                             "four-material grasp) and its report")
    dm.add_argument("--out", default="out/demo", help="report directory")
    dm.add_argument("--summary", action="store_true",
                    help="instead: generate the hardware and print a golden-model summary")
    add_quiet_option(dm)
    dm.set_defaults(func=cmd_demo)
