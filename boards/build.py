"""Builds: Verilog always, a bitstream with the yowasp tools where the device allows, and a
resource/timing report (JSON and text).

The amaranth build script is executed in the build directory (the yowasp tools see only the
current directory) with ``$YOSYS``, ``$NEXTPNR_ECP5``/``$NEXTPNR_ICE40`` and
``$ECPPACK``/``$ICEPACK`` pointing at the yowasp entry points. nextpnr runs with
``--timing-allow-fail`` so that a missed clock is reported rather than fatal; the report says
whether timing met the requested clock. ECP5 builds pack the flip-flops around the
multipliers and after the block RAMs into the MULT18X18D and DP16KD registers between yosys
and nextpnr (:func:`~cuneate.hdl.flow.ecp5_pack.packing_platform`; ``pack_registers=False``
builds without); the report's ``register_packing`` says what moved.
"""

from __future__ import annotations

import json
import math
import time
from collections import Counter
from pathlib import Path

from ..hdl.flow.ecp5_pack import packing_platform
from ..hdl.flow.synth import cell_counts, nextpnr_summary, run_yosys
from ..hdl.flow.tools import ToolError, yowasp_env
from ..hdl.flow.verilog import verilog_text
from ..hdl.lib.config import ConfigError
from ..hdl.link import LinkedTop
from .scene import scene_request
from .sizing import size_core
from .targets import TARGETS

__all__ = ["build_target", "board_platform", "size_blocks", "BuildError", "yowasp_env"]


class BuildError(ToolError):
    """A tool failed or is missing (one line naming which)."""


def _nextpnr_report(path: Path, target: dict, clock_hz: float,
                    netlist: Path | None = None) -> dict:
    """Resources, fmax per clock and timing of a board build's nextpnr report. nextpnr derives
    each clock's constraint from the board oscillator's through the PLL's dividers: a derived
    constraint other than the plan's clock (by more than 0.1 %) means the PLL does not make the
    clock the plan sized the cores for, and raises :class:`BuildError`."""
    rep = nextpnr_summary(json.loads(path.read_text()))
    cells = {k: (v["used"], v["available"]) for k, v in rep["utilization"].items()}

    def usage(used, avail):
        return {"used": used, "available": avail,
                "percent": round(100.0 * used / avail, 2) if avail else None}

    # nextpnr names a clock by its global net ("$glbnet$clk"): the report gives the domain's
    def domain(net):
        return net.removeprefix("$glbnet$")

    fmax = {domain(k): v for k, v in rep["fmax_mhz"].items()}
    for clk, c in rep.get("constraint_mhz", {}).items():
        if c is not None and abs(c * 1e6 - clock_hz) > 1e-3 * clock_hz:
            raise BuildError(f"{target['name']}: nextpnr derives {c:.4g} MHz for clock "
                             f"{domain(clk)} from the PLL, the clock plan asks "
                             f"{clock_hz / 1e6:g} MHz (the PLL's dividers do not give the plan's "
                             f"clock)")
    core_fmax = rep["min_fmax_mhz"]
    res = {kind: usage(*cells.get(cell, (0, 0)))
           for kind, cell in target["nextpnr_cells"].items()}
    if target.get("netlist_cells"):
        # iCE40: nextpnr counts logic cells (a LUT4 and a flip-flop each); the synthesized
        # netlist says how many of each the design uses
        types = Counter(cell["type"]
                        for mod in json.loads(netlist.read_text())["modules"].values()
                        for cell in mod.get("cells", {}).values())
        avail = cells.get(target["netlist_cells"]["per"], (0, 0))[1]
        for kind, prefix in target["netlist_cells"]["count"].items():
            res[kind] = usage(sum(v for k, v in types.items() if k.startswith(prefix)), avail)
    res = {k: res[k] for k in dict.fromkeys(["LC", "LUT", "FF", *res]) if k in res}
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


