"""Register packing for ECP5 multipliers and block RAMs: moves fabric flip-flops into the
MULT18X18D's own input and output registers and the DP16KD's output registers in a
``synth_ecp5`` JSON netlist, before nextpnr-ecp5 reads it.

yosys maps a product to a bare MULT18X18D (no register enabled), so a multiplier fed from
registers and feeding registers costs its whole combinational delay (about 3.9 ns on the
LFE5U-85F -6) plus the routing from and to fabric flip-flops on each side. The DSP block has
registers of its own (Lattice TN1267, sysDSP usage guide: ``REG_INPUTA/B`` and
``REG_OUTPUT``, each with a clock, clock-enable and reset selected from ``CLK0..3``,
``CE0..3``, ``RST0..3``). :func:`pack_dsp_registers` uses them where the netlist already has
the equivalent register, so the cycle-level behaviour is unchanged:

* **Inputs A and B.** Every bit of both ports is a constant or the ``Q`` of a plain
  flip-flop (a ``TRELLIS_FF`` clocked on the rising edge, clock enable tied high, no set/reset
  net), all on one clock. Each port bit driven by a flip-flop is rewired to the flip-flop's
  ``DI`` net and ``REG_INPUTA/B_CLK = CLK0``: the DSP's register holds what the flip-flop
  holds, cycle for cycle. A flip-flop left with no other load is removed; one with other loads
  stays (the register is duplicated into the DSP). A constant port is registered too (it holds
  its constant from the first clock edge after configuration on): nextpnr-ecp5 times the input
  registers only when both ports have them, so both or neither are packed.
* **Output.** Every used product bit's only load is a plain flip-flop on that same clock. The
  flip-flops are removed and the product bits drive their ``Q`` nets (``REG_OUTPUT_CLK =
  CLK0``).

``CE0`` is tied high and ``RST0`` low; both the flip-flops replaced and the DSP registers start
at zero after configuration. Anything else (a clock enable, a reset, two clocks, a product bit
with a second load or a combinational load) leaves that port unpacked. The result is counted
(:class:`PackReport`). nextpnr-ecp5 times a multiplier by which registers it has
(``MULT18X18D_REGS_INPUT``/``OUTPUT``/``ALL``), so the packing shows in its fmax.

**Block RAM outputs** (:func:`pack_bram_registers`). yosys maps a memory's read port to a
DP16KD without its output register (``REGMODE = "NOREG"``): its data leaves 5.6-5.8 ns after
the clock. A read port whose every used data bit feeds only a plain flip-flop on the port's
clock (a memory read into a register and nothing else, as
:mod:`cuneate.hdl.lib.banked` builds the cores' memories) gets ``REGMODE = "OUTREG"``, the
flip-flops removed and the output enable ``OCE`` tied high (Lattice TN1264: the output
register loads the read latch every clock it is enabled), the same cycle behaviour.
:func:`pack_registers` packs the block RAMs first, then the multipliers.

Command line (what ``cuneate sweep --fmax --pack-registers``,
``synthesize(..., pack_registers=True)`` and the ECP5 board builds run between yosys and
nextpnr; ``--report`` writes :meth:`PackReport.to_dict` as JSON)::

    python -m cuneate.hdl.flow.ecp5_pack NETLIST.json [--report REPORT.json]

**Board builds** (:func:`packing_platform`): amaranth's ``LatticeECP5Platform`` (Trellis
toolchain) builds from its ``command_templates`` (yosys, nextpnr-ecp5, ecppack); the subclass
inserts this command after yosys's, on ``{{name}}.json`` in the build directory, run by
``$PYTHON`` (one more of the platform's ``required_tools``).
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["PackReport", "pack_dsp_registers", "pack_bram_registers", "pack_registers",
           "pack_netlist_file", "packing_platform", "PACK_COMMAND"]

#: the build-script command amaranth renders between yosys and nextpnr-ecp5 (relative paths:
#: the script runs in the build directory)
PACK_COMMAND = r"""
    {{invoke_tool("python")}} -m cuneate.hdl.flow.ecp5_pack {{name}}.json
        --report {{name}}.pack.json
