"""The host side of the AXI face (:class:`AxiTransport`, the ``axi`` engine): any block behind
:class:`~cuneate.hdl.axi.AxiTop`, compiled by Verilator with ``axi_harness.cpp`` (the bus
transactions in C++, no Python per cycle, in its own process), driven through the host
driver's transport interface and counter contract
(:mod:`cuneate.sim.host.transport`), as the ``board`` engine drives the UART face.

Lockstep, as the UART transport: the device is stopped between calls. ``run(n)`` writes
``STEP`` for the sweeps up to the next sweep with writes, waits for their TLAST beats (the
device then stands between the sweeps: ``SWEEP`` names the next), streams each of that sweep's
writes as one burst on ``s_axis`` (the face's write rule puts them in effect exactly from
it), and goes on; the spike beats are decoded as they come (one packet per sweep, a marker
for an empty sweep). Loss is never silent: a sweep's beats carrying another sweep's number,
an id the block does not have, a malformed marker, a bus error response, or any device
counter that disagrees with what the host sent and received raises
:class:`~cuneate.sim.host.transport.TransportError`.
"""

from __future__ import annotations

import struct
import subprocess
import time
from pathlib import Path

import numpy as np

from ...hdl.axi import AxiTop, face_cycles
from ...hdl.flow.verilog import verilog_text
from ...hdl.lib.payload import payload_spec
from ...hdl.lib.regmap import COUNTERS, MAGIC, register, stream_format
from ..engines.verilator_fast import compile_harness, quit_harness
from ..host.transport import SpikeBatch, Transport, TransportError, queue_write, sweep_count

__all__ = ["AxiTransport", "axi_spec", "AXI_HARNESS"]

AXI_HARNESS = Path(__file__).with_name("axi_harness.cpp")
TOP = "axi"
#: cycles one 'S' request may run before the transport asks why
STEP_PATIENCE = 1 << 26


def axi_spec(block, **spec):
    """The payload the ``axi`` engine builds for ``block`` (a payload spec or a block
    configuration with the spec's options): its tick external, its clock raised where
    needed so that a sweep behind the face (:func:`~cuneate.hdl.axi.face_cycles`) fits a tick
    (the arithmetic and the sweep rate unchanged)."""
    p = payload_spec(block, **spec)
    need = face_cycles(p.info)
    clock = p.info.update_hz * need if p.info.cycles_per_tick < need else None
    return p.retimed(clock)