def packs_registers(target: dict, pack_registers: bool = True) -> bool:
    """Whether a build of ``target`` packs registers (asked, and an ECP5 target)."""
    return pack_registers and target["family"] == "ecp5"


def board_platform(target: dict, pack_registers: bool = True):
    """The platform a build of ``target`` runs on: its board file's, with the ECP5 register
    packing between yosys and nextpnr when :func:`packs_registers`."""
    platform = target["platform"]()
    return packing_platform(platform) if packs_registers(target, pack_registers) else platform


def build_target(board: str, out: Path, n_neurons: int | None = None,
                 clock_hz: float | None = None, update_hz: float | None = None,
                 bitstream: bool = True, seed: int = 1, name: str | None = None,
                 pipeline_stages: int | None = None, scene=None,
                 baud: float | None = None, pack_registers: bool = True) -> dict:
    """Size the core for ``board``, write its Verilog (``<name>.v`` of the linked core, the
    board top's ``<name>.debug.v``), build the bitstream when the board supports it and
    ``bitstream`` is true, and write ``<name>.report.json`` / ``.txt``. Returns the report.
    ``scene`` (a :class:`~cuneate.sim.scenes.scene.Scene`): the board holds exactly the
    scene's blocks, sized to it (:func:`scene_request`), and the report gives the link's
    budget for it. Raises :class:`~cuneate.hdl.izhikevich.config.ConfigError` for a core the
    device cannot hold or a scene the link cannot carry in real time, and
    :class:`BuildError` for a failed tool. ``pack_registers`` (ECP5 bitstreams): the
    register packing between yosys and nextpnr (:mod:`~cuneate.hdl.flow.ecp5_pack`)."""
    from ..sim import progress as prog
    from ..sim.provenance import provenance
    if board not in TARGETS:
        raise ConfigError(f"unknown board {board!r}; known: {', '.join(TARGETS)}")
    target = TARGETS[board]
    depth = {} if pipeline_stages is None else {"pipeline_stages": pipeline_stages}
    request = scene_request(scene, target, baud=baud) if scene is not None else None
    if request is not None and request.kind != "core":
        sized = size_blocks(target, request, clock_hz, pipeline_stages, baud)
    else:
        sized = _size_cores(target, request, n_neurons, clock_hz, update_hz, depth, baud)
    lcfg = sized["link"]
    name = name or f"cuneate_{board}"
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    if not target.get("zynq"):          # a Zynq board's block is behind the AXI face (below)
        (out / f"{name}_core.v").write_text(verilog_text(LinkedTop(lcfg), f"{name}_core"))
    report = {"board": board, "device": target["device"], "name": name,
              "neurons": request.neurons if request is not None else lcfg.n_neurons,
              "requested_neurons": sized["requested_neurons"],
              "cores": lcfg.n_cores, "neurons_per_core": lcfg.core.n_neurons,
              "pipeline_stages": getattr(lcfg.core, "pipeline_stages", None),
              "core": lcfg.core.to_kwargs(), "link": lcfg.to_dict(),
              "clock_plan": sized["plan"], "estimate": sized["estimate"],
              "bitstream": None, "seed": seed, "register_packing": None}
    if request is not None:
        report["scene"] = request.describe()
    if target.get("bitstream") and bitstream:
        from .top import BoardTop
        platform = board_platform(target, pack_registers)
        packing = packs_registers(target, pack_registers)
        top = BoardTop(lcfg, sized["pll"], target.get("uart_tx_enable", False),
                       target.get("status_leds"))
        opts = f"--report {name}.nextpnr.json --timing-allow-fail --seed {seed}"
        if target.get("nextpnr_freq"):
            # nextpnr does not derive the clock through this family's PLL: the plan's clock
            # is its target for every clock (the oscillator's net only feeds the PLL)
            opts += f" --freq {lcfg.core.clock_hz / 1e6:g}"
        if target.get("nextpnr_extra"):
            opts += " " + target["nextpnr_extra"]
        plan = platform.prepare(top, name=name, nextpnr_opts=opts,
                                **target.get("prepare_opts", {}))
        t0 = time.monotonic()
        try:
            with prog.step(f"{board}: synthesis, place and route, bitstream (yosys, "
                           f"nextpnr-{target['family']}; minutes)"):
                plan.execute_local(out, env=yowasp_env(target["family"])
                                   | target.get("tool_env", {}))
        except Exception as exc:       # the script's failure: name the log to read
            raise BuildError(f"{board} build failed ({exc.__class__.__name__}); see the logs "
                             f"in {out}") from None
        report["build_seconds"] = round(time.monotonic() - t0, 1)
        if packing:
            report["register_packing"] = json.loads((out / f"{name}.pack.json").read_text())
        bit = out / f"{name}.{target['bitstream_ext']}"
        report["bitstream"] = str(bit) if bit.exists() else None
        report["place_route"] = _nextpnr_report(out / f"{name}.nextpnr.json", target,
                                                lcfg.core.clock_hz, out / f"{name}.json")
        report["timing_met"] = report["place_route"]["timing_met"]
    if target.get("vivado"):
        from .top import BoardTop
        from .vivado import check_tcl, write_project
        top = BoardTop(lcfg, sized["pll"], False, target.get("status_leds"))
        files = write_project(target["platform"](), top, out, name)
        try:
            check = check_tcl(out, name)
        except FileNotFoundError as exc:
            check = {"ok": None, "error": str(exc)}
        report["vivado_project"] = {"files": files, "tcl_check": check,
                                    "not_run": "Vivado (synthesis, place and route, "
                                               "bitstream)"}
    if target.get("zynq"):
        from .vivado import check_tcl
        from .zynq import BD_COMMANDS, write_ip_package
        ip = write_ip_package(target, lcfg.payload, out, name)
        try:
            ip["tcl_check"] = check_tcl(Path(ip["dir"]), f"{name}_bd", BD_COMMANDS)
        except FileNotFoundError as exc:
            ip["tcl_check"] = {"ok": None, "error": str(exc)}
        report["vivado_ip"] = ip
    if target.get("synth_family") and bitstream:
        with prog.step(f"{board}: yosys synth_{target['synth_family']} resource estimate"):
            if target.get("zynq"):          # the packaged block behind the AXI face
                report["yosys_estimate"] = _yosys_estimate(Path(ip["dir"]) / "src", name,
                                                           target)
            else:
                report["yosys_estimate"] = _yosys_estimate(out, f"{name}_core", target)
    report["provenance"] = provenance()
    (out / f"{name}.report.json").write_text(json.dumps(report, indent=2, sort_keys=True)
                                             + "\n")
    (out / f"{name}.report.txt").write_text(format_report(report))
    return report


