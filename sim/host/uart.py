"""Host side of the UART link: :class:`UartTransport` behind the driver's transport interface.

The transport talks to a :class:`~cuneate.hdl.link.LinkedTop` on a board through pyserial
(any ``serial_for_url`` URL: a device path, ``socket://host:port``, ``loop://``), to the
protocol model (:class:`ModelSerial`, the simulated serial path used by tests and for dry
runs), or to the gateware in the Amaranth simulator
(:class:`~cuneate.sim.link.engines.AmaranthSerial`).

Lockstep: the core is stopped between calls. ``write_currents`` queues writes by sweep;
``run(n)`` sends a ``STEP`` to each sweep at which writes are due, waits for the spike batch
that ends there (so the device is known to stand exactly between the sweeps), sends the writes
for that sweep, and a final ``STEP`` to the end. A frame lost on the way to the device
therefore never leaves a write waiting for a sweep that never comes: a lost ``STEP`` is seen at
once (its batch does not arrive) and a lost ``WRITE`` in the device's counters. ``collect``
reads spike frames until they cover every sweep run.

Loss is never silent: a device sequence gap, a gap in the ticks of spike batches, dropped
spikes, a spike for a neuron the core does not have, or a damaged or malformed frame from the
device raises :class:`~cuneate.sim.host.transport.TransportError` where it is seen; damaged
and malformed frames are also counted (``rx_*_errors``). :meth:`UartTransport.counters` reads
the device's counters (``READ_COUNTERS``) and reports the driver's counter contract
(:data:`~cuneate.sim.host.transport.COUNTERS`): ``frames_lost`` counts the host's frames the
device did not accept and the device's frames the host refused, so that the driver fails a run
that lost a frame, naming the counters that saw it. When the device does not answer in
``timeout_s``, the transport asks for its counters before giving up and names what they show.
:meth:`UartTransport.check` fails on any host or device error counter. A damaged frame is never
accepted: every frame is checked (COBS, size, CRC-32, version, length, layout) before anything
in it is used.
"""

from __future__ import annotations

import time

import numpy as np

from ...hdl.link.codec import (COUNTER_NAMES, FRAME_ERRORS, MAX_FRAME, MIN_FRAME, MSG_COUNTERS,
                               MSG_SPIKES, OP_CLEAR_COUNTERS, OP_READ_COUNTERS, OP_STEP, OP_STOP,
                               SPIKE_HEADER, FrameDecoder, FrameError, control_message,
                               current_bytes, encode_frame, parse_counters, parse_spikes,
                               write_message)
from ...hdl.link.twin import LinkModel
from .transport import (SimulatedSerial, SpikeBatch, Transport, TransportError, queue_write,
                        sweep_count)

__all__ = ["UartTransport", "ModelSerial", "DEVICE_ERRORS", "HOST_ERRORS", "link_budget",
           "measured_budget", "run_budget", "format_budget", "BUDGET_BAUDS"]

#: Device counters that mean something was lost or refused.
DEVICE_ERRORS = tuple(n for n in COUNTER_NAMES if n != "frames_ok")
#: Host counters of frames from the device refused as damaged or malformed, by kind
#: (``rx_length_errors`` includes intact frames whose payload does not fit their type).
HOST_ERRORS = tuple(f"rx_{k}_errors" for k in FRAME_ERRORS)


class _NoAnswer(TransportError):
    """The device did not answer in time (while the transport was asking why)."""


class ModelSerial(SimulatedSerial):
    """A serial port whose far end is :class:`LinkModel` (the device's protocol on the twin):
    what is written is fed to the model, which runs each step at once; ``read`` returns its
    answers. ``corrupt``, if given, is called on every chunk the device sends and
    ``corrupt_host`` on every chunk the host writes (line faults, e.g. from
    :mod:`cuneate.sim.link.faults`)."""

    def __init__(self, lcfg, corrupt=None, corrupt_host=None):
        self.model = LinkModel(lcfg)
        self.corrupt = corrupt
        self.corrupt_host = corrupt_host
        self._rx = bytearray()
        self.is_open = True

    def write(self, data: bytes) -> int:
        n = len(data)
        if self.corrupt_host is not None:
            data = self.corrupt_host(bytes(data))
        out = self.model.feed(bytes(data))
        self.model.advance(self.model.steps)
        out += self.model.feed(b"")
        if self.corrupt is not None:
            out = self.corrupt(out)
        self._rx += out
        return n

    @property
    def silent(self) -> bool:
        """Nothing more will come until the host writes (the model answers at once)."""
        return not self._rx

    def close(self):
        self.is_open = False