class _Harness:
    """The compiled AXI top in its process (the protocol of ``axi_harness.cpp``)."""

    def __init__(self, top: AxiTop, build_root: Path | None):
        field = 8 * stream_format(top.info)["write_field_bytes"]
        t0 = time.perf_counter()
        self.exe = compile_harness(verilog_text(top, TOP), TOP, AXI_HARNESS,
                                   {"CUNEATE_WRITE_FIELD_BITS": field}, build_root,
                                   prefix="Vaxi")
        self.build_s = time.perf_counter() - t0
        self.proc = subprocess.Popen([str(self.exe)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE)
        self.sim_s = 0.0
        self.cycle = 0
        self.totals: dict = {}

    def _ask(self, request: bytes, answer: str):
        p = self.proc
        t0 = time.perf_counter()
        try:
            p.stdin.write(request)
            p.stdin.flush()
            size = struct.calcsize("<" + answer)
            data = p.stdout.read(size)
        except BrokenPipeError:
            data = b""
        if len(data) != size:
            raise TransportError(f"axi: the simulated device ended (exit {p.wait()})")
        self.sim_s += time.perf_counter() - t0
        return struct.unpack("<" + answer, data)

    def burst(self, pairs) -> None:
        body = b"".join(struct.pack("<Ii", int(a), int(v)) for a, v in pairs)
        (self.cycle,) = self._ask(b"W" + struct.pack("<I", len(pairs)) + body, "Q")

    def write(self, addr: int, data: int) -> int:
        resp, self.cycle = self._ask(b"L" + struct.pack("<II", addr, data & 0xFFFFFFFF), "BQ")
        return resp

    def read(self, addr: int) -> tuple[int, int]:
        data, resp, self.cycle = self._ask(b"R" + struct.pack("<I", addr), "IBQ")
        return data, resp

    def sweeps(self, target: int, max_cycles: int):
        """Run until ``target`` sweeps have ended; every beat since the last call
        (``(tdata, tlast, tuser)``) and whether the target was reached."""
        (m,) = self._ask(b"S" + struct.pack("<QQ", target, max_cycles), "I")
        t0 = time.perf_counter()
        raw = self.proc.stdout.read(9 * m)
        tail = self.proc.stdout.read(9)
        if len(raw) != 9 * m or len(tail) != 9:
            raise TransportError(f"axi: the simulated device ended (exit {self.proc.wait()})")
        self.sim_s += time.perf_counter() - t0
        beats = np.frombuffer(raw, dtype=np.dtype([("d", "<u8"), ("f", "u1")]), count=m)
        self.cycle, why = struct.unpack("<QB", tail)
        return beats, why == 0

    def close(self) -> None:
        self.totals = quit_harness(self.proc)


class AxiTransport(Transport):
    """The ``axi`` engine (see the module docstring). ``fanout``
    (:class:`~cuneate.hdl.fanout.FanoutConfig`): the channel fan-out in front of the block,
    the host's writes the channels' raw samples. ``build_dir`` is taken for the transports'
    common signature (the compiled top is kept in the compiled-harness cache,
    :func:`~cuneate.sim.engines.verilator_fast.default_build_root`)."""

    name = "axi"

    def __init__(self, build_dir: Path | None = None, progress=None, waves=None, fanout=None,
                 build_root: Path | None = None):
        if waves:
            raise ValueError("engine 'axi' writes no waveforms (those that do: amaranth, "
                             "icarus, verilator)")
        self.progress, self.fanout, self.build_root = progress, fanout, build_root
        self.dev = None

    # -- connection --------------------------------------------------------------------------
    def open(self, config) -> None:
        self.spec = axi_spec(config, fanout=self.fanout)
        self.info = info = self.spec.info
        self.top = AxiTop(self.spec)
        self.cfg = info.writes()
        sf = stream_format(info)
        self._F, self._marker = 8 * sf["spike_field_bytes"], sf["marker_id"]
        self._t0 = time.perf_counter()
        self.dev = _Harness(self.top, self.build_root)
        ident, _ = self.dev.read(register("ID").offset)
        if ident != MAGIC:
            raise TransportError(f"axi: the device's ID reads {ident:#x}, not {MAGIC:#x}")
        self._reg("CONTROL", 0b0110)             # stop, clear the counters
        self._ticks = 0                          # sweeps requested
        self._covered = 0                        # sweeps whose TLAST came
        self._queued: dict[int, list[tuple[int, np.ndarray]]] = {}
        self._spikes: list[SpikeBatch] = []
        self._cur_t: list[int] = []
        self._cur_n: list[int] = []
        self._counts = {"writes_sent": 0, "values_sent": 0, "bursts_sent": 0,
                        "spikes_received": 0, "sweeps_received": 0, "markers_received": 0,
                        "steps_sent": 0}

    def close(self) -> None:
        if self.dev is not None:
            self.dev.close()

    def _reg(self, name: str, value: int) -> None:
        if self.dev.write(register(name).offset, value):
            raise TransportError(f"axi: the device refused the write of {value} to {name}")

    def _read(self, name: str) -> int:
        value, resp = self.dev.read(register(name).offset)
        if resp:
            raise TransportError(f"axi: the device refused the read of {name}")
        return value

    # -- transport interface -----------------------------------------------------------------
    def write_currents(self, tick: int, first: int, raw) -> None:
        queue_write(self._queued, "axi", tick, self._ticks, first, raw, self.info.n_written,
                    "values", "block")

    def _step_to(self, end: int) -> None:
        """Step the device from the sweep it stands at to ``end`` and take the beats."""
        n = end - self._covered
        if n > 0:
            self._reg("STEP", n)
            self._counts["steps_sent"] += 1
        beats, done = self.dev.sweeps(end, STEP_PATIENCE)
        self._decode(beats)
        if not done or self._covered != end:
            raise TransportError(f"axi: the device ended {self._covered} of {end} sweeps "
                                 f"(status {self._read('STATUS'):#x})")

    def _decode(self, beats) -> None:
        F, sw = self._F, self.info.sweep_width
        data, flags = beats["d"].astype(np.int64), beats["f"]
        ids, sweeps = data & ((1 << F) - 1), (data >> F) & ((1 << sw) - 1)
        last, marker = (flags & 1) != 0, (flags & 2) != 0
        # the sweep each beat belongs to: the sweeps whose TLAST came before it
        k = self._covered + np.concatenate([[0], np.cumsum(last)[:-1]]).astype(np.int64)
        bad = np.flatnonzero(sweeps != (k & ((1 << sw) - 1)))
        if bad.size:
            i = int(bad[0])
            raise TransportError(f"axi: a beat of sweep {int(k[i])} carries sweep number "
                                 f"{int(sweeps[i])} (sweeps lost or beats out of order)")
        if np.any(marker & (~last | (ids != self._marker))):
            raise TransportError("axi: a malformed empty-sweep marker (TUSER without TLAST or "
                                 "its id)")
        spike = ~marker
        if np.any(ids[spike] >= self.info.n_spike_ids):
            raise TransportError(f"axi: a spike id {int(ids[spike].max())} the block does not "
                                 f"have (0..{self.info.n_spike_ids - 1})")
        self._spikes.append(SpikeBatch(k[spike], ids[spike]))
        self._covered += int(last.sum())
        self._counts["spikes_received"] += int(spike.sum())
        self._counts["sweeps_received"] += int(last.sum())
        self._counts["markers_received"] += int(marker.sum())

    def _flush(self, tick: int) -> None:
        for first, raw in self._queued.pop(tick, []):
            self.dev.burst(list(zip(range(first, first + raw.size), raw.tolist())))
            self._counts["writes_sent"] += 1
            self._counts["bursts_sent"] += 1
            self._counts["values_sent"] += int(raw.size)

    def run(self, n_ticks: int) -> None:
        n_ticks = sweep_count(n_ticks, "axi")
        end = self._ticks + n_ticks
        for t in sorted(k for k in self._queued if self._ticks <= k < end):
            self._step_to(t)
            self._flush(t)
        self._step_to(end)
        self._ticks = end
        if self.progress is not None:
            self.progress(self._ticks)

    def collect(self) -> SpikeBatch:
        out = SpikeBatch.concat(self._spikes)
        self._spikes = []
        return out

    def counters(self) -> dict[str, int]:
        """The device's counters (``device_*``, :data:`~cuneate.hdl.lib.regmap.COUNTERS`,
        and its ``STATUS`` flags), the host's, and the driver's contract: ``writes`` the
        writes sent when the device took every value and burst of them (fewer otherwise),
        ``spikes_counted`` the spike beats the device sent, ``frames_lost`` the sweeps whose
        packet did not arrive whole, ``overflow`` the block's sticky spike-loss flag,
        ``overrun`` the ticks lost (the face's and the block's)."""
        dev = {n: self._read(n.upper()) for n, _ in COUNTERS}
        status = self._read("STATUS")
        c = self._counts
        took = (dev["writes"] == c["values_sent"] and dev["bursts"] == c["bursts_sent"]
                and dev["writes_refused"] == 0)
        contract = {
            "writes": c["writes_sent"] if took else min(dev["bursts"], c["writes_sent"] - 1),
            "spikes": c["spikes_received"], "spikes_counted": dev["spikes"],
            "frames_lost": abs(dev["sweeps"] - c["sweeps_received"]),
            "overflow": status >> 6 & 1,
            "overrun": dev["tick_overruns"] + (status >> 7 & 1),
            "late_writes": 0,
        }
        return dict(c, **{f"device_{k}": v for k, v in dev.items()},
                    device_status=status, **contract)

    def loss_detail(self, counters: dict) -> str:
        """The device's counters that disagree with the host's."""
        c = counters
        out = []
        if c.get("device_writes") != c.get("values_sent"):
            out.append(f"device took {c.get('device_writes')} of {c.get('values_sent')} values")
        if c.get("device_writes_refused"):
            out.append(f"device refused {c['device_writes_refused']} values")
        if c.get("device_sweeps") != c.get("sweeps_received"):
            out.append(f"device closed {c.get('device_sweeps')} sweeps, "
                       f"{c.get('sweeps_received')} arrived")
        return ", ".join(out)

    def check(self) -> dict[str, int]:
        """Counters, raising :class:`TransportError` on any loss the contract names."""
        from ..host.transport import check_counters
        c = self.counters()
        check_counters(self, c, c["writes_sent"], c["spikes_received"])
        return c

    @property
    def sim_s(self) -> float | None:
        """Wall time of the simulation proper (the harness answering the host)."""
        return None if self.dev is None else self.dev.sim_s

    def figures(self) -> dict:
        """Wall time, cycles, their rate, the build time and the beats and register accesses
        each way."""
        d = self.dev
        tot = d.totals or {}
        return {"cycles": d.cycle, "wall_s": round(time.perf_counter() - self._t0, 3),
                "cycles_per_s": round(d.cycle / d.sim_s) if d.sim_s else 0,
                "build_s": round(d.build_s, 3), "clock_hz": self.info.clock_hz,
                "cycles_per_tick": self.info.cycles_per_tick,
                "beats_to_device": tot.get("beats_to_device"),
                "beats_from_device": tot.get("beats_from_device"),
                "register_writes": tot.get("register_writes"),
                "register_reads": tot.get("register_reads")}
