"""Builds: Verilog always, a bitstream with the yowasp tools where the device allows, and a
resource/timing report (JSON and text).

The amaranth build script is executed in the build directory (the yowasp tools see only the
current directory) with ``$YOSYS``, ``$NEXTPNR_ECP5``/``$NEXTPNR_ICE40`` and
``$ECPPACK``/``$ICEPACK`` pointing at the yowasp entry points. nextpnr runs with
``--timing-allow-fail`` so that a missed clock is reported rather than fatal; the report says
whether timing met the requested clock.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from ..hdl.flow.synth import cell_counts, nextpnr_summary, run_yosys
from ..hdl.flow.tools import ToolError, yowasp_env
from ..hdl.flow.verilog import verilog_text
from ..hdl.lib.config import ConfigError
from ..hdl.link import LinkedCore
from .sizing import size_core
from .targets import TARGETS

__all__ = ["build_target", "BuildError", "yowasp_env"]


class BuildError(ToolError):
    """A tool failed or is missing (one line naming which)."""


def _nextpnr_report(path: Path, target: dict, clock_hz: float) -> dict:
    rep = nextpnr_summary(json.loads(path.read_text()))
    cells = {k: (v["used"], v["available"]) for k, v in rep["utilization"].items()}
    fmax, core_fmax = rep["fmax_mhz"], rep["min_fmax_mhz"]
    keys = target["nextpnr_cells"]
    res = {}
    for kind, cell in keys.items():
        used, avail = cells.get(cell, (0, 0))
        res[kind] = {"used": used, "available": avail,
                     "percent": round(100.0 * used / avail, 2) if avail else None}
    return {"resources": res, "fmax_mhz": fmax, "min_fmax_mhz": core_fmax,
            "requested_mhz": clock_hz / 1e6,
            "timing_met": core_fmax is not None and core_fmax >= clock_hz / 1e6}


def _yosys_estimate(out: Path, top: str, target: dict) -> dict:
    """``synth_xilinx`` of the linked core (flattened): LUT, FF, BRAM (in 18 Kbit blocks) and
    DSP counts with percent of the device. A synthesis estimate, not a vendor place and route."""
    try:
        run_yosys(out, f"read_verilog {top}.v; synth_xilinx -flatten -family "
                       f"{target['synth_family']} -top {top}; "
                       f"tee -q -o {top}.stat.json stat -json")
    except ToolError as exc:
        raise BuildError(str(exc)) from None
    cells = cell_counts(out / f"{top}.stat.json")
    lut = sum(v for k, v in cells.items() if k.startswith("LUT")) + \
        4 * cells.get("RAM32M", 0) + cells.get("RAM32X1D", 0) * 2 + cells.get("RAM64X1D", 0) * 2
    ff = sum(v for k, v in cells.items() if k.startswith("FD"))
    bram = sum(n * target["bram_cells"].get(k, 0) for k, n in cells.items())
    dsp = sum(v for k, v in cells.items() if k.startswith("DSP"))
    res = target["resources"]
    used = {"LUT": lut, "FF": ff, "BRAM": bram, "DSP": dsp}
    return {k: {"used": v, "available": res[k], "percent": round(100.0 * v / res[k], 2)}
            for k, v in used.items()}


def build_target(board: str, out: Path, n_neurons: int | None = None,
                 clock_hz: float | None = None, update_hz: float | None = None,
                 bitstream: bool = True, seed: int = 1, name: str | None = None,
                 pipeline_stages: int | None = None, scene=None) -> dict:
    """Size the core for ``board``, write its Verilog (``<name>.v`` of the linked core, the
    board top's ``<name>.debug.v``), build the bitstream when the board supports it and
    ``bitstream`` is true, and write ``<name>.report.json`` / ``.txt``. Returns the report.
    ``scene`` (a :class:`~cuneate.sim.scenes.scene.Scene`): the board holds exactly the
    scene's blocks, sized to it (:func:`scene_request`), and the report gives the link's
    budget for it. Raises :class:`~cuneate.hdl.izhikevich.config.ConfigError` for a core the
    device cannot hold or a scene the link cannot carry in real time, and
    :class:`BuildError` for a failed tool."""
    from ..sim import progress as prog
    from ..sim.provenance import provenance
    if board not in TARGETS:
        raise ConfigError(f"unknown board {board!r}; known: {', '.join(TARGETS)}")
    target = TARGETS[board]
    depth = {} if pipeline_stages is None else {"pipeline_stages": pipeline_stages}
    request = scene_request(scene, target) if scene is not None else None
    neuron_sets = None
    if request is not None:
        n_neurons, update_hz = request["neurons"], request["core"]["update_hz"]
        depth.update({k: v for k, v in request["core"].items()
                      if k not in ("update_hz", "neuron_sets")})
        if len(request["core"]["param_sets"]) > 1:
            neuron_sets = request["core"]["neuron_sets"]
    sized = size_core(target, n_neurons=n_neurons, clock_hz=clock_hz, update_hz=update_hz,
                      **depth)
    if neuron_sets is not None:
        # the cores of an array share one neuron-to-set table: one core, or one set
        k = sized["link"].n_cores
        if k > 1:
            raise ConfigError(f"{board}: the scene needs {k} cores and mixes "
                              f"{len(request['core']['param_sets'])} parameter sets; the cores "
                              f"share one neuron-to-set table (one set, or "
                              f"{sized['link'].core.n_neurons} neurons at most)")
        sized = size_core(target, n_neurons=n_neurons, clock_hz=clock_hz,
                          update_hz=update_hz, neuron_sets=neuron_sets, **depth)
    lcfg = sized["link"]
    name = name or f"cuneate_{board}"
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}_core.v").write_text(verilog_text(LinkedCore(lcfg), f"{name}_core"))
    report = {"board": board, "device": target["device"], "name": name,
              "neurons": lcfg.n_neurons, "requested_neurons": sized["requested_neurons"],
              "cores": lcfg.n_cores, "neurons_per_core": lcfg.core.n_neurons,
              "pipeline_stages": lcfg.core.pipeline_stages,
              "core": lcfg.core.to_kwargs(), "link": lcfg.to_dict(),
              "clock_plan": sized["plan"], "estimate": sized["estimate"],
              "bitstream": None, "seed": seed}
    if request is not None:
        report["scene"] = {k: v for k, v in request.items() if k not in ("core",)}
    if target.get("bitstream") and bitstream:
        from .top import BoardTop
        platform = target["platform"]()
        top = BoardTop(lcfg, sized["pll"], target.get("uart_tx_enable", False))
        opts = f"--report {name}.nextpnr.json --timing-allow-fail --seed {seed}"
        plan = platform.prepare(top, name=name, nextpnr_opts=opts,
                                **target.get("prepare_opts", {}))
        t0 = time.monotonic()
        try:
            with prog.step(f"{board}: synthesis, place and route, bitstream (yosys, "
                           f"nextpnr-{target['family']}; minutes)"):
                plan.execute_local(out, env=yowasp_env(target["family"]))
        except Exception as exc:       # the script's failure: name the log to read
            raise BuildError(f"{board} build failed ({exc.__class__.__name__}); see the logs "
                             f"in {out}") from None
        report["build_seconds"] = round(time.monotonic() - t0, 1)
        bit = out / f"{name}.{target['bitstream_ext']}"
        report["bitstream"] = str(bit) if bit.exists() else None
        report["place_route"] = _nextpnr_report(out / f"{name}.nextpnr.json", target,
                                                lcfg.core.clock_hz)
        report["timing_met"] = report["place_route"]["timing_met"]
    if target.get("synth_family") and bitstream:
        with prog.step(f"{board}: yosys synth_{target['synth_family']} resource estimate"):
            report["yosys_estimate"] = _yosys_estimate(out, f"{name}_core", target)
    report["provenance"] = provenance()
    (out / f"{name}.report.json").write_text(json.dumps(report, indent=2, sort_keys=True)
                                             + "\n")
    (out / f"{name}.report.txt").write_text(format_report(report))
    return report


def scene_request(scene, target: dict) -> dict:
    """What a board for ``scene`` holds and whether its link carries the scene in real time at
    the board's baud (worst case: every current every sample, every neuron at 200 Hz);
    :class:`ConfigError` names the first limit it exceeds. Only afferent scenes (Izhikevich
    afferents behind the link) build today."""
    from ..sim.host.uart import BUDGET_BAUDS, format_budget, link_budget
    from ..sim.scenes.registry import kind_for
    kind = kind_for(scene["stimulus"]["kind"])
    if kind.name != "afferent":
        raise ConfigError(f"scene {scene.name!r} ({kind.name}) needs the {kind.block} block on "
                          f"the board; cuneate build makes board tops of Izhikevich afferents "
                          f"behind the link (afferent scenes)")
    from ..sim.scenes.afferent import build_neurons, n_driven, scene_core
    neurons = build_neurons(scene, n_driven(scene)[0])
    core = scene_core(scene, neurons)
    req = {"neurons": len(neurons), "core": core, "sample_hz": scene["sensor"]["sample_rate_hz"],
           "blocks": [{"block": "izhikevich_core", "neurons": len(neurons),
                       "param_sets": list(core["param_sets"])}]}
    from ..hdl.izhikevich.config import IzhikevichConfig
    width = IzhikevichConfig(n_neurons=8, clock_hz=16 * req["core"]["update_hz"],
                             update_hz=req["core"]["update_hz"],
                             current_format=req["core"]["current_format"]).I.width
    from ..hdl.link.codec import MAX_FRAME, MIN_FRAME, SPIKE_HEADER
    baud = target["clock_plan"].baud
    budget = link_budget(req["neurons"], width, req["sample_hz"], req["core"]["update_hz"],
                         200.0 * req["neurons"], bauds=sorted({*BUDGET_BAUDS, baud}))
    req["link_budget"] = budget
    row = next(r for r in budget["rows"] if r["baud"] == baud)
    cap = baud / 10
    if budget["in_bytes_per_s"] > cap:
        raise ConfigError(f"{target['name']}: the scene's currents take "
                          f"{budget['in_bytes_per_s']:,.0f} B/s to the board (worst case: "
                          f"{req['neurons']} currents every sample at {req['sample_hz']:g} Hz), "
                          f"more than the {baud / 1e6:g} Mbaud link's {cap:,.0f} B/s (link limit)")
    if not row["real_time"]:
        raise ConfigError(f"{target['name']}: the scene's spikes take "
                          f"{budget['out_bytes_per_s']:,.0f} B/s from the board (worst case: "
                          f"{req['neurons']} neurons at 200 Hz), more than the "
                          f"{baud / 1e6:g} Mbaud link's {cap:,.0f} B/s (link limit)")
    frame_spikes = (MAX_FRAME - MIN_FRAME - SPIKE_HEADER) // 3
    if budget["spikes_per_batch"] > frame_spikes:
        raise ConfigError(f"{target['name']}: {budget['spikes_per_batch']:.0f} spikes a batch "
                          f"of {budget['batch_sweeps']} sweeps (worst case: {req['neurons']} "
                          f"neurons at 200 Hz) exceed the {frame_spikes} a spike frame holds "
                          f"(link limit)")
    req["link_budget_lines"] = format_budget(budget)
    return req


def format_report(r: dict) -> str:
    pr = r.get("place_route")
    lines = []
    if pr and not pr["timing_met"]:
        lines.append(f"TIMING NOT MET: {pr['min_fmax_mhz']} MHz reached, "
                     f"{pr['requested_mhz']:g} MHz requested")
    cores = r.get("cores", 1)
    lines.append(f"{r['board']} ({r['device']}): {r.get('neurons', r['core']['n_neurons'])} "
                 f"neurons ({cores} core{'s' if cores > 1 else ''} of "
                 f"{r['core']['n_neurons']}, pipeline depth "
                 f"{r['core'].get('pipeline_stages', 5)}), {r['core']['clock_hz'] / 1e6:g} MHz, "
                 f"{r['core']['update_hz'] / 1e3:g} kHz updates, UART "
                 f"{r['link']['baud'] / 1e6:g} Mbaud")
    sc = r.get("scene")
    if sc:
        lines.append("scene blocks: " + "; ".join(
            f"{b['block']} ({b['neurons']} neurons, sets {', '.join(b['param_sets'])})"
            for b in sc["blocks"]))
        lines.append("link bandwidth (worst case: every current every sample, 200 Hz a neuron):")
        lines += [f"  {x}" for x in sc["link_budget_lines"]]
    est = r.get("estimate") or {}
    if est:
        lines.append("estimate: " + ", ".join(f"{k} {v}" for k, v in est.items()))
    ye = r.get("yosys_estimate")
    if ye:
        lines.append("yosys synth_xilinx estimate (BRAM in 18 Kbit blocks):")
        for kind, v in ye.items():
            lines.append(f"{kind:5s} {v['used']:8g} / {v['available']} ({v['percent']:.1f} %)")
    if pr:
        for kind, v in pr["resources"].items():
            pct = f" ({v['percent']:.1f} %)" if v["percent"] is not None else ""
            lines.append(f"{kind:5s} {v['used']:6d} / {v['available']}{pct}")
        lines.append(f"fmax {pr['min_fmax_mhz']} MHz, requested {pr['requested_mhz']:g} MHz: "
                     f"timing {'met' if pr['timing_met'] else 'NOT met'}")
    if r.get("bitstream"):
        lines.append(f"bitstream {r['bitstream']}")
    return "\n".join(lines) + "\n"
