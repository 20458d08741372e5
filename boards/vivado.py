"""Vivado-ready projects for the Xilinx boards: the Verilog of the board top, the XDC from the
board file and the build TCL amaranth writes (:func:`write_project`), and a syntax check of
that TCL and XDC with ``tclsh`` (:func:`check_tcl`): both files are Tcl, and each is run
against stubs of the Vivado commands it may call, which record the calls (and check that the
files the project reads exist) instead of running them. Vivado itself is not run.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

__all__ = ["write_project", "check_tcl", "VIVADO_COMMANDS"]

#: the Vivado Tcl commands amaranth's project script and the boards' XDC use; any other
#: command fails the check (a misspelt or unexpected command is an error, as in Vivado)
VIVADO_COMMANDS = (
    "create_project", "add_files", "read_xdc", "synth_design", "opt_design", "place_design",
    "phys_opt_design", "route_design", "write_checkpoint", "write_bitstream", "write_cfgmem",
    "report_timing_summary", "report_utilization", "report_io", "report_control_sets",
    "report_clock_utilization", "report_route_status", "report_drc", "report_methodology",
    "report_power", "report_timing", "set_property", "get_property", "create_clock",
    "get_ports", "get_nets", "get_pins", "get_cells", "get_clocks", "get_iobanks",
    "current_design", "set_false_path", "set_max_delay", "set_clock_groups", "set_param",
    "set_msg_config", "get_runs", "launch_runs", "wait_on_run", "open_run", "set_input_delay",
    "set_output_delay", "create_generated_clock", "all_registers", "all_inputs",
    "all_outputs", "get_timing_paths", "quit")

_STUBS = r"""
set ::calls {}
set ::missing {}
foreach cmd $::vivado_commands {
    proc $cmd {args} "lappend ::calls [list $cmd]; return {}"
}
rename add_files _add_files
proc add_files {args} {
    foreach f $args { if {$f ne "" && [string index $f 0] ne "-" && ![file exists $f]} { lappend ::missing $f } }
    lappend ::calls add_files
}
rename read_xdc _read_xdc
proc read_xdc {args} {
    set f [lindex $args end]
    if {![file exists $f]} { lappend ::missing $f; return }
    lappend ::calls read_xdc
    uplevel #0 [list source $f]
}
if {[catch {source [lindex $::argv 0]} err]} {
    puts "error: $err"
    exit 1
}
puts "ok [llength $::calls]"
foreach f $::missing { puts "missing $f" }
foreach c [lsort -unique $::calls] { puts "used $c" }
"""


def write_project(platform, top, out: Path, name: str) -> list[str]:
    """Write ``name``.v, ``.xdc``, ``.tcl`` and ``build_<name>.sh`` of ``top`` on ``platform``
    (an amaranth ``XilinxPlatform``, Vivado toolchain) into ``out``; returns the files."""
    plan = platform.prepare(top, name=name)
    files = []
    for fname, data in plan.files.items():
        if fname.endswith((".v", ".xdc", ".tcl", ".sh")):
            p = Path(out) / fname
            p.write_bytes(data if isinstance(data, bytes) else data.encode())
            files.append(fname)
    return sorted(files)


def check_tcl(out: Path, name: str, extra_commands=()) -> dict:
    """Run ``name``.tcl (which reads ``name``.xdc) under ``tclsh`` with the Vivado commands
    (and ``extra_commands``) stubbed: ``{"ok", "commands", "used", "missing", "error"}``.
    Raises ``FileNotFoundError`` when ``tclsh`` is not installed."""
    tclsh = shutil.which("tclsh")
    if tclsh is None:
        raise FileNotFoundError("tclsh not found (apt-get install tcl)")
    stub = Path(out) / f"{name}.vivado_stub.tcl"
    commands = " ".join(VIVADO_COMMANDS + tuple(extra_commands))
    stub.write_text(f"set ::vivado_commands {{{commands}}}\n" + _STUBS)
    r = subprocess.run([tclsh, stub.name, f"{name}.tcl"], cwd=out, capture_output=True,
                       text=True, timeout=60)
    stub.unlink()
    lines = r.stdout.strip().splitlines()
    oks = [i for i, x in enumerate(lines) if x.startswith("ok ")]
    if r.returncode != 0 or not oks:
        return {"ok": False, "error": (lines[-1] if lines else r.stderr.strip())[:300]}
    printed, lines = lines[:oks[-1]], lines[oks[-1]:]     # what the script printed itself
    missing = [x[8:] for x in lines if x.startswith("missing ")]
    return {"ok": not missing, "commands": int(lines[0].split()[1]), "missing": missing,
            "used": [x[5:] for x in lines if x.startswith("used ")], "printed": printed}


if __name__ == "__main__":          # python -m cuneate.boards.vivado DIR NAME
    import sys
    print(json.dumps(check_tcl(Path(sys.argv[1]), sys.argv[2])))
