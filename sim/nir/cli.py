"""``cuneate nir import``, ``cuneate nir export``, ``cuneate nir spiketouch`` and
``cuneate simulate nir``.

Every bad input - a file that is not NIR, a truncated HDF5, a node or parameter the hardware
cannot hold, weights that saturate the chosen width, an input file of the wrong shape - exits
with status 2 and one line naming the file or the node and the reason.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from ..cli.options import (CliError, CommandGroups, engine_choices, input_file, nonneg_int,
                           output_dir, positive_float, positive_int, probability, run_budget,
                           add_quiet_option)

__all__ = ["register", "mapped_from_args", "load_input"]


def _mapping_options(p) -> None:
    g = p.add_argument_group("mapping")
    g.add_argument("--update-hz", type=positive_float, default=10_000.0,
                   help="tick rate of the cores; dt = 1 / update-hz (default 10000: dt 0.1 ms, "
                        "the step snnTorch's NIR export assumes)")
    g.add_argument("--scheme", choices=("exact", "euler"), default="exact",
                   help="discretization of NIR's equations (see docs/nir.md)")
    g.add_argument("--weight-bits", type=positive_int, default=8)
    g.add_argument("--weight-frac-bits", type=nonneg_int, default=None,
                   help="fix the weights' scale (2**-f); default: the finest that holds them")
    g.add_argument("--v-frac-bits", type=positive_int, default=16)


def mapped_from_args(args, graph_path: str):
    """Read and map the graph, or a one-line refusal."""
    from .graph import NirError, layers_of, read_graph
    from .mapping import map_graph
    try:
        chain = layers_of(read_graph(graph_path))
        return map_graph(chain, update_hz=args.update_hz, scheme=args.scheme,
                         weight_bits=args.weight_bits, weight_frac_bits=args.weight_frac_bits,
                         v_frac_bits=args.v_frac_bits)
    except NirError as exc:
        msg = str(exc)
        raise CliError(f"cuneate: {msg if msg.startswith(graph_path) else f'{graph_path}: {msg}'}"
                       ) from None


def load_input(path: str, n_inputs: int) -> np.ndarray:
    """An input file: ``.npy`` or ``.npz`` (the array ``input``, or its only array), or ``.csv``
    (one row per step), of shape (steps, n_inputs)."""
    p = input_file(path, "--input")
    try:
        if p.suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                if "input" not in z.files and len(z.files) != 1:
                    raise CliError(f"--input {path!r}: holds {len(z.files)} arrays "
                                   f"({', '.join(z.files[:6])}) and none named 'input'; name the "
                                   f"one to use 'input'")
                x = z["input"] if "input" in z.files else z[z.files[0]]
        elif p.suffix == ".npy":
            x = np.load(p)
        else:
            x = np.loadtxt(p, delimiter=",", ndmin=2)
    except (OSError, ValueError, KeyError, IndexError, EOFError, zipfile.BadZipFile) as exc:
        raise CliError(f"--input {path!r}: not a readable array ({str(exc)[:120]})") from None
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1 and n_inputs == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[1] != n_inputs or x.shape[0] < 1:
        raise CliError(f"--input {path!r}: shape {x.shape}, the graph takes (steps, {n_inputs})")
    return x


def _decay(alpha: float, quantized: float) -> str:
    """A decay and its quantized value, to digits that show the difference (``1 - 1e-08``
    where six significant digits would print 1)."""
    if alpha > 0.999:
        return f"1 - {1 - alpha:.4g} -> 1 - {1 - quantized:.4g}"
    return f"{alpha:.6g} -> {quantized:.6g}"


def _print_report(mapped) -> None:
    print(f"dt {mapped.dt * 1e3:g} ms, scheme {mapped.scheme}, {mapped.n_inputs} inputs, "
          f"{len(mapped.report)} layer(s), settle {mapped.config.settle_cycles} cycles per tick")
    for r in mapped.report:
        w, b = r["weights"], r["bias"]
        print(f"  layer {r['layer']} {r['node']} ({r['kind']}): {r['neurons']} neurons on a core "
              f"of {r['core_neurons']}, state {r['state']['format']}")
        print(f"    weights {w['format']} range [{w['range'][0]:.4g}, {w['range'][1]:.4g}] "
              f"lsb {w['scale_lsb']:.3g} worst error {w['max_abs_error']:.3g} saturated "
              f"{w['saturated']} zeroed {w['zeroed']}")
        print(f"    bias    {b['format']} range [{b['range'][0]:.4g}, {b['range'][1]:.4g}] "
              f"worst error {b['max_abs_error']:.3g} saturated {b['saturated']}")
        print("    decay   " + ", ".join(_decay(d["alpha"], d["alpha_quantized"])
                                         for d in r["decay"][:4]))
        if "synapse" in r:
            s = r["synapse"]
            print(f"    synapse {s['alpha']:.6g} -> {s['alpha_quantized']:.6g} (trace "
                  f"{s['trace']})")
        if "delay_ticks" in r:
            print(f"    delays  {r['delay_ticks']} ticks")


def _import_estimate(mapped) -> dict:
    """Memory and time of generating the network's Verilog, measured on 2 cores: about 5 s and
    200 MiB, plus per input of a core (its fan-in adder tree) 16 ms and 0.25 MiB, plus the
    weight memory's initial contents (2 us a weight); a 200-neuron layer of 2000 inputs took
    36 s and 650 MiB."""
    layers = mapped.config.layers
    fan_in = sum(c.n_inputs for c in layers)
    weights = sum(c.n_inputs * c.n_neurons for c in layers)
    return {"what": f"generating the Verilog of {len(layers)} layer(s) ({fan_in} inputs, "
                    f"{weights} weights)",
            "bytes": 200 * 2.0 ** 20 + fan_in * 0.25 * 2.0 ** 20 + weights * 64.0,
            "seconds": 5.0 + 0.016 * fan_in + 2e-6 * weights}


def cmd_import(args) -> int:
    from ...hdl.nir import generate_nir_network
    from .. import progress as prog
    from ..cli.options import check_estimate, start_progress
    mapped = mapped_from_args(args, args.graph)
    est = _import_estimate(mapped)
    check_estimate("cuneate nir import", est)
    out = output_dir(args.out)
    start_progress(args)
    with prog.step(f"{est['what']} (~{est['seconds']:.0f} s estimated)"):
        files = generate_nir_network(out, mapped.config)
    (out / "mapping.json").write_text(json.dumps(mapped.to_dict(), indent=1, default=float))
    if args.json:
        print(json.dumps(mapped.report, default=float))
        return 0
    _print_report(mapped)
    for f in [*files, out / "mapping.json"]:
        print(f)
    return 0


def cmd_export(args) -> int:
    import nir

    from ..cli.run import resolve_scene
    from .export import scene_graph
    from .graph import NirError
    scene = resolve_scene(args.scene, "cuneate nir export")   # a file or a shipped example
    try:
        graph = scene_graph(scene)
    except NirError as exc:
        raise CliError(f"cuneate nir export: {args.scene}: {exc}") from None
    out = Path(args.out)
    output_dir(out.parent if str(out.parent) else ".", "--out")
    nir.write(out, graph)
    print(f"{out}: {scene.kind} scene's second layer, {len(graph.nodes)} NIR nodes")
    if scene.kind == "ridge":
        print("  the afferents (Izhikevich) are not exported; the cuneate neurons' Izhikevich "
              "parameters travel in the Output node's metadata (cuneate_extension)")
    return 0


def _budget(args, mapped, steps: int) -> dict:
    """Refuse (one line) a run of ``steps`` whose memory (the input and, per step, every layer's
    spikes and state) or time (neuron updates, each weighing its fan-in; HDL engines: the
    network's cycles a tick) exceeds the limits, before anything of that size exists."""
    from ...golden.budget import array_bytes
    from ..engines.registry import ENGINES
    layers = mapped.config.layers
    neurons = sum(c.n_neurons for c in layers)
    nbytes = array_bytes(steps, mapped.n_inputs, itemsize=9) + array_bytes(steps, neurons,
                                                                          itemsize=24)
    if ENGINES[args.engine].hdl:
        work = float(steps) * (mapped.config.settle_cycles + 8)
    else:
        work = float(steps) * sum(c.n_neurons * (1 + c.n_inputs / 64) for c in layers)
    return run_budget("cuneate simulate nir", "nir", args.engine, work, nbytes,
                      what=f"{steps:.4g} steps of {args.graph} ({neurons} neurons in "
                           f"{len(layers)} layer(s))",
                      hint="fewer --steps or a shorter --input")


def cmd_simulate(args) -> int:
    from .engines import run_dict, run_network
    from .graph import NirError
    mapped = mapped_from_args(args, args.graph)
    if args.input:
        x = load_input(args.input, mapped.n_inputs)
        _budget(args, mapped, x.shape[0])
    else:
        _budget(args, mapped, args.steps)
        rng = np.random.default_rng(args.seed)
        x = (rng.random((args.steps, mapped.n_inputs)) < args.input_rate).astype(float)
    build = output_dir(args.build_dir, "--build-dir") if args.build_dir else None
    try:
        run = run_network(args.engine, mapped, x, build_dir=build)
    except NirError as exc:
        raise CliError(f"cuneate simulate nir: {exc}") from None
    out = run_dict(run, mapped) | {"graph": args.graph, "scheme": mapped.scheme}
    if args.json:
        print(json.dumps(out, default=float))
        return 0
    print(f"{args.graph} on {args.engine}: {run.n_ticks} steps of {mapped.dt * 1e3:g} ms "
          f"({mapped.scheme}), {run.wall_s:.2f} s")
    if run.spikes is not None:
        for i, s in enumerate(out["spikes_s"]):
            head = ", ".join(f"{t * 1e3:g}" for t in s[:6]) + (" ..." if len(s) > 6 else "")
            print(f"  output {i}: {len(s)} spikes (ms): {head}")
    else:
        print("  readout v after the last step: " + ", ".join(f"{v:.4g}" for v in
                                                              out["v_last"]))
    return 0


def cmd_spiketouch(args) -> int:
    from .spiketouch import format_table, run_spiketouch
    out = output_dir(args.out)
    try:
        res = run_spiketouch(out, quick=args.quick, hdl_trials=args.hdl_trials,
                             seed=args.seed, log=print)
    except RuntimeError as exc:
        raise CliError(f"cuneate nir spiketouch: {exc}") from None
    print(format_table(res))
    return 0


def register(groups: CommandGroups) -> None:
    s = groups.simulate.add_parser("nir", help="a NIR graph on the LIF cores")
    s.add_argument("graph", metavar="GRAPH.nir")
    s.add_argument("--engine", choices=engine_choices("nir"), metavar="ENGINE", default="golden",
                   help="%(choices)s (default golden)")
    s.add_argument("--input", default=None, metavar="FILE",
                   help="input spikes or values (steps x inputs): .npy, .npz or .csv")
    s.add_argument("--steps", type=positive_int, default=200,
                   help="without --input: random input spikes for this many steps")
    s.add_argument("--input-rate", type=probability, default=0.1,
                   help="without --input: each input's spike probability per step")
    s.add_argument("--seed", type=nonneg_int, default=0)
    s.add_argument("--build-dir", default=None)
    s.add_argument("--json", action="store_true")
    _mapping_options(s)
    s.set_defaults(func=cmd_simulate)

    p = groups.root.add_parser("nir", help="NIR graphs: import, export, SpikeTouch")
    sub = p.add_subparsers(dest="nir_command", required=True, parser_class=type(p))
    i = sub.add_parser("import", help="map a NIR graph onto LIF cores: Verilog, JSON, report")
    i.add_argument("graph", metavar="GRAPH.nir")
    i.add_argument("--out", required=True)
    i.add_argument("--json", action="store_true")
    add_quiet_option(i)
    _mapping_options(i)
    i.set_defaults(func=cmd_import)
    e = sub.add_parser("export", help="write a scene's second layer as a NIR graph")
    e.add_argument("scene", metavar="SCENE", help="scene file or shipped example name (as "
                                                  "cuneate run takes it)")
    e.add_argument("--out", required=True, metavar="GRAPH.nir")
    e.set_defaults(func=cmd_export)
    t = sub.add_parser("spiketouch", help="train, quantize, import and test a tactile SNN "
                                          "(needs the cross-check environment)")
    t.add_argument("--out", default="out/spiketouch")
    t.add_argument("--quick", action="store_true", help="a small run (tests)")
    t.add_argument("--hdl-trials", type=nonneg_int, default=20,
                   help="test trials run on Verilator per configuration (0: none)")
    t.add_argument("--seed", type=nonneg_int, default=0)
    t.set_defaults(func=cmd_spiketouch)
