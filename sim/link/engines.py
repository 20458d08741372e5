"""The host link's gateware behind a serial port: :class:`AmaranthSerial` runs
:class:`~cuneate.hdl.link.LinkedCore` in the Amaranth simulator and drives its ``rx`` pin and
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

import json
import struct
import subprocess
import time
from collections import deque
from pathlib import Path

from amaranth.sim import Simulator

from ...hdl.izhikevich import IzhikevichConfig
from ...hdl.link import LinkConfig, LinkedCore
from ...hdl.link.config import LINK_IDLE_CYCLES
from ...hdl.link.codec import MAX_FRAME
from ..host.transport import SimulatedSerial
from ..host.uart import UartTransport

__all__ = ["AmaranthSerial", "VerilatorSerial", "BoardTransport", "board_link_config",
           "board_network_config", "board_fanout_config", "board_fanout_network_config",
           "board_lif_config", "BOARD_CLOCKS_PER_BIT"]

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
            2 * lcfg.batch_sweeps * lcfg.core.cycles_per_tick
        self.dut = dut = LinkedCore(lcfg)
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


def _board_batch_and_cycles(update_hz: float, busy_cycles: int,
                            clocks_per_bit: int) -> tuple[int, int]:
    """One spike batch a millisecond (sweeps a batch) and the fewest cycles a sweep for a block
    busy ``busy_cycles`` a sweep: the idle cycles a board keeps between sweeps
    (:data:`~cuneate.hdl.link.config.LINK_IDLE_CYCLES`) and the largest spike frame leaving
    within a batch's sweeps (batches never pile up behind the transmitter)."""
    batch = max(1, int(round(update_hz / 1000)))
    frame_cycles = (MAX_FRAME + 2) * 10 * clocks_per_bit
    return batch, max(-(-frame_cycles // batch), busy_cycles + LINK_IDLE_CYCLES)


def board_link_config(core: IzhikevichConfig, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT,
                      n_cores: int = 1) -> LinkConfig:
    """The link of the ``board`` engine for the core ``core`` (its arithmetic and sweep rate;
    the link drives its ticks) and ``clocks_per_bit`` on the line, with one spike batch a
    millisecond as on the boards (:func:`cuneate.boards.sizing.size_core`). The clock is the
    core's, raised where needed (a core at one update a clock, as the other engines run it)
    to keep the idle cycles a board keeps between sweeps
    (:data:`~cuneate.hdl.link.config.LINK_IDLE_CYCLES`) and to let the largest spike frame
    leave within a batch's sweeps (batches never pile up behind the transmitter). With the
    link's external tick the clock changes nothing but the time: the engines' results depend
    on the update rate alone."""
    batch, min_cycles = _board_batch_and_cycles(core.update_hz, core.n_neurons, clocks_per_bit)
    kw = core.to_kwargs(tick_source="external")
    if core.clock_hz / core.update_hz < min_cycles:
        kw["clock_hz"] = core.update_hz * min_cycles
    ext = IzhikevichConfig.from_kwargs(kw)
    return LinkConfig(ext, clocks_per_bit=clocks_per_bit, batch_sweeps=batch, n_cores=n_cores)


def _board_network(ncfg, clocks_per_bit: int, extra_cycles: int = 0):
    """The network of ``ncfg`` on the ``board`` engine and its batch: external tick, the clock
    raised where needed so a sweep holds the network's tick work (its ``cycles_needed``, the
    report's settling and the draining of one spike per afferent and cuneate neuron),
    ``extra_cycles`` of a block in front of it and the link's idle cycles, and lets the
    largest spike frame leave within a batch (:func:`_board_batch_and_cycles`)."""
    from ...hdl.network import REPORT_SETTLE, NetworkConfig
    busy = ncfg.cycles_needed + REPORT_SETTLE + ncfg.n_afferents + ncfg.n_targets + extra_cycles
    batch, min_cycles = _board_batch_and_cycles(ncfg.update_hz, busy, clocks_per_bit)
    kw = ncfg.to_kwargs() | {"tick_source": "external"}
    if ncfg.clock_hz / ncfg.update_hz < min_cycles:
        kw["clock_hz"] = ncfg.update_hz * min_cycles
    return NetworkConfig(**kw), batch


def board_network_config(ncfg, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT):
    """The network and its link on the ``board`` engine
    (:class:`~cuneate.hdl.link.LinkedNetwork`): ``(network config, link config)``.

    As :func:`board_link_config`, for the afferent -> cuneate network ``ncfg``
    (:class:`~cuneate.hdl.network.NetworkConfig`): external tick, one spike batch a
    millisecond, the clock raised where needed to keep a board's idle cycles beyond a tick's
    work (the network's ``cycles_needed``, the report's settling and the draining of one
    spike per afferent and cuneate neuron) and to let the largest spike frame leave within a
    batch. The link writes the afferents' currents (the network's afferent core gives the
    formats) and carries the spike ids of both populations."""
    net, batch = _board_network(ncfg, clocks_per_bit)
    lcfg = LinkConfig(net.core, clocks_per_bit=clocks_per_bit, batch_sweeps=batch,
                      spike_ids=net.n_afferents + net.n_targets)
    return net, lcfg


def board_fanout_network_config(ncfg, fanout, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT):
    """The network fed by the channel fan-out ``fanout``
    (:class:`~cuneate.hdl.fanout.FanoutConfig`) and its link on the ``board`` engine (board top
    :class:`~cuneate.hdl.link.LinkedFanoutNetwork`): ``(network config, link config)``.

    As :func:`board_network_config`, with a tick's cycles covering a frame's channel writes
    and a fan-out run too, before the network's tick work and the link's idle cycles (a
    sample's frame lands between two ticks: :class:`~cuneate.hdl.link.LinkConfig` refuses a
    sweep too short for the writes and the run). The host writes the channels' raw samples
    (``n_written`` = the fan-out's channels, in its sample format); spike ids cover both
    populations. A fan-out of fewer afferents than the network's is padded with idle ones
    (:meth:`~cuneate.hdl.fanout.FanoutConfig.padded`)."""
    fanout = fanout.padded(ncfg.n_afferents)
    net, batch = _board_network(ncfg, clocks_per_bit,
                                fanout.n_channels + fanout.cycles_per_run)
    lcfg = LinkConfig(net.core, clocks_per_bit=clocks_per_bit, batch_sweeps=batch,
                      spike_ids=net.n_afferents + net.n_targets, fanout=fanout)
    return net, lcfg


def board_fanout_config(core: IzhikevichConfig, fanout,
                        clocks_per_bit: int = BOARD_CLOCKS_PER_BIT) -> LinkConfig:
    """The link of the ``board`` engine for a core fed by the channel fan-out ``fanout``
    (:class:`~cuneate.hdl.fanout.FanoutConfig`; board top
    :class:`~cuneate.hdl.link.LinkedFanoutCore`): as :func:`board_link_config`, with a sweep's
    cycles covering a frame's channel writes and a fan-out run too (a sample's frame can land
    before any sweep; :class:`~cuneate.hdl.link.LinkConfig` refuses less). A core padded to
    its fewest neurons gets a fan-out padded with idle afferents
    (:meth:`~cuneate.hdl.fanout.FanoutConfig.padded`)."""
    fanout = fanout.padded(core.n_neurons)
    busy = core.n_neurons + fanout.n_channels + fanout.cycles_per_run
    batch, min_cycles = _board_batch_and_cycles(core.update_hz, busy, clocks_per_bit)
    kw = core.to_kwargs(tick_source="external")
    if core.clock_hz / core.update_hz < min_cycles:
        kw["clock_hz"] = core.update_hz * min_cycles
    ext = IzhikevichConfig.from_kwargs(kw)
    return LinkConfig(ext, clocks_per_bit=clocks_per_bit, batch_sweeps=batch, fanout=fanout)


def board_lif_config(core, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT) -> LinkConfig:
    """The link of the ``board`` engine for the LIF core ``core``
    (:class:`~cuneate.hdl.lif.LifConfig`; board top :class:`~cuneate.hdl.link.LinkedLif`).

    As :func:`board_link_config`: the core's arithmetic and update rate, external tick, one
    spike batch a millisecond, the clock raised where needed to keep a board's idle cycles
    beyond a sweep of ``n_neurons`` and to let the largest spike frame leave within a batch.
    The link's current format is the core's."""
    from ...hdl.lif import LifConfig
    batch, min_cycles = _board_batch_and_cycles(core.update_hz, core.n_neurons, clocks_per_bit)
    kw = core.to_kwargs(tick_source="external")
    if core.clock_hz / core.update_hz < min_cycles:
        kw["clock_hz"] = core.update_hz * min_cycles
    return LinkConfig(LifConfig.from_kwargs(kw), clocks_per_bit=clocks_per_bit,
                      batch_sweeps=batch)


class VerilatorSerial(SimulatedSerial):
    """A serial port whose far end is the board top (``top``, by default the
    :class:`~cuneate.hdl.link.LinkedCore` of ``lcfg``; or a
    :class:`~cuneate.hdl.link.LinkedNetwork`, :class:`~cuneate.hdl.link.LinkedLif`,
    :class:`~cuneate.hdl.link.LinkedFanoutCore` or :class:`~cuneate.hdl.link
    .LinkedFanoutNetwork`: the link and the blocks behind it, the PLL and I/O buffers replaced
    by a clock and wires)
    compiled by Verilator with ``serial_harness.cpp``: the harness drives ``rx`` with the
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
    top
        The board top to compile (an elaboratable with the pins ``rx`` and ``tx``, served by
        ``lcfg``); default ``LinkedCore(lcfg)``.
    """

    def __init__(self, lcfg: LinkConfig, corrupt=None, corrupt_host=None,
                 build_root: Path | None = None, top=None):
        from ...hdl.flow.verilog import verilog_text
        from ..engines.verilator_fast import compile_harness
        self.lcfg = lcfg
        self.corrupt, self.corrupt_host = corrupt, corrupt_host
        cpb = lcfg.clocks_per_bit
        self.quiet_cycles = 2 * (MAX_FRAME + 2) * 10 * cpb + \
            2 * lcfg.batch_sweeps * lcfg.core.cycles_per_tick
        #: idle cycles on ``tx`` after a byte that end a read (a frame's bytes come back to
        #: back: three byte times of silence mean the frame is whole)
        self.gap_cycles = 30 * cpb
        self.max_cycles = max(self.quiet_cycles, 1 << 20)
        t0 = time.perf_counter()
        top = LinkedCore(lcfg) if top is None else top
        self.exe = compile_harness(verilog_text(top, BOARD_TOP), BOARD_TOP,
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
        p = self._proc
        try:
            p.stdin.write(b"Q")
            p.stdin.flush()
            line = p.stdout.readline()
            self.totals = json.loads(line) if line.strip() else {}
        except (OSError, ValueError):
            self.totals = {}
        finally:
            try:
                p.stdin.close()
            except OSError:                  # the harness already gone (killed, crashed)
                pass
            p.wait()


class BoardTransport(UartTransport):
    """The ``board`` engine: the real host stack (:class:`~cuneate.sim.host.uart.UartTransport`:
    COBS/CRC frames, sequence numbers, lockstep, every counter) over :class:`VerilatorSerial`,
    the board top sized to what it is opened with: an Izhikevich core (the driver's; board top
    :class:`~cuneate.hdl.link.LinkedCore`, :func:`board_link_config`) or an afferent -> cuneate
    network (:class:`~cuneate.hdl.network.NetworkConfig`; board top
    :class:`~cuneate.hdl.link.LinkedNetwork`, :func:`board_network_config`: currents are
    written to the afferents, spike ids ``n_afferents + j`` are cuneate neuron ``j``), a LIF
    core (:class:`~cuneate.hdl.lif.LifConfig`; board top :class:`~cuneate.hdl.link.LinkedLif`,
    :func:`board_lif_config`); or, given ``fanout`` (:class:`~cuneate.hdl.fanout.FanoutConfig`),
    a core fed by the channel fan-out (board top :class:`~cuneate.hdl.link.LinkedFanoutCore`,
    :func:`board_fanout_config`) or a network whose afferents it feeds (board top
    :class:`~cuneate.hdl.link.LinkedFanoutNetwork`, :func:`board_fanout_network_config`:
    spike ids ``n_afferents + j`` are cuneate neuron ``j``), the host's writes being the
    channels' raw samples, ``write_currents(tick, first, samples)``; or,
    given ``port``, over that serial port to a programmed board (``cuneate stream``: the same
    driver path, the same report).

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
        if self.device_port is not None:        # a programmed board: the core it was built for
            self.lcfg = None
            # the receive FIFO of a board's link (LinkConfig's default, as the boards build it)
            self.ahead_bytes = 512 if self.ahead else None
            self._t0 = time.perf_counter()
            from ...hdl.network import NetworkConfig
            if isinstance(config, NetworkConfig):   # both populations' ids; the afferents'
                self.spike_ids = config.n_afferents + config.n_targets   # core is written
                config = config.core
            super().open(config if self.fanout is None else self.fanout.written(config))
            return
        from ...hdl.lif import LifConfig
        from ...hdl.link import LinkedLif, LinkedNetwork
        from ...hdl.network import NetworkConfig
        written = None
        if self.fanout is not None and not isinstance(config, (IzhikevichConfig,
                                                               NetworkConfig)):
            raise ValueError(f"the channel fan-out feeds an Izhikevich core or the afferents "
                             f"of a network, not a {type(config).__name__}")
        if isinstance(config, NetworkConfig) and self.fanout is not None:
            from ...hdl.link import LinkedFanoutNetwork
            self.network, self.lcfg = board_fanout_network_config(config, self.fanout,
                                                                  self.clocks_per_bit)
            top = LinkedFanoutNetwork(self.network, self.lcfg)
            written = self.lcfg.fanout.written(self.lcfg.core)
        elif isinstance(config, NetworkConfig):
            self.network, self.lcfg = board_network_config(config, self.clocks_per_bit)
            top = LinkedNetwork(self.network, self.lcfg)
        elif self.fanout is not None:
            from ...hdl.link import LinkedFanoutCore
            self.network = None
            self.lcfg = board_fanout_config(config, self.fanout, self.clocks_per_bit)
            top = LinkedFanoutCore(self.lcfg)
            written = self.fanout.written(self.lcfg.core)
        elif isinstance(config, LifConfig):
            self.network, self.lcfg = None, board_lif_config(config, self.clocks_per_bit)
            top = LinkedLif(self.lcfg)
        else:
            self.network, self.lcfg = None, board_link_config(config, self.clocks_per_bit)
            top = LinkedCore(self.lcfg)
        self.batch_sweeps = self.lcfg.batch_sweeps
        self.spike_ids = self.lcfg.n_spike_ids
        self.ahead_bytes = self.lcfg.rx_fifo_depth if self.ahead else None
        self.serial = VerilatorSerial(self.lcfg, *self._faults, top=top)
        self._port_arg = self.serial
        self._t0 = time.perf_counter()
        super().open(written or self.lcfg.core)

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
        core = self.lcfg.core
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