def _size_cores(target: dict, request, n_neurons, clock_hz, update_hz, depth: dict,
                baud=None) -> dict:
    """The Izhikevich core(s) behind the link (:class:`LinkedTop`): ``n_neurons``, or the
    afferents of an afferent scene's ``request``."""
    neuron_sets = None
    if request is not None:
        n_neurons, update_hz = request.neurons, request.core["update_hz"]
        depth = depth | {k: v for k, v in request.core.items()
                         if k not in ("update_hz", "neuron_sets")}
        if len(request.core["param_sets"]) > 1:
            neuron_sets = request.core["neuron_sets"]
    # an array's cores share the table of parameter sets; each starts its own neurons with
    # their own sets (the scene's populations wherever they land)
    return size_core(target, n_neurons=n_neurons, clock_hz=clock_hz, update_hz=update_hz,
                     baud=baud, **depth,
                     **({} if neuron_sets is None else {"neuron_sets": neuron_sets}))


def size_blocks(target: dict, request, clock_hz, pipeline_stages, baud=None) -> dict:
    """The scene's blocks behind the link (a fan-out core, a network, a LIF core: one of each)
    at the first of the target's clock plans whose sweep holds them and whose clock stays
    below the measured fmax (as :func:`~cuneate.boards.sizing.size_core` chooses for cores),
    on the line at ``baud``. A fan-out core's block RAMs and multipliers (the core's, the
    link's, the table's and the fan-out's product) are estimated and checked against the
    device; a network's or a LIF core's resources come from place and route."""
    from .sizing import FMAX_MARGIN, chosen_plans, count_blocks, device_overrun, estimate, \
        fmax_bound
    from ..hdl.izhikevich.config import PIPELINE_DEPTH
    if pipeline_stages not in (None, PIPELINE_DEPTH) and request.kind != "fanout":
        raise ConfigError(f"{target['name']}: --pipeline-stages sets the depth of an afferent "
                          f"scene's Izhikevich cores, not of a {request.kind} board")
    depth = pipeline_stages or 5
    plans = chosen_plans(target, clock_hz, request.update_hz, baud)
    fmax = fmax_bound(target, depth)
    why = []
    for plan, pll in plans:
        if fmax is not None and plan.clock_hz > FMAX_MARGIN * fmax and len(plans) > 1:
            why.append(f"the {plan.clock_hz / 1e6:g} MHz plan is above {FMAX_MARGIN:g} x the "
                       f"{fmax / 1e6:.4g} MHz fmax (fmax limit)")
            continue
        try:
            lcfg = request.linked(plan, target, pipeline_stages=depth)
        except ConfigError as exc:
            why.append(f"at {plan.clock_hz / 1e6:g} MHz: {exc}")
            continue
        est = {}
        if request.kind == "fanout" or request.extra:
            est = estimate(lcfg, target)
            f = lcfg.fanout
            if f is not None:
                est["BRAM"] += count_blocks([(f.n_neurons, f.entry_width),
                                             (f.n_channels, f.S.width)], target)
                est["DSP"] += math.ceil(f.gain_width / target["dsp_width"]) * \
                    math.ceil(f.S.width / target["dsp_width"])
            for k, v in request.extra.items():      # a cuneate layer's detector
                est[k] = est.get(k, 0) + v
            over = device_overrun(est, target)
            if over is not None:
                why.append(f"at {plan.clock_hz / 1e6:g} MHz: {over}")
                continue
        return {"link": lcfg, "pll": pll, "estimate": est,
                "requested_neurons": request.neurons,
                "plan": {"osc_hz": plan.osc_hz, "clock_hz": plan.clock_hz,
                         "update_hz": plan.update_hz, "baud": plan.line_baud,
                         "cycles_per_tick": plan.cycles_per_tick,
                         "clocks_per_bit": plan.clocks_per_bit}}
    raise ConfigError(f"{target['name']}: no clock plan holds the scene's "
                      f"{', '.join(b['block'] for b in request.blocks)}: {'; '.join(why)}")


