"""The LiteX SoC of :mod:`~cuneate.boards.litex_soc` simulated with the host on LiteX's own
bridge: :func:`write_sim_soc` writes the SoC with its clock and reset on pins instead of the
PLL (the rest as the ULX3S build: UARTBone, the peripheral at ``CUNEATE_BASE``);
:func:`run_sim` runs it on Icarus or Verilator under cocotb (:mod:`cuneate.boards.litex_bench`:
cocotbext-uart on ``serial_rx``/``serial_tx`` bridged to a pseudo-terminal, one pump each bit
time) while :func:`host_session`, in a thread of this process, drives it through
``litex.tools.remote.comm_uart.CommUART`` on that terminal with the addresses of the
``csr.csv`` LiteX wrote.

The line: ``sys_clk_hz / CLOCKS_PER_BIT`` baud (8 clocks a bit; the nominal clock only sets
UARTBone's tuning word and its 100 ms frame timeout, the simulator's clock period is 10 ns);
the pseudo-terminal's own rate is meaningless (``CommUART`` is given 115200).
"""

from __future__ import annotations

import re
import shutil
import threading
import time
from pathlib import Path

from .litex_soc import CUNEATE_BASE, require_litex, soc_around, ulx3s_platform, write_soc

__all__ = ["write_sim_soc", "host_session", "run_sim", "SIM_TOP", "CLOCKS_PER_BIT",
           "SIM_CLOCK_HZ"]

SIM_TOP = "cuneate_litex_sim"
CLOCKS_PER_BIT = 8
#: the SoC's nominal clock in simulation (UARTBone's tuning word and timeout)
SIM_CLOCK_HZ = 100e6
_BLOCK = "cuneate_wb"


