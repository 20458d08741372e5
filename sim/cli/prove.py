"""``cuneate prove``: SymbiYosys checks of the Izhikevich datapath
(:mod:`cuneate.hdl.izhikevich.formal`); ``cuneate prove core|lif``: the pipelined Izhikevich or
LIF core against its one-step datapath (:mod:`cuneate.hdl.izhikevich.formal_core`,
:mod:`cuneate.hdl.lif.formal_core`); ``cuneate prove coincidence``: the coincidence detector
against its one-tick reference (:mod:`cuneate.hdl.coincidence.formal_core`); ``cuneate prove
banked``: a memory in banks of block RAM against its per-cycle contract
(:mod:`cuneate.hdl.lib.banked_proof`); k-induction with ``--unbounded``; ``cuneate prove
fanout``: the channel fan-out's one-entry datapath against its specification for every gain and
sample (:mod:`cuneate.hdl.fanout.formal`); ``cuneate prove faces`` (or one of its targets
``axi-stream-out``, ``axi-stream-in``, ``axi-lite``, ``wishbone``): the bus faces' protocols
(:mod:`cuneate.hdl.axi.formal`, :mod:`cuneate.hdl.wishbone.formal`); ``cuneate prove
plasticity``: the learning stage against its one-operation specification
(:mod:`cuneate.hdl.plasticity.formal_core`)."""

from __future__ import annotations

import contextlib
import json
import tempfile
from pathlib import Path

from ...hdl.axi.formal import MUTANTS as AXI_MUTANTS
from ...hdl.axi.formal import prove_face
from ...hdl.coincidence import CoincidenceConfig
from ...hdl.coincidence.formal_core import MUTANTS as DETECTOR_MUTANTS
from ...hdl.coincidence.formal_core import (coincidence_proof_config, prove_coincidence,
                                             prove_history_slot)
from ...hdl.fanout.formal import MUTANTS as FANOUT_MUTANTS
from ...hdl.fanout.formal import prove_fanout
from ...hdl.flow.sby import SOLVER, SOLVERS, FormalError, reporting
from ...hdl.izhikevich import ConfigError, IzhikevichConfig
from ...hdl.izhikevich.config import PIPELINE_STAGES
from ...hdl.lib.banked_proof import MUTANTS as BANK_MUTANTS
from ...hdl.lib.banked_proof import prove_banked
from ...hdl.lib.core_proof import MUTANTS
from ...hdl.lif import LifConfig
from ...hdl.link.config import link_config
from ...hdl.link.formal_core import MUTANTS as LINK_MUTANTS
from ...hdl.link.formal_core import decoder_proof_config, prove_decoder
from ...hdl.plasticity.formal_core import MUTANTS as STAGE_MUTANTS
from ...hdl.plasticity.formal_core import prove_stage, stage_proof_config
from ...hdl.wishbone.formal import PROOFS as WB_PROOFS
from .. import progress
from .options import (CliError, CommandGroups, add_quiet_option, positive_float, positive_int,
                      start_progress)

__all__ = ["register", "cmd_prove"]

#: the bus faces' mutants (cuneate prove faces)
FACE_MUTANTS = tuple(AXI_MUTANTS) + tuple(v[3] for v in WB_PROOFS.values())


