"""The host link's gateware behind a serial port: :class:`AmaranthSerial` runs
:class:`~cuneate.hdl.link.LinkedTop` in the Amaranth simulator and drives its ``rx`` pin and
reads its ``tx`` pin bit by bit (8N1 at the link's ``clocks_per_bit``), so that the host's
:class:`~cuneate.sim.host.uart.UartTransport` (and the host driver over it) talks to the very
gateware a board runs, cycle by cycle.

The simulation advances only when the host waits for an answer: ``read`` runs it a block of
cycles at a time until bytes arrive. ``silent`` tells the transport that nothing more will come
(nothing left to send, and no byte from the device for longer than a frame and a batch take),
so a lost answer is reported at once instead of after a wall-clock timeout. Line faults can be
injected in both directions (``corrupt`` on the device's bytes, ``corrupt_host`` on the
host's), as with :class:`~cuneate.sim.host.uart.ModelSerial`.

The ``board`` engine: :class:`VerilatorSerial` is the same far end compiled by Verilator (the
board top behind ``serial_harness.cpp``, in its own process), :class:`BoardTransport` the host
stack over it, or over a programmed board's serial port (``cuneate stream``).
:class:`~cuneate.sim.link.pty.PtyBoard` serves a :class:`VerilatorSerial` on a pseudo-terminal.
"""

from __future__ import annotations

import struct
import subprocess
import time
from collections import deque
from pathlib import Path

from amaranth.sim import Simulator

from ...hdl.flow.verilog import verilog_text
from ...hdl.lib.payload import payload_spec
from ...hdl.link import LinkConfig, LinkedTop
from ...hdl.link.config import sweep_cycles
from ...hdl.link.codec import MAX_FRAME
from ..engines.verilator_fast import compile_harness, quit_harness
from ..host.transport import SimulatedSerial
from ..host.uart import UartTransport

__all__ = ["AmaranthSerial", "VerilatorSerial", "BoardTransport", "board_link",
           "BOARD_CLOCKS_PER_BIT"]

CLOCK_S = 1e-6