class UartTransport(Transport):
    """The board link as a :class:`~cuneate.sim.host.transport.Transport`.

    Parameters
    ----------
    port
        A pyserial URL or device path, or an open serial-like object (``write``, ``read``,
        ``in_waiting``, ``close``), e.g. :class:`ModelSerial`.
    baud
        Line rate for a URL (the board top's rate, 3 Mbaud by default).
    batch_sweeps
        Sweeps per spike batch of the gateware (``LinkConfig.batch_sweeps``).
    timeout_s
        How long ``collect``/``counters`` wait for the device before raising.
    ahead_bytes
        ``None`` (lockstep): a sweep's writes are sent once the device is known to stand at it
        (its spike batches cover every sweep before). Else the host sends writes ahead, the
        STEPs between them in order: the device's decoder holds each write until its sweep
        (``WAIT``), so nothing lands early and the device never waits for the host while
        frames are queued; the host keeps at most ``ahead_bytes`` of frames the device may not
        yet have taken (its receive FIFO's depth, ``LinkConfig.rx_fifo_depth``), learning
        what it took from the spike batches.
    spike_ids
        The neuron ids the device's spikes may carry (``LinkConfig.n_spike_ids``; default the
        core's ``n_neurons``, the neurons written): a network behind the link reports its
        cuneate neurons after its afferents.
    """

    name = "uart"

    def __init__(self, port, baud: int = 3_000_000, batch_sweeps: int = 16,
                 timeout_s: float = 5.0, ahead_bytes: int | None = None,
                 spike_ids: int | None = None):
        self._port_arg, self.baud, self.batch_sweeps = port, baud, batch_sweeps
        self.timeout_s = timeout_s
        if ahead_bytes is not None and ahead_bytes < MAX_FRAME + 2:
            raise ValueError(f"ahead_bytes must hold a whole frame ({MAX_FRAME + 2} bytes), "
                             f"not {ahead_bytes}")
        self.ahead_bytes = ahead_bytes
        self.spike_ids = spike_ids
        self.port = None
        self.cfg = None

    # -- connection --------------------------------------------------------------------------
    def open(self, config) -> None:
        self.cfg = config
        if isinstance(self._port_arg, str):
            self.port = self.open_port(self._port_arg, self.baud)
        else:
            self.port = self._port_arg
        #: bytes written to the line and read from it since ``open``
        self.bytes_sent = self.bytes_received = 0
        self._dec = FrameDecoder()
        self._seq = 0
        self._dev_seq = None
        self._ticks = 0                 # sweeps requested so far
        self._covered = 0               # sweeps covered by spike frames received
        self._queued: dict[int, list[tuple[int, np.ndarray]]] = {}
        self._spikes: list[SpikeBatch] = []
        self._counts = {"frames_sent": 0, "write_frames_sent": 0, "writes_sent": 0,
                        "currents_sent": 0, "frames_received": 0, "spikes_received": 0,
                        "rx_seq_gaps": 0}
        self._last_counters = None
        self._device_tick = 0
        self._inflight: list[tuple[int, int]] = []   # (sweep that frees it, wire bytes)
        self._frontier = 0              # the latest sweep a sent write waits for
        self._diagnosing = False
        self._since_clear = 0
        self._send(control_message(0, OP_STOP))
        self._send(control_message(0, OP_CLEAR_COUNTERS))
        self._since_clear = 0           # frames sent after CLEAR_COUNTERS (the device counts)

    @staticmethod
    def open_port(url: str, baud: int = 3_000_000):
        """The pyserial port ``url`` (a device path or any ``serial_for_url`` URL) opened
        at ``baud`` the way the transport reads it (short read timeouts), or
        :class:`TransportError` naming it (``uart: cannot open URL: why``)."""
        import serial
        try:
            return serial.serial_for_url(url, baudrate=baud, timeout=0.05)
        except (serial.SerialException, ValueError) as exc:
            raise TransportError(f"uart: cannot open {url}: {exc}") from None

    def close(self) -> None:
        if self.port is not None:
            self.port.close()
            self.port = None

    # -- frames ------------------------------------------------------------------------------
    def _send(self, msg, write_tick: int | None = None):
        msg = type(msg)(msg.type, self._seq, msg.tick, msg.payload)
        self._seq = (self._seq + 1) & 0xFF
        wire = encode_frame(msg)
        if self.ahead_bytes is not None:
            self._make_room(len(wire), write_tick)
        try:
            self.port.write(wire)
        except OSError as exc:              # pyserial's SerialException is an OSError
            raise self._line_failed(exc) from None
        self.bytes_sent += len(wire)
        self._counts["frames_sent"] += 1
        self._since_clear += 1

    def _make_room(self, nbytes: int, write_tick: int | None) -> None:
        """Ahead mode: wait until the frames the device may not have taken, and this one,
        fit ``ahead_bytes``. The device takes frames in order and a write when it reaches the
        write's sweep, so a frame is taken once the batches cover its sweep."""
        if write_tick is not None:
            self._frontier = max(self._frontier, write_tick)
        while not self._diagnosing:         # READ_COUNTERS, asking why, goes at once
            self._inflight = [(t, n) for t, n in self._inflight if t > self._covered]
            if sum(n for _, n in self._inflight) + nbytes <= self.ahead_bytes:
                break
            start = self._covered
            self._receive(lambda: self._covered > start,
                          f"the spikes of sweep {start} (the device's receive buffer holds "
                          f"{sum(n for _, n in self._inflight)} bytes not yet taken)")
        self._inflight.append((self._frontier, nbytes))

    def _receive(self, until, what: str):
        """Read frames until ``until()`` is true; raise on a frame damaged or refused while
        waiting (it is counted first), or after ``timeout_s`` without an answer (naming what
        the device's counters show, when it still answers)."""
        deadline = time.monotonic() + self.timeout_s
        while not until():
            try:
                data = self.port.read(max(1, getattr(self.port, "in_waiting", 0) or 1))
            except OSError as exc:
                raise self._line_failed(exc) from None
            self.bytes_received += len(data)
            if not data:
                if time.monotonic() > deadline or getattr(self.port, "silent", False):
                    self._timeout(what)
                continue
            before = dict(self._dec.errors)
            msgs = self._dec.feed(data)
            new = {k: v - before[k] for k, v in self._dec.errors.items() if v != before[k]}
            if new:
                raise TransportError(
                    f"uart: damaged frames from the device while waiting for {what}: " +
                    ", ".join(f"{k}={v}" for k, v in new.items()))
            for msg in msgs:
                self._accept(msg)

    def _line_failed(self, exc: OSError) -> TransportError:
        """The error for a line that fails under the transport (a device unplugged, a
        simulated board whose far end ended)."""
        return TransportError(f"uart: the line to {self.port_name} failed: {exc}")

    @property
    def port_name(self) -> str:
        """The port's URL or device path (or, for a serial-like object, its ``port`` or
        class name)."""
        if isinstance(self._port_arg, str):
            return self._port_arg
        port = self.port if self.port is not None else self._port_arg
        return str(getattr(port, "port", None) or type(port).__name__)

    def _timeout(self, what: str):
        msg = f"uart: no answer from the device while waiting for {what} ({self.timeout_s:g} s)"
        if self._diagnosing:
            raise _NoAnswer(msg)
        self._diagnosing = True
        try:
            dev = self._read_device_counters()
        except _NoAnswer:
            raise TransportError(f"{msg}; it does not answer READ_COUNTERS either (no device, "
                                 f"a dead line, or a device stalled)") from None
        except TransportError as exc:          # what its answer showed on the way
            raise TransportError(f"{msg}; then {exc}") from None
        finally:
            self._diagnosing = False
        bad = {k: dev[k] for k in DEVICE_ERRORS if dev[k]}
        if bad:
            raise TransportError(f"{msg}; the device counted " +
                                 ", ".join(f"{k}={v}" for k, v in bad.items()) +
                                 " (a frame was lost or damaged on the way to it)")
        raise TransportError(f"{msg}; the device counted no error (it stands at sweep "
                             f"{self._device_tick})")

    def _accept(self, msg):
        self._counts["frames_received"] += 1
        if self._dev_seq is not None and msg.seq != (self._dev_seq + 1) & 0xFF:
            self._counts["rx_seq_gaps"] += (msg.seq - self._dev_seq - 1) & 0xFF
            raise TransportError(f"uart: device frame sequence gap: expected "
                                 f"{(self._dev_seq + 1) & 0xFF}, got {msg.seq} (frames from "
                                 f"the device lost)")
        self._dev_seq = msg.seq
        try:
            self._use(msg)
        except FrameError as exc:
            self._dec.errors["length"] += 1
            raise TransportError(f"uart: malformed frame from the device: {exc}") from None

    def _use(self, msg):
        if msg.type == MSG_SPIKES:
            dropped, sweeps, spikes = parse_spikes(msg)
            N = self.cfg.n_neurons if self.spike_ids is None else self.spike_ids
            for tick, n in spikes:
                if n >= N or not msg.tick <= tick < msg.tick + sweeps:
                    raise FrameError(f"a spike of neuron {n} at sweep {tick} in the batch of "
                                     f"sweeps {msg.tick}..{msg.tick + sweeps - 1}: the device "
                                     f"has neuron ids 0..{N - 1}")
            if msg.tick != self._covered:
                raise TransportError(f"uart: spike batches lost: expected the batch of sweep "
                                     f"{self._covered}, got sweep {msg.tick}")
            if dropped:
                raise TransportError(f"uart: {dropped} spikes dropped in the batch of sweeps "
                                     f"{msg.tick}..{msg.tick + sweeps - 1} (batch buffer full)")
            self._covered += sweeps
            t = np.array([s[0] for s in spikes], np.int64)
            n = np.array([s[1] for s in spikes], np.int64)
            self._spikes.append(SpikeBatch(t, n))
            self._counts["spikes_received"] += len(spikes)
        elif msg.type == MSG_COUNTERS:
            self._last_counters = parse_counters(msg)
            self._device_tick = msg.tick
        else:
            raise FrameError(f"unexpected frame type {msg.type:#x}")

    # -- transport interface -----------------------------------------------------------------
    def write_currents(self, tick: int, first: int, raw) -> None:
        queue_write(self._queued, "uart", tick, self._ticks, first, raw, self.cfg.n_neurons)

    def _flush_writes(self, tick: int):
        """Send the writes for ``tick`` once the device is known to stand at it (its spike
        batches cover every sweep before it)."""
        if tick not in self._queued:
            return
        if self.ahead_bytes is None:
            self._receive(lambda: self._covered >= tick,
                          f"the spikes of sweeps {self._covered}..{tick - 1} (the device must "
                          f"stand at sweep {tick} before its writes are sent)")
        width = self.cfg.I.width
        per_frame = (MAX_FRAME - MIN_FRAME - 2) // current_bytes(width)
        for first, raw in self._queued.pop(tick):
            for i in range(0, raw.size, per_frame):
                self._send(write_message(0, tick, first + i, raw[i:i + per_frame], width),
                           write_tick=tick)
                self._counts["write_frames_sent"] += 1
                self._counts["currents_sent"] += min(per_frame, raw.size - i)
            self._counts["writes_sent"] += 1

    def run(self, n_ticks: int) -> None:
        n_ticks = sweep_count(n_ticks, "uart")
        end = self._ticks + n_ticks
        self._flush_writes(self._ticks)
        at = self._ticks
        for t in sorted(k for k in self._queued if at < k < end):
            self._send(control_message(0, OP_STEP, t - at))
            self._flush_writes(t)
            at = t
        if end > at:
            self._send(control_message(0, OP_STEP, end - at))
        self._ticks = end

    def collect(self) -> SpikeBatch:
        self._receive(lambda: self._covered >= self._ticks,
                      f"the spikes of sweeps {self._covered}..{self._ticks - 1}")
        out = SpikeBatch.concat(self._spikes)
        self._spikes = []
        return out

    def _read_device_counters(self) -> dict:
        self._last_counters = None
        self._send(control_message(0, OP_READ_COUNTERS))
        self._receive(lambda: self._last_counters is not None, "the device counters")
        return self._last_counters

    def counters(self) -> dict[str, int]:
        """The device's counters (``device_*``), the host's (frames sent and received, damaged
        frames refused: ``rx_*_errors``) and the driver's contract
        (:data:`~cuneate.sim.host.transport.COUNTERS`): ``writes`` is the writes sent when no
        frame was lost (a lower bound otherwise), ``spikes_counted`` the spikes delivered plus
        those the device dropped, ``frames_lost`` the host's frames the device did not accept
        plus the device's frames the host refused or missed."""
        dev = self._read_device_counters()
        c = self._counts
        host = {f"rx_{k}_errors": v for k, v in self._dec.errors.items()}
        lost_out = max(self._since_clear - dev["frames_ok"], 0)
        lost_in = sum(host.values()) + c["rx_seq_gaps"]
        contract = {
            "writes": c["writes_sent"] - min(lost_out, c["writes_sent"]),
            "spikes": c["spikes_received"],
            "spikes_counted": c["spikes_received"] + dev["spikes_dropped"],
            "frames_lost": lost_out + lost_in,
            "overflow": dev["spikes_dropped"] + dev["batches_dropped"],
            "overrun": dev["tick_overruns"],
            "late_writes": dev["late_writes"],
        }
        return dict(c, **host, **{f"device_{k}": v for k, v in dev.items()}, **contract)

    def loss_detail(self, counters: dict) -> str:
        """The device's and the host's error counters that are not zero."""
        dev = [f"device {k}={counters[f'device_{k}']}" for k in DEVICE_ERRORS
               if counters.get(f"device_{k}")]
        host = [f"host {k}={counters[k]}" for k in HOST_ERRORS + ("rx_seq_gaps",)
                if counters.get(k)]
        lost_out = self._since_clear - counters.get("device_frames_ok", self._since_clear)
        sent = [f"{lost_out} of {self._since_clear} frames sent not accepted by the device"] \
            if lost_out > 0 else []
        return ", ".join(sent + dev + host)

    def check(self) -> dict[str, int]:
        """Counters, raising :class:`TransportError` naming every error counted: frames from the
        device the host refused (:data:`HOST_ERRORS`) and the device's own error counters."""
        c = self.counters()
        bad = {k: c[k] for k in HOST_ERRORS if c[k]}
        if bad:
            raise TransportError("uart: the host refused damaged frames from the device: " +
                                 ", ".join(f"{k}={v}" for k, v in bad.items()))
        bad = {k: c[f"device_{k}"] for k in DEVICE_ERRORS if c[f"device_{k}"]}
        if bad:
            raise TransportError("uart: the device counted errors: " +
                                 ", ".join(f"{k}={v}" for k, v in bad.items()))
        return c