def write_sim_soc(spec, out: Path, sys_clk_hz: float = SIM_CLOCK_HZ,
                  lowered: bool = False) -> dict:
    """The simulation SoC's Verilog in ``out/gateware`` (LiteX's top, its banner's date
    removed so that the same design has the same bytes, and the block behind the Wishbone
    face; ``lowered``: the block as the yosys-lowered netlist, for Icarus 11) and the CSR
    maps. Returns ``{"sources", "csr_csv", "csr_json", "baud"}``."""
    require_litex()
    from migen import ClockDomain
    from litex.build.generic_platform import Pins, Subsignal
    from litex.gen import LiteXModule

    out = Path(out).resolve()
    gw = out / "gateware"
    gw.mkdir(parents=True, exist_ok=True)
    platform = ulx3s_platform([("clk", 0, Pins("G2")), ("rst", 0, Pins("H2")),
                               ("serial", 0, Subsignal("tx", Pins("L4")),
                                Subsignal("rx", Pins("M1")))])

    class _CRG(LiteXModule):
        def __init__(self):
            self.cd_sys = ClockDomain()
            self.comb += [self.cd_sys.clk.eq(platform.request("clk")),
                          self.cd_sys.rst.eq(platform.request("rst"))]

    baud = int(sys_clk_hz // CLOCKS_PER_BIT)
    # LiteX's simulation flavour of combinational logic (one process per signal): the
    # synthesis flavour's shared processes loop forever in Icarus 11's delta cycles
    write_soc(soc_around(platform, _CRG, spec, gw, sys_clk_hz, baud), out, SIM_TOP,
              regular_comb=False)
    top = gw / f"{SIM_TOP}.v"
    top.write_text(_canonical(top.read_text()))
    if lowered:
        from ..hdl.flow.verilog import verilog_text
        from ..hdl.wishbone import WishboneTop
        (gw / f"{_BLOCK}.v").write_text(verilog_text(WishboneTop(spec), _BLOCK, lowered=True))
    return {"sources": [gw / f"{_BLOCK}.v", top], "csr_csv": out / "csr.csv",
            "csr_json": out / "csr.json", "baud": baud}


def _canonical(text: str) -> str:
    """LiteX's Verilog with the same bytes for the same design (the simulator cache's key):
    the banner's dates removed and the combinational processes, which LiteX's simulation
    flavour emits in an order that changes from run to run, sorted (the order of concurrent
    processes means nothing in Verilog)."""
    text = re.sub(r"(?m)^(//.*?)\s*(on )?\d{4}-\d\d-\d\d \d\d:\d\d:\d\d", r"\1", text)
    head, rest = text.split("// Combinatorial Logic\n", 1)
    rule, rest = rest.split("\n", 1)
    comb, tail = rest.split("//" + "-" * 78 + "\n// Synchronous Logic\n", 1)
    items, cur = [], []
    for line in comb.splitlines(keepends=True):
        if not cur and not line.strip():
            continue
        cur.append(line)
        if (cur[0].startswith("always") and line == "end\n") or \
                (cur[0].startswith("assign") and line.rstrip().endswith(";")):
            items.append("".join(cur))
            cur = []
    if cur or sorted("".join(items).splitlines()) != sorted(
            x for x in comb.splitlines() if x.strip()):
        raise ValueError("LiteX's combinational section not in the form expected")
    return (head + "// Combinatorial Logic\n" + rule + "\n" + "\n".join(sorted(items))
            + "\n//" + "-" * 78 + "\n// Synchronous Logic\n" + tail)


def _pack(info, addr: int, raw: int) -> int:
    from ..sim.axi.scoreboard import pack_write
    return pack_write(info, addr, raw)


def host_session(comm, spec, schedule: dict, n_sweeps: int) -> dict:
    """What a host does through ``comm`` (a LiteX ``CommUART`` with the SoC's ``csr.csv``):
    each burst of ``schedule`` (``{sweep: [(first, raw values), ...]}``) pushed beat by beat
    at its sweep, ``STEP`` to each such sweep and to ``n_sweeps``, every spike beat popped
    until that many sweeps have ended (TLAST); then ``CLAMP_FLAGS``, the face's counters
    (one burst read) and the peripheral's ``write_lost``/``spike_lost``. Returns
    ``{"packets", "id", "clamp_flags", "counters", "write_lost", "spike_lost",
    "transactions"}`` (packets: per sweep ``[(tdata, marker), ...]``)."""
    from ..hdl.lib.regmap import COUNTERS, register
    regs, info = comm.regs, spec.info
    wb = comm.mems.cuneate.base
    assert wb == CUNEATE_BASE, f"csr.csv puts the block at {wb:#x}"
    level = regs.cuneate_spike_level
    # spike_level, spike_data, spike_flags: consecutive CSR words, read in one burst
    assert (regs.cuneate_spike_data.addr == level.addr + 4 * level.length
            and regs.cuneate_spike_flags.addr == regs.cuneate_spike_data.addr + 4
            and regs.cuneate_spike_data.length == 1), "spike CSRs not consecutive"
    n_tx = [0]

    def read(addr, length=None):
        n_tx[0] += 1
        return comm.read(addr, length)

    def write(addr, value):
        n_tx[0] += 1
        comm.write(addr, value)

    packets, beats = [], []

    def drain_to(k: int):
        while len(packets) < k:
            n, data, flags = read(level.addr, 3)
            if n == 0:
                continue
            write(regs.cuneate_spike_pop.addr, 1)
            beats.append((data, flags >> 1 & 1))
            if flags & 1:
                packets.append(list(beats))
                beats.clear()

    step = wb + register("STEP").offset
    ident = read(wb + register("ID").offset)
    at = 0
    for k in sorted(schedule):
        if k > at:
            write(step, k - at)
            drain_to(k)
            at = k
        for first, raw in schedule[k]:
            for i, v in enumerate(raw):
                regs.cuneate_write_data.write(_pack(info, first + i, v))
                n_tx[0] += 1
                write(regs.cuneate_write_push.addr, 3 if i == len(raw) - 1 else 1)
    if n_sweeps > at:
        write(step, n_sweeps - at)
        drain_to(n_sweeps)
    clamps = read(wb + register("CLAMP_FLAGS").offset)
    values = read(wb + register(COUNTERS[0][0].upper()).offset, len(COUNTERS))
    return {"packets": packets, "id": ident, "clamp_flags": clamps,
            "counters": {name: v for (name, _), v in zip(COUNTERS, values)},
            "write_lost": read(regs.cuneate_write_lost.addr),
            "spike_lost": read(regs.cuneate_spike_lost.addr), "transactions": n_tx[0]}


def _host_thread(files: dict, soc: dict, spec, schedule, n_sweeps, result: dict,
                 wait_s: float):
    """Wait for the bench's terminal name, run :func:`host_session` on it, then write the
    bench's stop file (also on failure: the error goes into ``result``)."""
    from litex.tools.remote.comm_uart import CommUART
    comm = None
    try:
        end = time.monotonic() + wait_s
        while not files["pty"].exists():
            if time.monotonic() > end or files["stop"].exists():
                raise TimeoutError("the bench never opened its terminal")
            time.sleep(0.05)
        comm = CommUART(files["pty"].read_text().strip(), 115200,
                        csr_csv=str(soc["csr_csv"]))
        comm.open()
        result.update(host_session(comm, spec, schedule, n_sweeps))
    except BaseException as exc:         # noqa: BLE001 - reported to the caller
        result["error"] = f"{type(exc).__name__}: {exc}"
    finally:
        if comm is not None:
            comm.close()
        files["stop"].write_text("done\n")


def run_sim(simulator: str, spec, schedule: dict, n_sweeps: int, build_dir: Path,
            wall_s: float = 120.0) -> dict:
    """The SoC of ``spec`` on ``simulator`` with :func:`host_session` on LiteX's
    ``CommUART``: the session's result, with ``"bench"`` (the bench's report: bytes each
    way, cycles, bits pumped) and ``"sources"``. Raises ``RuntimeError`` naming the host's
    error."""
    from ..sim.engines.cocotb import run_cocotb
    build_dir = Path(build_dir).resolve()
    soc = write_sim_soc(spec, build_dir / "soc", lowered=simulator == "icarus")
    for init in (build_dir / "soc" / "gateware").glob("*.init"):
        shutil.copy(init, build_dir)     # $readmemh's relative names: the simulator's cwd
    files = {"pty": build_dir / "pty.name", "stop": build_dir / "host.done"}
    for f in files.values():
        f.unlink(missing_ok=True)
    result: dict = {}
    host = threading.Thread(target=_host_thread, daemon=True,
                            args=(files, soc, spec, schedule, n_sweeps, result, wall_s))
    host.start()
    cfg = {"clock_ns": 10, "clocks_per_bit": CLOCKS_PER_BIT,
           "pty_file": str(files["pty"]), "stop_file": str(files["stop"]), "wall_s": wall_s}
    try:
        run = run_cocotb(simulator, soc["sources"], SIM_TOP, "cuneate.boards.litex_bench",
                         build_dir, config=cfg, testcase="bridge")
    finally:
        files["stop"].write_text("done\n")   # a bench that failed early: the host ends
        host.join(timeout=30)
    if "error" in result:
        raise RuntimeError(f"{simulator}: the host failed: {result['error']}")
    return result | {"bench": run.report, "sources": [str(s) for s in soc["sources"]]}