def _block_line(b: dict) -> str:
    if b["block"] == "channel_fanout":
        return (f"channel_fanout ({b['n_channels']} channels to {b['n_neurons']} afferents, "
                f"samples {b['sample_format']['format']}, table {b['table_bits']} bits)")
    sets = f", sets {', '.join(b['param_sets'])}" if b.get("param_sets") else ""
    role = f", {b['role']}" if b.get("role") else ""
    return f"{b['block']} ({b['neurons']} neurons{sets}{role})"


def _mhz(f: float | None) -> str:
    return "unknown" if f is None else f"{f:.2f}"


def format_report(r: dict) -> str:
    pr = r.get("place_route")
    lines = []
    if pr and not pr["timing_met"]:
        lines.append(f"TIMING NOT MET: {_mhz(pr['min_fmax_mhz'])} MHz reached, "
                     f"{pr['requested_mhz']:g} MHz requested")
    cores = r.get("cores", 1)
    depth = r.get("pipeline_stages")
    lines.append(f"{r['board']} ({r['device']}): {r.get('neurons', r['core']['n_neurons'])} "
                 f"neurons ({cores} core{'s' if cores > 1 else ''} of "
                 f"{r['core']['n_neurons']}"
                 + (f", pipeline depth {depth}" if depth else "")
                 + f"), {r['core']['clock_hz'] / 1e6:g} MHz, "
                 f"{r['core']['update_hz'] / 1e3:g} kHz updates, "
                 + ("behind the AXI face (no UART)" if "vivado_ip" in r else
                    "UART " + (f"{r['link']['baud'] / 1e6:g} Mbaud" if r['link']['baud'] >= 1e6
                               else f"{r['link']['baud']:.0f} baud "
                                    f"({r['link']['clocks_per_bit']} clocks a bit)")))
    ip = r.get("vivado_ip")
    if ip:
        chk = ip["tcl_check"]
        lines.append(f"Vivado IP {ip['vlnv']} in {ip['dir']}: component.xml (IP-XACT 1685-2009), "
                     f"block design {Path(ip['dir']).name[:-3]}_bd.tcl (tclsh with stubs: "
                     f"{'ok' if chk.get('ok') else chk.get('error') or chk.get('missing')}), "
                     f"PYNQ driver; streams {ip['streams']['write_tdata_bits']}-bit writes, "
                     f"{ip['streams']['spike_tdata_bits']}-bit spikes; not run: {ip['not_run']}")
    sc = r.get("scene")
    if sc:
        lines.append("scene blocks: " + "; ".join(_block_line(b) for b in sc["blocks"]))
        if sc.get("trials_on_board", sc.get("trials")) != sc.get("trials"):
            lines.append(f"the board holds {sc['trials_on_board']} of the scene's "
                         f"{sc['trials']} trials (hardware.board_trials); cuneate stream "
                         f"plays them in turn, {sc['trials_on_board']} at a time")
        values = "channel" if sc.get("kind") == "fanout" else "current"
        lines.append(f"link bandwidth (worst case: every {values} every sample, 200 Hz a "
                     f"neuron):")
        lines += [f"  {x}" for x in sc["link_budget_lines"]]
    est = r.get("estimate") or {}
    if est:
        lines.append(("sizing estimate (with the UART link's buffers): " if ip else "estimate: ")
                     + ", ".join(f"{k} {v}" for k, v in est.items()))
    ye = r.get("yosys_estimate")
    if ye:
        lines.append("yosys synth_xilinx estimate (BRAM in 18 Kbit blocks):")
        for kind, v in ye.items():
            lines.append(f"{kind:5s} {v['used']:8g} / {v['available']} ({v['percent']:.1f} %)")
    if pr:
        for kind, v in pr["resources"].items():
            pct = f" ({v['percent']:.1f} %)" if v["percent"] is not None else ""
            lines.append(f"{kind:5s} {v['used']:6d} / {v['available']}{pct}")
        per_clock = pr.get("fmax_mhz") or {}
        if len(per_clock) > 1:
            lines += [f"fmax of clock {clk}: {_mhz(f)} MHz" for clk, f in per_clock.items()]
        lines.append(f"fmax {_mhz(pr['min_fmax_mhz'])} MHz, requested {pr['requested_mhz']:g} MHz: "
                     f"timing {'met' if pr['timing_met'] else 'NOT met'}")
    rp = r.get("register_packing")
    if rp:
        lines.append(f"registers packed: {rp['inputs_packed']} multiplier input ports and "
                     f"{rp['outputs_packed']} outputs of {rp['multipliers']} MULT18X18D, "
                     f"{rp['ram_outputs_packed']} read ports of {rp['block_rams']} DP16KD "
                     f"({rp['ffs_removed'] + rp['ram_ffs_removed']} flip-flops removed)")
    if r.get("bitstream"):
        lines.append(f"bitstream {r['bitstream']}")
    return "\n".join(lines) + "\n"