"""

@dataclass
class PackReport:
    """What :func:`pack_dsp_registers` did: multipliers seen, input ports (A and B counted
    apart) and outputs packed, flip-flops removed and flip-flops duplicated into a DSP
    block (kept for their other loads)."""

    multipliers: int = 0
    inputs_packed: int = 0
    outputs_packed: int = 0
    ffs_removed: int = 0
    ffs_duplicated: int = 0
    block_rams: int = 0
    ram_outputs_packed: int = 0
    ram_ffs_removed: int = 0
    skipped: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"multipliers": self.multipliers, "inputs_packed": self.inputs_packed,
                "outputs_packed": self.outputs_packed, "ffs_removed": self.ffs_removed,
                "ffs_duplicated": self.ffs_duplicated, "block_rams": self.block_rams,
                "ram_outputs_packed": self.ram_outputs_packed,
                "ram_ffs_removed": self.ram_ffs_removed, "skipped": list(self.skipped)}

    def line(self) -> str:
        return (f"register packing: {self.multipliers} MULT18X18D, {self.inputs_packed} input "
                f"ports and {self.outputs_packed} outputs registered in the DSP "
                f"({self.ffs_removed} flip-flops removed, {self.ffs_duplicated} duplicated); "
                f"{self.block_rams} DP16KD, {self.ram_outputs_packed} read ports registered in "
                f"the block ({self.ram_ffs_removed} flip-flops removed)")


def _top(netlist: dict) -> dict:
    # yosys writes the top attribute as a binary string
    tops = [m for m in netlist["modules"].values()
            if int(str(m.get("attributes", {}).get("top", "0")), 2)]
    if len(tops) != 1:
        raise ValueError(f"the netlist has {len(tops)} top modules; expected one (flattened "
                         f"synth_ecp5 output)")
    return tops[0]


class _Nets:
    """Driver and loads of every net bit of one module."""

    def __init__(self, module: dict):
        self.cells = module["cells"]
        self.driver: dict = {}
        self.loads: dict = defaultdict(list)
        self.ports: set = set()
        for p in module.get("ports", {}).values():
            self.ports.update(b for b in p["bits"] if not isinstance(b, str))
        for name, c in self.cells.items():
            for pin, bits in c["connections"].items():
                out = c.get("port_directions", {}).get(pin) == "output"
                for b in bits:
                    if isinstance(b, str):
                        continue
                    if out:
                        self.driver[b] = (name, pin)
                    else:
                        self.loads[b].append((name, pin))

    def plain_ff(self, name: str) -> bool:
        """A rising-edge flip-flop with no clock enable and no set/reset net."""
        c = self.cells.get(name)
        if c is None or c["type"] != "TRELLIS_FF":
            return False
        par, con = c["parameters"], c["connections"]
        if par.get("CLKMUX", "CLK") != "CLK":
            return False
        ce_high = par.get("CEMUX", "1").strip() == "1" or con.get("CE") == ["1"]
        no_lsr = con.get("LSR", ["0"]) in (["0"], ["x"], [])
        starts_low = par.get("REGSET", "RESET") == "RESET"
        return ce_high and no_lsr and starts_low

    def load_count(self, bit) -> int:
        return len(self.loads.get(bit, [])) + (bit in self.ports)


def _pin(cell: dict, pin: str):
    return cell["connections"][pin][0]


def _set_pin(cell: dict, pin: str, value, direction: str = "input"):
    cell["connections"][pin] = [value]
    cell.setdefault("port_directions", {})[pin] = direction


def pack_dsp_registers(netlist: dict) -> PackReport:
    """Pack plain flip-flops into the MULT18X18D input and output registers of the (flattened)
    top module of ``netlist`` (yosys JSON, changed in place). Returns what it did."""
    mod = _top(netlist)
    cells = mod["cells"]
    rep = PackReport()
    for name in sorted(n for n, c in cells.items() if c["type"] == "MULT18X18D"):
        rep.multipliers += 1
        nets = _Nets(mod)              # rebuilt per block: the previous one rewired nets
        dsp = cells[name]
        packed_in: dict = {}
        for side in "AB":
            ffs = {}
            for i in range(18):
                b = _pin(dsp, f"{side}{i}")
                if isinstance(b, str):
                    continue
                drv = nets.driver.get(b)
                if drv is None or drv[1] != "Q" or not nets.plain_ff(drv[0]):
                    rep.skipped.append(f"{name}.{side}")
                    break
                ffs[i] = drv[0]
            else:
                packed_in[side] = ffs
        in_clocks = {_pin(cells[f], "CLK") for ffs in packed_in.values() for f in ffs.values()}
        if len(packed_in) < 2 or len(in_clocks) != 1:
            # both ports or neither, on one clock; constant ports alone stay as they are
            packed_in = {}
        p_ffs = {}
        for i in range(36):
            b = _pin(dsp, f"P{i}")
            if isinstance(b, str) or nets.load_count(b) == 0:
                continue
            loads = nets.loads.get(b, [])
            if b in nets.ports or len(loads) != 1 or loads[0][1] != "DI" \
                    or not nets.plain_ff(loads[0][0]):
                p_ffs = {}
                break
            p_ffs[i] = loads[0][0]
        p_clocks = {_pin(cells[f], "CLK") for f in p_ffs.values()}
        if len(p_clocks) != 1:
            rep.skipped.append(f"{name}.P")
            p_ffs, p_clocks = {}, set()
        if packed_in and p_clocks and in_clocks != p_clocks:
            packed_in = {}             # one clock for the block: the output's registers win
        clocks = p_clocks or (in_clocks if packed_in else set())
        if not clocks:
            continue
        clk = clocks.pop()
        _set_pin(dsp, "CLK0", clk)
        _set_pin(dsp, "CE0", "1")
        _set_pin(dsp, "RST0", "0")
        params = dsp.setdefault("parameters", {})
        candidates: set = set()
        for side, ffs in packed_in.items():
            for i, ff in ffs.items():
                _set_pin(dsp, f"{side}{i}", _pin(cells[ff], "DI"))
                candidates.add(ff)
            params.update({f"REG_INPUT{side}_CLK": "CLK0", f"REG_INPUT{side}_CE": "CE0",
                           f"REG_INPUT{side}_RST": "RST0"})
            rep.inputs_packed += 1
        for i, ff in p_ffs.items():
            _set_pin(dsp, f"P{i}", _pin(cells[ff], "Q"), "output")
            cells.pop(ff)
            rep.ffs_removed += 1
        if p_ffs:
            params.update({"REG_OUTPUT_CLK": "CLK0", "REG_OUTPUT_CE": "CE0",
                           "REG_OUTPUT_RST": "RST0"})
            rep.outputs_packed += 1
        after = _Nets(mod)
        for ff in sorted(candidates):
            if after.load_count(_pin(cells[ff], "Q")) == 0:
                cells.pop(ff)
                rep.ffs_removed += 1
            else:
                rep.ffs_duplicated += 1
    return rep


def pack_bram_registers(netlist: dict, rep: PackReport | None = None) -> PackReport:
    """Pack plain flip-flops into the DP16KD output registers (``REGMODE_A/B = "OUTREG"``) of
    the (flattened) top module of ``netlist`` (yosys JSON, changed in place): a read port
    whose every used data bit has one load, the ``DI`` of a plain flip-flop clocked by the
    port's own clock, with the port's reset tied low. The flip-flops are removed, the data
    bits drive their ``Q`` nets and the output clock enable (``OCEA/B``) is tied high: the
    block's register holds, cycle for cycle, what the flip-flops held. Counted into ``rep``
    (a new report when None), which is returned."""
    mod = _top(netlist)
    cells = mod["cells"]
    rep = rep or PackReport()
    for name in sorted(n for n, c in cells.items() if c["type"] == "DP16KD"):
        rep.block_rams += 1
        ram = cells[name]
        params = ram.setdefault("parameters", {})
        for side in "AB":
            if params.get(f"REGMODE_{side}", "NOREG") != "NOREG":
                continue
            nets = _Nets(mod)
            ffs = {}
            for i in range(18):
                pin = f"DO{side}{i}"
                if pin not in ram["connections"]:
                    continue
                b = _pin(ram, pin)
                if isinstance(b, str) or nets.load_count(b) == 0:
                    continue
                loads = nets.loads.get(b, [])
                if b in nets.ports or len(loads) != 1 or loads[0][1] != "DI" \
                        or not nets.plain_ff(loads[0][0]):
                    ffs = None
                    break
                ffs[pin] = loads[0][0]
            if not ffs:
                if ffs is None:
                    rep.skipped.append(f"{name}.DO{side}")
                continue
            clk = ram["connections"].get(f"CLK{side}", [None])[0]
            rst = ram["connections"].get(f"RST{side}", ["0"])
            if {_pin(cells[f], "CLK") for f in ffs.values()} != {clk} or rst != ["0"]:
                rep.skipped.append(f"{name}.DO{side}")
                continue
            for pin, ff in ffs.items():
                _set_pin(ram, pin, _pin(cells[ff], "Q"), "output")
                cells.pop(ff)
                rep.ram_ffs_removed += 1
            _set_pin(ram, f"OCE{side}", "1")
            params[f"REGMODE_{side}"] = "OUTREG"
            rep.ram_outputs_packed += 1
    return rep


def pack_registers(netlist: dict) -> PackReport:
    """:func:`pack_bram_registers` then :func:`pack_dsp_registers` (a block RAM's output
    register first: a flip-flop after a block RAM that also feeds a multiplier is then the
    block's, and the multiplier's input stays unregistered)."""
    rep = pack_bram_registers(netlist)
    dsp = pack_dsp_registers(netlist)
    for k in ("multipliers", "inputs_packed", "outputs_packed", "ffs_removed",
              "ffs_duplicated"):
        setattr(rep, k, getattr(dsp, k))
    rep.skipped += dsp.skipped
    return rep


def pack_netlist_file(path: Path) -> PackReport:
    """:func:`pack_registers` on the JSON netlist at ``path``, rewritten in place."""
    path = Path(path)
    netlist = json.loads(path.read_text())
    rep = pack_registers(netlist)
    path.write_text(json.dumps(netlist))
    return rep


class _PackingECP5:
    """Mixin over an amaranth ``LatticeECP5Platform`` (Trellis toolchain): the register
    packing between yosys and nextpnr-ecp5."""

    @property
    def required_tools(self):
        return [*super().required_tools, "python"]

    @property
    def command_templates(self):
        yosys, *rest = super().command_templates
        return [yosys, PACK_COMMAND, *rest]


def packing_platform(platform):
    """``platform`` (an amaranth ECP5 platform instance, Trellis toolchain) as an instance of
    a subclass whose build script packs the registers (:data:`PACK_COMMAND`) between yosys and
    nextpnr-ecp5, with the resources and connectors added to ``platform``. Anything else
    raises ``ValueError``."""
    if getattr(platform, "family", None) != "ecp5" or platform.toolchain != "Trellis":
        raise ValueError(f"register packing needs an ECP5 platform with the Trellis toolchain, "
                         f"not {type(platform).__name__}")
    cls = type(platform)
    packed = type(f"{cls.__name__}Packed", (_PackingECP5, cls), {"__module__": __name__})
    out = packed(toolchain=platform.toolchain)
    # what the board file added to its instance (a UART on a header, LEDs) comes along
    out.add_resources([r for k, r in platform.resources.items() if k not in out.resources])
    out.add_connectors([c for k, c in platform.connectors.items() if k not in out.connectors])
    return out


_USAGE = "usage: python -m cuneate.hdl.flow.ecp5_pack NETLIST.json [--report REPORT.json]"


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    report = None
    if len(args) == 3 and args[1] == "--report":
        args, report = args[:1], args[2]
    if len(args) != 1 or args[0].startswith("-"):
        print(_USAGE, file=sys.stderr)
        return 2
    try:
        rep = pack_netlist_file(Path(args[0]))
        if report is not None:
            Path(report).write_text(json.dumps(rep.to_dict(), indent=2) + "\n")
    except (OSError, ValueError, KeyError) as exc:
        print(f"ecp5_pack: {args[0]}: {exc}", file=sys.stderr)
        return 2
    print(rep.line())
    return 0


if __name__ == "__main__":
    sys.exit(main())