def _proof_target(args):
    """The configuration and the prove function of ``args.target`` (core, lif, coincidence,
    link)."""
    from ...hdl.izhikevich.formal_core import proof_config, prove_core
    from ...hdl.lif.formal_core import lif_proof_config, prove_lif
    configure, default, prove = {
        "core": (proof_config, IzhikevichConfig, prove_core),
        "lif": (lif_proof_config, LifConfig, prove_lif),
        "coincidence": (coincidence_proof_config, CoincidenceConfig, prove_coincidence),
        "link": (decoder_proof_config, link_config, prove_decoder),
    }[args.target]
    if args.mutant in FACE_MUTANTS or args.mutant in {v[3] for v in WB_PROOFS.values()}:
        raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is a bus face's "
                       f"(cuneate prove faces)")
    if args.mutant in BANK_MUTANTS:
        raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is the banked "
                       f"memory's (cuneate prove banked)")
    if args.mutant in FANOUT_MUTANTS:
        raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is the fan-out's "
                       f"(cuneate prove fanout)")
    if args.mutant in set(STAGE_MUTANTS) - {"skipped_write"}:
        raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is the learning "
                       f"stage's (cuneate prove plasticity)")
    if args.target == "link":
        if args.mutant and args.mutant not in LINK_MUTANTS:
            raise CliError(f"cuneate prove link: mutant {args.mutant} is not the link's (its "
                           f"mutants: {', '.join(LINK_MUTANTS)})")
    elif args.mutant in LINK_MUTANTS:
        raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is the link's")
    if args.target == "coincidence":
        if args.default_config:
            raise CliError("cuneate prove coincidence: --default-config is not offered (its "
                           "513-tick history is proven by the argument of docs/formal.md, not "
                           "by size); use --targets/--sources")
        if args.neurons or args.mutant in ("stage_off_by_one", "late_host_write",
                                           "tag_off_by_one"):
            raise CliError("cuneate prove coincidence: --neurons and the core's mutants do "
                           "not apply (use --targets, --sources, --history and its mutants "
                           "skipped_write, wrong_slot, stamp_wrong_slot)")
        kw = {k: v for k, v in (("n_targets", args.targets), ("n_sources", args.sources),
                                ("max_delay_ticks", args.history)) if v}
        if kw:
            S, M = kw.get("n_sources", 2), kw.get("n_targets", 2)
            D = kw.get("max_delay_ticks", 3)
            kw.update(delays_ticks=[[(t + s) % D for s in range(S)] for t in range(M)],
                      weights=[[8.0 / (1 + (t + 2 * s) % 4) for s in range(S)]
                               for t in range(M)])
        return coincidence_proof_config(**kw), prove
    if args.mutant in ("wrong_slot", "stamp_wrong_slot"):
        raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is the coincidence "
                       f"detector's")
    kw = {} if args.pipeline_stages is None else {"pipeline_stages": args.pipeline_stages}
    if args.default_config:
        return default(**kw), prove
    return (configure(args.neurons, **kw) if args.neurons else configure(**kw)), prove


def cmd_prove_core(args) -> int:
    """``cuneate prove core|lif|coincidence``: bounded (``--depth``, default the induction
    depth) or, with ``--unbounded``, k-induction; PASS/FAIL with mode, depth, solver and
    time."""
    try:
        cfg, prove = _proof_target(args)
    except ConfigError as exc:
        raise CliError(f"cuneate prove {args.target}: {exc}") from None
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        try:
            r = prove(cfg, Path(args.work_dir) if args.work_dir else Path(d),
                           mode="prove" if args.unbounded else "bmc", depth=args.depth,
                           mutant=args.mutant, timeout_s=args.timeout_s, solver=args.solver)
            slot = ring = None
            if args.target == "coincidence" and not args.mutant:
                # the ring address at the default detector's 513-tick history (the scale
                # argument of docs/formal.md rests on it)
                detector = CoincidenceConfig()
                ring = detector.max_delay_ticks
                slot = prove_history_slot(detector, Path(d) / "history_slot",
                                          args.timeout_s, args.solver)
        except FormalError as exc:
            raise CliError(f"cuneate prove {args.target}: {exc}") from None
    size = ({"n_targets": cfg.n_targets, "n_sources": cfg.n_sources,
             "max_delay_ticks": cfg.max_delay_ticks} if args.target == "coincidence"
            else {"n_neurons": cfg.n_neurons, "current_bytes": cfg.current_bytes,
                  "rx_fifo_depth": cfg.rx_fifo_depth} if args.target == "link"
            else {"n_neurons": cfg.n_neurons, "pipeline_stages": cfg.pipeline_stages}
            if args.target == "core" else {"n_neurons": cfg.n_neurons})
    out = r.to_dict() | size | {"mutant": args.mutant}
    if slot is not None:
        out["history_slot"] = slot.to_dict() | {"max_delay_ticks": ring}
    if args.json:
        print(json.dumps(out))
    else:
        what = "k-induction" if r.mode == "prove" else "bounded from the initial state"
        print(f"{r.property}: {r.status.upper()} ({what}, depth {r.depth}, {r.engine} "
              f"{r.solver}, {r.seconds:.1f} s, "
              + ", ".join(f"{k} = {v}" for k, v in size.items())
              + (f", mutant {args.mutant}" if args.mutant else "") + ")")
        if r.failed:
            print(f"  failed in step {r.step} ({r.phase}): {', '.join(r.failed)}")
        for a in r.abstractions:
            print(f"  abstraction: {a}")
        if slot is not None:
            print(f"{slot.property}: {slot.status.upper()} (every slot and delay of the "
                  f"default {ring}-tick history, {slot.engine} {slot.solver}, "
                  f"{slot.seconds:.1f} s)")
    return 0 if r.passed and (slot is None or slot.passed) else 1