# --------------------------------------------------------------------------- the link budget

#: Line rates the budget is stated at: the classic default and the rate the boards run (the
#: ULX3S's FTDI FT231X runs 3 Mbaud).
BUDGET_BAUDS = (115_200, 3_000_000)
#: Bits on the line per byte (8N1: start, eight data bits, stop).
BITS_PER_BYTE = 10


def _wire_bytes(payload_bytes: int) -> int:
    """Bytes on the line for a frame of ``payload_bytes``: header, payload and CRC (at most
    :data:`~cuneate.hdl.link.codec.MAX_FRAME`, one COBS block), its COBS code byte and the
    delimiter."""
    return MIN_FRAME + payload_bytes + 2


def link_budget(n_neurons: int, current_width: int, sample_hz: float, update_hz: float,
                spikes_per_s: float, words_per_sample: float | None = None,
                bauds=BUDGET_BAUDS, batch_sweeps: int | None = None) -> dict:
    """The line bandwidth streaming a scene takes, each way, against the line rates ``bauds``.

    The host's protocol (:class:`UartTransport`): for each sample (``sample_hz``) one
    ``STEP`` to the sample's sweep and the sample's currents in ``WRITE`` frames of at most
    :data:`~cuneate.hdl.link.LinkConfig.max_currents` values; ``words_per_sample`` currents a
    sample (default ``n_neurons``: every afferent's current changes every sample, the worst
    case). The device: a ``SPIKES`` frame for every batch of ``batch_sweeps`` sweeps (default:
    a millisecond's), and one more at every step's end that is not a batch's, and three bytes a
    spike (``spikes_per_s``). The line is full duplex: each direction has ``baud / 10`` bytes a
    second. Returns the bytes a second each way and per sweep, the spikes of a batch at that
    rate (``spikes_per_batch``, against the frame's capacity), and per rate the load of each
    direction and whether both fit the line (``real_time``: a bandwidth bound; the lockstep
    host also waits for each step's batch before its next writes, see docs/boards.md).
    """
    cb = current_bytes(current_width)
    per_frame = (MAX_FRAME - MIN_FRAME - 2) // cb
    words = float(n_neurons if words_per_sample is None else words_per_sample)
    full, rest = divmod(int(np.ceil(words)), per_frame)
    write = full * _wire_bytes(2 + per_frame * cb) + (_wire_bytes(2 + rest * cb) if rest else 0)
    step = _wire_bytes(5)
    bytes_in = sample_hz * (step + write)
    B = batch_sweeps or max(1, int(round(update_hz / 1000)))
    R = update_hz / sample_hz                      # sweeps a step (one step a sample)
    batches = float(sample_hz * np.ceil(R / B))    # frames the steps' batches take
    bytes_out = batches * _wire_bytes(SPIKE_HEADER) + 3.0 * spikes_per_s
    rows = []
    for baud in bauds:
        cap = baud / BITS_PER_BYTE
        rows.append({"baud": baud, "in_load": bytes_in / cap, "out_load": bytes_out / cap,
                     "real_time": bool(bytes_in <= cap and bytes_out <= cap)})
    return {"neurons": int(n_neurons), "words_per_sample": words, "sample_hz": sample_hz,
            "spikes_per_s": float(spikes_per_s), "batch_sweeps": B,
            "spikes_per_batch": spikes_per_s * min(B, R) / update_hz, "in_bytes_per_s": bytes_in,
            "out_bytes_per_s": bytes_out, "in_bytes_per_sweep": bytes_in / update_hz,
            "out_bytes_per_sweep": bytes_out / update_hz, "rows": rows}