class AmaranthSerial(SimulatedSerial):
    """A serial port whose far end is the link gateware in the Amaranth simulator.

    Parameters
    ----------
    lcfg
        The link configuration (:class:`~cuneate.hdl.link.LinkConfig`).
    corrupt, corrupt_host
        Called on each chunk of bytes the device sends / the host writes (line faults).
    block_cycles
        Cycles simulated per step while the host waits.
    """

    def __init__(self, lcfg, corrupt=None, corrupt_host=None, block_cycles: int = 256):
        self.lcfg = lcfg
        self.corrupt, self.corrupt_host = corrupt, corrupt_host
        self.block_cycles = int(block_cycles)
        cpb = lcfg.clocks_per_bit
        #: cycles without a byte from the device after which it has nothing more to say
        self.quiet_cycles = 2 * (MAX_FRAME + 2) * 10 * cpb + \
            2 * lcfg.batch_sweeps * lcfg.info.cycles_per_tick
        self.dut = dut = LinkedTop(lcfg)
        self._out: deque[int] = deque()          # bytes still to drive onto rx
        self._rx = bytearray()                   # bytes decoded from tx, not yet read
        self._chunk = bytearray()                # bytes from tx since the last read
        self._cycle = 0
        self._quiet = 0
        self.is_open = True
        self.sim = sim = Simulator(dut)
        sim.add_clock(CLOCK_S)

        # plain loops of ticks (not ``tick().repeat``): the background testbenches are
        # dropped suspended when the port is, which an async generator would complain about
        async def ticks(ctx, n):
            for _ in range(n):
                await ctx.tick()

        async def host(ctx):
            ctx.set(dut.rx, 1)
            while True:
                if not self._out:
                    await ticks(ctx, 8)
                    continue
                b = self._out.popleft()
                for bit in [0] + [(b >> i) & 1 for i in range(8)] + [1]:
                    ctx.set(dut.rx, bit)
                    await ticks(ctx, cpb)

        async def device(ctx):
            while True:
                await ctx.negedge(dut.tx)
                await ticks(ctx, cpb // 2)
                b = 0
                for i in range(8):
                    await ticks(ctx, cpb)
                    b |= ctx.get(dut.tx) << i
                await ticks(ctx, cpb)
                if ctx.get(dut.tx):                      # a stop bit; else a broken byte
                    self._chunk.append(b)

        sim.add_testbench(host, background=True)
        sim.add_testbench(device, background=True)

    def _advance(self, cycles: int):
        self._cycle += cycles
        self.sim.run_until(self._cycle * CLOCK_S)
        if self._chunk:
            data, self._chunk = bytes(self._chunk), bytearray()
            self._rx += self.corrupt(data) if self.corrupt is not None else data
            self._quiet = 0
        else:
            self._quiet += cycles

    # -- the serial port ---------------------------------------------------------------------
    def write(self, data: bytes) -> int:
        n = len(data)
        if self.corrupt_host is not None:
            data = self.corrupt_host(bytes(data))
        self._out.extend(bytes(data))
        self._quiet = 0
        return n

    def _fill(self) -> None:
        self._advance(self.block_cycles)

    @property
    def silent(self) -> bool:
        """Nothing left to send and no byte from the device for :attr:`quiet_cycles`."""
        return not self._rx and not self._out and self._quiet >= self.quiet_cycles

    @property
    def cycles(self) -> int:
        """Clock cycles simulated so far."""
        return self._cycle

    def close(self):
        self.is_open = False


# --------------------------------------------------------------------------- the board engine

#: Clocks per UART bit on the ``board`` engine's simulated line (both ends: the gateware's
#: receiver and transmitter and the harness's line model): bit-time acceleration, so that a
#: scene's bytes cost simulated cycles in proportion to the sweeps, not the real baud's.
BOARD_CLOCKS_PER_BIT = 4
SERIAL_HARNESS = Path(__file__).with_name("serial_harness.cpp")
BOARD_TOP = "board"


def board_link(block, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT, **spec) -> LinkConfig:
    """The link of the ``board`` engine for ``block`` (a payload spec, or a block
    configuration with the spec's options: an array's ``n_cores``, a ``fanout`` in front):
    one spike batch a millisecond, as on the boards, and ``clocks_per_bit`` on the line. The
    block keeps its arithmetic and sweep rate; its clock is raised where needed (a block
    sized at one update a clock, as the other engines run it) so that a sweep holds the
    block's work and the idle cycles a board keeps between sweeps
    (:data:`~cuneate.hdl.link.config.LINK_IDLE_CYCLES`), and the largest spike frame leaves
    within a batch's sweeps (batches never pile up behind the transmitter). With the link's
    external tick the clock changes nothing but the time: the engines' results depend on
    the update rate alone."""
    p = payload_spec(block, **spec)
    info = p.info
    batch = max(1, int(round(info.update_hz / 1000)))
    frame_cycles = (MAX_FRAME + 2) * 10 * clocks_per_bit
    need = max(-(-frame_cycles // batch), sweep_cycles(info))
    clock = info.update_hz * need if info.cycles_per_tick < need else None
    return LinkConfig(p.retimed(clock), clocks_per_bit=clocks_per_bit, batch_sweeps=batch)


class VerilatorSerial(SimulatedSerial):
    """A serial port whose far end is the board top of ``lcfg``
    (:class:`~cuneate.hdl.link.LinkedTop`: the link and the block behind it, the PLL and I/O
    buffers replaced by a clock and wires) compiled by Verilator with ``serial_harness.cpp``: the harness drives ``rx`` with the
    host's bytes and decodes ``tx``, 8N1 at the link's ``clocks_per_bit``, in its own process;
    the simulation advances only while the host waits for an answer (as
    :class:`AmaranthSerial`, whose line faults, ``silent`` and ``cycles`` it shares).

    Parameters
    ----------
    lcfg
        The link configuration.
    corrupt, corrupt_host
        Called on each chunk of bytes the device sends / the host writes (line faults).
    build_root
        Where compiled harnesses are cached (default: the ``verilator-fast`` cache).
    """

    def __init__(self, lcfg: LinkConfig, corrupt=None, corrupt_host=None,
                 build_root: Path | None = None):
        self.lcfg = lcfg
        self.corrupt, self.corrupt_host = corrupt, corrupt_host
        cpb = lcfg.clocks_per_bit
        self.quiet_cycles = 2 * (MAX_FRAME + 2) * 10 * cpb + \
            2 * lcfg.batch_sweeps * lcfg.info.cycles_per_tick
        #: idle cycles on ``tx`` after a byte that end a read (a frame's bytes come back to
        #: back: three byte times of silence mean the frame is whole)
        self.gap_cycles = 30 * cpb
        self.max_cycles = max(self.quiet_cycles, 1 << 20)
        t0 = time.perf_counter()
        self.exe = compile_harness(verilog_text(LinkedTop(lcfg), BOARD_TOP), BOARD_TOP,
                                   SERIAL_HARNESS, {"CUNEATE_CLOCKS_PER_BIT": cpb},
                                   build_root, prefix="Vboard")
        self.build_s = time.perf_counter() - t0
        self._proc = subprocess.Popen([str(self.exe)], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE)
        self._out = bytearray()                  # bytes to send with the next request
        self._rx = bytearray()
        self._cycle = 0
        self._quiet = False
        self.sim_s = 0.0
        self.totals: dict = {}
        self.is_open = True

    def write(self, data: bytes) -> int:
        n = len(data)
        if self.corrupt_host is not None:
            data = self.corrupt_host(bytes(data))
        self._out += bytes(data)
        self._quiet = False
        return n

    def _request(self, payload: bytes) -> tuple[bytes, int, int]:
        p = self._proc
        t0 = time.perf_counter()
        try:
            p.stdin.write(b"R" + struct.pack("<I", len(payload)) + payload +
                          struct.pack("<QQQ", self.gap_cycles, self.quiet_cycles,
                                      self.max_cycles))
            p.stdin.flush()
        except BrokenPipeError:
            raise RuntimeError(f"the board harness ended (exit {p.wait()})") from None
        head = p.stdout.read(4)
        if len(head) != 4:
            raise RuntimeError(f"the board harness ended (exit {p.wait()})")
        (m,) = struct.unpack("<I", head)
        data = p.stdout.read(m)
        cycle, why = struct.unpack("<QB", p.stdout.read(9))
        self.sim_s += time.perf_counter() - t0
        return data, cycle, why

    def _fill(self) -> None:
        if not self.is_open:
            return
        payload, self._out = bytes(self._out), bytearray()
        data, self._cycle, why = self._request(payload)
        if data:
            self._rx += self.corrupt(data) if self.corrupt is not None else data
        self._quiet = why == 1

    def advance(self) -> None:
        """Send the bytes written so far and run the simulation until a frame comes back,
        the device falls quiet (:attr:`silent`) or ``max_cycles`` have run: what a read of an
        empty buffer does, for a caller that relays the device's bytes itself
        (:class:`~cuneate.sim.link.pty.PtyBoard`)."""
        self._fill()

    @property
    def silent(self) -> bool:
        """Nothing left to send and no byte from the device for :attr:`quiet_cycles`."""
        return not self._rx and not self._out and self._quiet

    @property
    def cycles(self) -> int:
        """Clock cycles simulated so far."""
        return self._cycle

    def kill(self) -> None:
        """End the harness at once (a simulation request in flight fails: the harness
        ended); :meth:`close` still releases the port."""
        if self._proc.poll() is None:
            self._proc.kill()

    def close(self):
        if not self.is_open:
            return
        self.is_open = False
        self.totals = quit_harness(self._proc)


class BoardTransport(UartTransport):
    """The ``board`` engine: the real host stack (:class:`~cuneate.sim.host.uart.UartTransport`:
    COBS/CRC frames, sequence numbers, lockstep, every counter) over :class:`VerilatorSerial`,
    the board top (:class:`~cuneate.hdl.link.LinkedTop`) of the block it is opened with (any
    block with a payload, :func:`~cuneate.hdl.lib.payload.payload_spec`: an Izhikevich core,
    a LIF core, the afferent -> cuneate network, whose spike ids ``n_afferents + j`` are
    cuneate neuron ``j``), sized by :func:`board_link`; given ``fanout``
    (:class:`~cuneate.hdl.fanout.FanoutConfig`) the channel fan-out stands in front of the
    block and the host's writes are the channels' raw samples,
    ``write_currents(tick, first, samples)``; or, given ``port``, over that serial port to a
    programmed board (``cuneate stream``: the same driver path, the same report).

    Line faults (``corrupt``, ``corrupt_host``) reach the simulated line; :meth:`figures` gives
    what the run cost: simulated cycles, wall time, bytes and frames each way. The compiled
    board top is kept in the compiled-harness cache
    (:func:`~cuneate.sim.engines.verilator_fast.default_build_root`, one build per design,
    shared by parallel runs under a lock); ``build_dir`` is taken for the transports' common
    signature.

    Parameters
    ----------
    port
        ``None``: the board top in Verilator; else a pyserial URL or device path, or an open
        serial-like object (see :class:`~cuneate.sim.host.uart.UartTransport`), with a board
        behind it programmed for the core.
    baud
        Line rate when ``port`` is a URL.
    timeout_s
        How long the host waits for the device (the simulated board answers as fast as
        Verilator runs it: the default allows minutes).
    """

    name = "board"

    def __init__(self, build_dir: Path | None = None, progress=None, waves=None,
                 clocks_per_bit: int = BOARD_CLOCKS_PER_BIT, corrupt=None, corrupt_host=None,
                 timeout_s: float = 600.0, port=None, baud: int = 3_000_000,
                 ahead: bool = True, fanout=None):
        if waves:
            raise ValueError("engine 'board' writes no waveforms (those that do: amaranth, "
                             "icarus, verilator)")
        if port is not None and (corrupt is not None or corrupt_host is not None):
            raise ValueError("line faults are injected on the simulated line only (no port)")
        self.clocks_per_bit = clocks_per_bit
        self._faults = (corrupt, corrupt_host)
        self.progress = progress
        self.device_port = port
        self.ahead = ahead
        self.fanout = fanout
        self.serial = None
        super().__init__(port, baud=baud, timeout_s=timeout_s)

    def open(self, config) -> None:
        spec = payload_spec(config, fanout=self.fanout)
        if self.device_port is not None:        # a programmed board: the block it was built for
            self.lcfg = None
            # the receive FIFO of a board's link (LinkConfig's default, as the boards build it)
            self.ahead_bytes = 512 if self.ahead else None
            self._t0 = time.perf_counter()
            self.spike_ids = spec.info.n_spike_ids
            super().open(spec.info.writes())
            return
        self.lcfg = board_link(spec, self.clocks_per_bit)
        self.batch_sweeps = self.lcfg.batch_sweeps
        self.spike_ids = self.lcfg.n_spike_ids
        self.ahead_bytes = self.lcfg.rx_fifo_depth if self.ahead else None
        self.serial = VerilatorSerial(self.lcfg, *self._faults)
        self._port_arg = self.serial
        self._t0 = time.perf_counter()
        super().open(self.lcfg.info.writes())

    def run(self, n_ticks: int) -> None:
        super().run(n_ticks)
        if self.progress is not None:
            self.progress(self._ticks)

    @property
    def sim_s(self) -> float | None:
        """Wall time of the simulation proper (the harness answering the host); ``None`` for
        a board on a port."""
        return None if self.serial is None else self.serial.sim_s

    def figures(self) -> dict:
        """Wall time and the line's bytes and frames each way; on the simulated line also the
        cycles, their rate, the harness's build time and the line's framing errors; on a port,
        its name and rate."""
        wall = round(time.perf_counter() - self._t0, 3)
        frames = {"frames_to_device": self._counts["frames_sent"],
                  "frames_from_device": self._counts["frames_received"]}
        s = self.serial
        if s is None:
            return {"port": self.port_name, "baud": self.baud, "wall_s": wall,
                    "bytes_to_device": self.bytes_sent,
                    "bytes_from_device": self.bytes_received, **frames}
        line = s.totals or {}
        core = self.lcfg.info
        nominal = self._ticks * core.cycles_per_tick
        return {"cycles": s.cycles, "wall_s": wall,
                # the device's cycles against its sweeps at the tick rate (1.0: it never
                # waited for the host), and the line rate it had, relative to its clock
                "cycles_per_sweep_rate": round(s.cycles / nominal, 4) if nominal else None,
                "baud_equivalent": round(core.cycles_per_tick * core.update_hz
                                         / self.lcfg.clocks_per_bit),
                "ahead": self.ahead_bytes is not None,
                "cycles_per_s": round(s.cycles / s.sim_s) if s.sim_s else 0,
                "build_s": round(s.build_s, 3), "clocks_per_bit": self.lcfg.clocks_per_bit,
                "bytes_to_device": line.get("bytes_to_device"),
                "bytes_from_device": line.get("bytes_from_device"),
                "framing_errors": line.get("framing_errors"), **frames}