def cmd_prove_banked(args) -> int:
    """``cuneate prove banked``: a memory in banks of block RAM, read a cycle ahead or at the
    fetch, against its per-cycle contract (:mod:`cuneate.hdl.lib.banked_proof`), with the
    write port as the host's (unregistered) and as the write-back's or the deepest core's
    (registered); by default the default core's state memory (2500 words in five banks of
    512)."""
    if args.mutant and args.mutant not in BANK_MUTANTS:
        raise CliError(f"cuneate prove banked: mutant {args.mutant} is not the memory's (its "
                       f"mutants: {', '.join(BANK_MUTANTS)})")
    depth, bank = args.neurons or 2500, args.bank_depth or 512
    if bank & (bank - 1):
        raise CliError(f"cuneate prove banked: --bank-depth must be a power of two, got {bank}")
    records = []
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        for registered in (False, True):
            work = Path(args.work_dir or d) / f"write_register_{int(registered)}"
            try:
                r = prove_banked(work, depth, bank, write_register=registered,
                                 mode="prove" if args.unbounded else "bmc", k=args.depth,
                                 mutant=args.mutant, timeout_s=args.timeout_s)
            except FormalError as exc:
                raise CliError(f"cuneate prove banked: {exc}") from None
            records.append(r.to_dict() | {"words": depth, "bank_depth": bank,
                                          "banks": -(-depth // bank),
                                          "write_register": registered,
                                          "mutant": args.mutant})
    return _report(args, records, lambda rec: (
        f"{rec['seconds']:.1f} s, {rec['words']} words in {rec['banks']} banks of "
        f"{rec['bank_depth']}, write {'registered' if rec['write_register'] else 'direct'}"),
        lambda rec: f" in step {rec['step']} ({rec['phase']})")


def _report(args, records: list, detail, where) -> int:
    """Print proof ``records`` (JSON with ``--json``, else one line each: ``detail(rec)`` after
    the mode and depth, a failure's properties after ``where(rec)``); 0 when every one
    passed."""
    if args.json:
        print(json.dumps(records))
    else:
        for rec in records:
            what = "k-induction" if rec["mode"] == "prove" else "bounded from the start"
            print(f"{rec['property']}: {rec['status'].upper()} ({what}, depth {rec['depth']}, "
                  f"{detail(rec)}" + (f", mutant {args.mutant}" if args.mutant else "") + ")")
            if rec["failed"]:
                print(f"  failed{where(rec)}: {', '.join(rec['failed'])}")
    return 0 if all(rec["status"] == "pass" for rec in records) else 1


def cmd_prove_fanout(args) -> int:
    """``cuneate prove fanout``: :func:`~cuneate.hdl.fanout.formal.prove_fanout` on each of its
    tables (a combinational check: every input at once, so ``--unbounded`` changes nothing);
    one line per table, exit 0 when every one passes."""
    if args.mutant and args.mutant not in FANOUT_MUTANTS:
        raise CliError(f"cuneate prove fanout: mutant {args.mutant} is not the fan-out's (its "
                       f"mutants: {', '.join(FANOUT_MUTANTS)})")
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        try:
            results = prove_fanout(Path(args.work_dir or d), mutant=args.mutant,
                                   timeout_s=args.timeout_s, solver=args.solver)
        except FormalError as exc:
            raise CliError(f"cuneate prove fanout: {exc}") from None
    records = []
    for name, cfg, r in results:
        raw = [c.raw for c in cfg.gains_]
        records.append(r.to_dict() | {
            "table": name, "shift": cfg.shift, "rounding": cfg.rounding,
            "sample_format": str(cfg.S), "current_format": str(cfg.I),
            "gain_raw_range": [min(raw), max(raw)], "gain_frac_bits": cfg.gain_frac,
            "clamp_built": cfg.can_clamp, "mutant": args.mutant})
    if args.json:
        print(json.dumps(records))
    else:
        for rec in records:
            lo, hi = rec["gain_raw_range"]
            print(f"{rec['property']}: {rec['status'].upper()} (every sample {rec['sample_format']}"
                  f" and gain {lo} .. {hi} x 2^{-rec['gain_frac_bits']}, shift {rec['shift']}, "
                  f"{rec['rounding']}, current {rec['current_format']}, clamp "
                  f"{'built' if rec['clamp_built'] else 'not built'}; {rec['solver']}, "
                  f"{rec['seconds']:.1f} s" + (f", mutant {args.mutant}" if args.mutant else "")
                  + ")")
            if rec["failed"]:
                print(f"  failed: {', '.join(rec['failed'])}")
    return 0 if all(rec["status"] == "pass" for rec in records) else 1


#: the bus faces' protocol targets (``faces``: every one)
FACE_TARGETS = ("axi-stream-out", "axi-stream-in", "axi-lite", "wishbone")


def cmd_prove_faces(args) -> int:
    """``cuneate prove faces`` (or one face target): each protocol proof, bounded (``--depth``,
    default the target's k) or by k-induction (``--unbounded``); one line per target, exit 0
    when every one passes. A ``--mutant`` selects the target it belongs to."""
    owners = AXI_MUTANTS | {v[3]: k for k, v in WB_PROOFS.items()}
    targets = FACE_TARGETS if args.target == "faces" else (args.target,)
    if args.mutant:
        if args.mutant not in owners or owners[args.mutant] not in targets:
            raise CliError(f"cuneate prove {args.target}: mutant {args.mutant} is not its "
                           f"(its mutants: {', '.join(m for m, t in owners.items() if t in targets)})")
        targets = (owners[args.mutant],)
    records = []
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        for t in targets:
            try:
                r = prove_face(t, Path(args.work_dir or d) / t,
                               mode="prove" if args.unbounded else "bmc", depth=args.depth,
                               mutant=args.mutant, timeout_s=args.timeout_s,
                               solver=args.solver)
            except FormalError as exc:
                raise CliError(f"cuneate prove {t}: {exc}") from None
            records.append(r.to_dict() | {"target": t, "mutant": args.mutant})
    return _report(args, records, lambda rec: f"{rec['solver']}, {rec['seconds']:.1f} s",
                   lambda rec: "")


def cmd_prove_plasticity(args) -> int:
    """``cuneate prove plasticity``: the learning stage (2 CNs of 2 synapses, any synapse
    tracked) against its one-operation specification, bounded (``--depth``, default the
    induction depth) or, with ``--unbounded``, k-induction; PASS/FAIL as ``prove core``."""
    if args.mutant and args.mutant not in STAGE_MUTANTS:
        raise CliError(f"cuneate prove plasticity: mutant {args.mutant} is not the learning "
                       f"stage's (its mutants: {', '.join(STAGE_MUTANTS)})")
    cfg = stage_proof_config()
    with tempfile.TemporaryDirectory(prefix="cuneate-prove-") as d:
        try:
            r = prove_stage(cfg, Path(args.work_dir) if args.work_dir else Path(d),
                            mode="prove" if args.unbounded else "bmc", depth=args.depth,
                            mutant=args.mutant, timeout_s=args.timeout_s, solver=args.solver)
        except FormalError as exc:
            raise CliError(f"cuneate prove plasticity: {exc}") from None
    size = {"n_targets": cfg.n_targets, "n_synapses": cfg.n_synapses}
    if args.json:
        print(json.dumps(r.to_dict() | size | {"mutant": args.mutant}))
    else:
        what = "k-induction" if r.mode == "prove" else "bounded from the initial state"
        print(f"{r.property}: {r.status.upper()} ({what}, depth {r.depth}, {r.engine} "
              f"{r.solver}, {r.seconds:.1f} s, {cfg.n_targets} CNs x {cfg.n_synapses} "
              f"synapses" + (f", mutant {args.mutant}" if args.mutant else "") + ")")
        if r.failed:
            print(f"  failed in step {r.step} ({r.phase}): {', '.join(r.failed)}")
        for a in r.abstractions:
            print(f"  abstraction: {a}")
    return 0 if r.passed else 1


def cmd_prove(args) -> int:
    """Every ``cuneate prove``: says while it runs what it checks, the phase and step each
    SymbiYosys run has reached and the time (:mod:`cuneate.sim.progress`; ``-q`` silences)."""
    if args.pipeline_stages is not None and args.target != "core":
        raise CliError(f"cuneate prove {args.target}: --pipeline-stages is the Izhikevich "
                       f"core's (cuneate prove core)")
    start_progress(args)
    what = (f"cuneate prove {args.target}" + (f" {args.property}" if args.target ==
                                               "datapath" else "")
            + (" (k-induction)" if getattr(args, "unbounded", False) else ""))
    with contextlib.ExitStack() as stack:
        steps = []

        def note(text):                 # the step opens with the first SymbiYosys run, so a
            if not steps:               # refused argument is still one line on stderr
                steps.append(stack.enter_context(progress.step(what)))
            steps[0].note(text)
        with reporting(note):
            return _cmd_prove(args)


def _cmd_prove(args) -> int:
    if args.target == "faces" or args.target in FACE_TARGETS:
        return cmd_prove_faces(args)
    if args.target in ("core", "lif", "coincidence", "link"):
        return cmd_prove_core(args)
    if args.target == "banked":
        return cmd_prove_banked(args)
    if args.target == "fanout":
        return cmd_prove_fanout(args)
    if args.target == "plasticity":
        return cmd_prove_plasticity(args)
    from ...hdl.izhikevich.formal import prove
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
    f = groups.root.add_parser("prove", help="SymbiYosys checks of the one-update datapath "
                               "and of the pipelined core")
    f.add_argument("target", nargs="?",
                   choices=("datapath", "core", "lif", "coincidence", "link", "banked", "fanout",
                            "faces") + FACE_TARGETS + ("plasticity",),
                   default="datapath",
                   help="datapath (default): one update's range properties; core, lif: the "
                   "pipelined Izhikevich or LIF core equals its one-step datapath; "
                   "coincidence: the detector equals its one-tick reference; link: the host "
                   "link's frame decoder meets the wire format; banked: a memory in banks of "
                   "block RAM meets its per-cycle contract; fanout: the channel fan-out's "
                   "one-entry datapath meets its specification for every gain and sample; "
                   "faces (or axi-stream-out, axi-stream-in, axi-lite, wishbone): the bus "
                   "faces' protocols; plasticity: the learning stage equals its one-operation "
                   "specification")
    f.add_argument("--unbounded", action="store_true",
                   help="core: k-induction (every input sequence of every length)")
    f.add_argument("--depth", type=positive_int, default=None,
                   help="core: steps (default the core's latency + 2)")
    f.add_argument("--neurons", type=positive_int, default=None,
                   help="core: neurons (default the fewest accepted, one per stage); banked: "
                   "the memory's words (default 2500)")
    f.add_argument("--pipeline-stages", type=int, choices=PIPELINE_STAGES, default=None,
                   help="core: the pipeline depth proven (default 5; its smallest core is "
                   "depth + 1 neurons)")
    f.add_argument("--bank-depth", type=positive_int, default=None,
                   help="banked: words per bank, a power of two (default 512, the default "
                   "core's state banks)")
    f.add_argument("--default-config", action="store_true",
                   help="core, lif: the block's default configuration (e.g. 2500 neurons, "
                   "internal tick) instead of the smallest core")
    f.add_argument("--targets", type=positive_int, default=None,
                   help="coincidence: targets (default 2)")
    f.add_argument("--sources", type=positive_int, default=None,
                   help="coincidence: sources (default 2)")
    f.add_argument("--history", type=positive_int, default=None,
                   help="coincidence: history depth in ticks (default 3)")
    f.add_argument("--mutant",
                   choices=tuple(dict.fromkeys(MUTANTS + DETECTOR_MUTANTS + LINK_MUTANTS
                                               + BANK_MUTANTS + tuple(FANOUT_MUTANTS)
                                               + FACE_MUTANTS + tuple(STAGE_MUTANTS))),
                   default=None, help="core, lif, coincidence, link, plasticity: build this "
                   "fault into the block (the proof must fail)")
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
    add_quiet_option(f)
    f.set_defaults(func=cmd_prove, preset=None)