def measured_budget(bytes_in: int, bytes_out: int, seconds: float,
                    bauds=BUDGET_BAUDS) -> dict:
    """The load a run's measured line traffic (``bytes_in`` to the device, ``bytes_out``
    from it, over ``seconds`` of simulated time) puts on each line rate."""
    bin_s, bout_s = bytes_in / seconds, bytes_out / seconds
    rows = [{"baud": b, "in_load": bin_s * BITS_PER_BYTE / b,
             "out_load": bout_s * BITS_PER_BYTE / b,
             "real_time": max(bin_s, bout_s) * BITS_PER_BYTE <= b} for b in bauds]
    return {"in_bytes_per_s": bin_s, "out_bytes_per_s": bout_s, "seconds": seconds,
            "rows": rows}


def run_budget(counters: dict, seconds: float, n_neurons: int, current_width: int,
               sample_hz: float, update_hz: float, n_spikes: int) -> dict:
    """A board engine run's budget in real time: ``measured`` (the bytes its line carried,
    ``counters`` ``line_bytes_*``, per second of scene time) and ``worst_case`` (every
    current every sample, at the run's spike rate), each at :data:`BUDGET_BAUDS`."""
    return {"measured": measured_budget(counters["line_bytes_to_device"],
                                        counters["line_bytes_from_device"], seconds),
            "worst_case": link_budget(n_neurons, current_width, sample_hz, update_hz,
                                      n_spikes / seconds)}


def format_budget(budget: dict) -> list[str]:
    """One line per line rate: bytes a second each way and the load."""
    out = []
    for r in budget["rows"]:
        rate = f"{r['baud'] / 1e6:g} Mbaud" if r["baud"] >= 1e6 else f"{r['baud']:g} baud"
        out.append(f"{rate}: to the device {budget['in_bytes_per_s']:,.0f} "
                   f"B/s ({100 * r['in_load']:.0f} %), from it "
                   f"{budget['out_bytes_per_s']:,.0f} B/s ({100 * r['out_load']:.0f} %): "
                   f"{'fits the line' if r['real_time'] else 'does NOT fit the line'}")
    return out
