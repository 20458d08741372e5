"""The host transport interface: how the host driver talks to a core.

Every engine (the bit-exact twin, the Amaranth simulator, cocotb on Icarus and Verilator) and
the board's UART link implement :class:`Transport`. The driver writes raw currents with the
sweep (tick) from which they take effect, lets the core run, and collects spikes; counters
report every frame, write and spike so that loss is never silent.

The counter contract
--------------------
Every transport's :meth:`Transport.counters` reports at least the keys of :data:`COUNTERS`,
read from the core or device where it counts them (a board's link answers ``READ_COUNTERS``),
so that one check (:func:`check_counters`) serves every transport: every write applied, every
spike the core produced delivered, no frame lost or damaged, nothing overflowed, overran or
arrived late. A transport may report more (clamp counts, raw device counters) and explain a
loss in its own terms (:meth:`Transport.loss_detail`).

Conventions
-----------
* Ticks count sweeps of the core from 0. A spike produced by the update of sweep ``k`` carries
  ``tick == k``; in milliseconds it is at ``(k + 1) * dt`` (the golden convention).
* A current written for tick ``k`` is used by every update of sweep ``k`` and later, until
  overwritten. Ticks never go backwards: a write for a tick already run is an error, never
  applied late.
* Neuron indices are core-global (population offsets are the driver's business).
"""

from __future__ import annotations

import abc
from dataclasses import dataclass, field

import numpy as np

from ..engines.run import spike_times

__all__ = ["SpikeBatch", "Transport", "TransportError", "queue_write", "sweep_count", "COUNTERS",
           "check_counters", "SimulatedSerial"]

#: The counters every transport reports, and what each counts.
COUNTERS = {
    "writes": "current writes (write_currents calls) the core applied",
    "spikes": "spikes the transport delivered to the host",
    "spikes_counted": "spikes the core produced, by its own count",
    "frames_lost": "frames lost, damaged or refused on the link, both directions (0 without a "
                   "link)",
    "overflow": "spikes lost to a full spike FIFO or batch",
    "overrun": "ticks lost because a sweep was still running",
    "late_writes": "writes refused because their tick had already run",
}


class TransportError(RuntimeError):
    """Something was lost or refused on the way to or from a core (one line naming what and
    where: a sequence gap, a dropped frame, a FIFO overflow, a late write)."""


@dataclass
class SpikeBatch:
    """Spikes as two parallel int64 arrays, sorted by ``(tick, neuron)``."""

    tick: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    neuron: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    def __post_init__(self):
        self.tick = np.asarray(self.tick, dtype=np.int64).ravel()
        self.neuron = np.asarray(self.neuron, dtype=np.int64).ravel()
        if self.tick.shape != self.neuron.shape:
            raise ValueError(f"SpikeBatch: {self.tick.size} ticks but {self.neuron.size} neurons")
        order = np.lexsort((self.neuron, self.tick))
        self.tick, self.neuron = self.tick[order], self.neuron[order]

    def __len__(self) -> int:
        return int(self.tick.size)

    @classmethod
    def concat(cls, batches) -> "SpikeBatch":
        batches = list(batches)
        if not batches:
            return cls()
        return cls(np.concatenate([b.tick for b in batches]),
                   np.concatenate([b.neuron for b in batches]))

    def times_ms(self, dt_ms: float, n_neurons: int, first: int = 0) -> list[np.ndarray]:
        """Spike times per neuron (``first`` .. ``first + n_neurons - 1``) in ms, ``(k+1) dt``."""
        return [spike_times(self.tick[self.neuron == i], dt_ms)
                for i in range(first, first + n_neurons)]


def sweep_count(n_ticks, name: str) -> int:
    """``n_ticks`` as the sweeps a :meth:`Transport.run` advances: an integer >= 0, or a
    :class:`TransportError` naming the transport (a negative or fractional count is never
    run as 0 or truncated)."""
    try:
        n = int(n_ticks)
    except (TypeError, ValueError, OverflowError):
        raise TransportError(f"{name}: cannot run {n_ticks!r} sweeps") from None
    if n != n_ticks or n < 0:
        raise TransportError(f"{name}: cannot run {n_ticks!r} sweeps (a whole number >= 0)")
    return n


def queue_write(queue: dict, name: str, tick: int, ran: int, first: int, raw, n: int,
                what: str = "neurons", owner: str = "core") -> None:
    """Queue the write of ``raw`` to ``first`` .. of ``n`` (``what`` of the ``owner``) for
    sweep ``tick`` in ``queue`` (sweep -> ``[(first, raw)]``), refused when the device has
    already run to sweep ``ran`` past it or when it falls outside."""
    raw = np.asarray(raw, dtype=np.int64).ravel()
    if tick < ran:
        raise TransportError(f"{name}: write for sweep {tick} but the core has run to sweep "
                             f"{ran}: it would be applied late")
    if first < 0 or first + raw.size > n:
        raise TransportError(f"{name}: write of {what} {first}..{first + raw.size - 1} "
                             f"outside the {owner}'s {n}")
    queue.setdefault(int(tick), []).append((int(first), raw))


class Transport(abc.ABC):
    """One way of reaching a core: an engine or a board link."""

    name: str = "transport"

    @abc.abstractmethod
    def open(self, config) -> None:
        """Prepare a core with ``config`` (a core configuration, e.g. ``IzhikevichConfig``)."""

    @abc.abstractmethod
    def write_currents(self, tick: int, first: int, raw: np.ndarray) -> None:
        """Raw currents (integers in the core's current format) for neurons ``first`` ..
        ``first + len(raw) - 1``, in effect from sweep ``tick`` on."""

    @abc.abstractmethod
    def run(self, n_ticks: int) -> None:
        """Let the core advance ``n_ticks`` sweeps (:func:`sweep_count`: refused unless a whole
        number >= 0)."""

    @abc.abstractmethod
    def collect(self) -> SpikeBatch:
        """Every spike of the sweeps run so far and not yet collected."""

    @abc.abstractmethod
    def counters(self) -> dict[str, int]:
        """The counters of :data:`COUNTERS` (and any more: frames, clamp counts)."""

    def loss_detail(self, counters: dict) -> str:
        """What the transport's own counters say about a loss (e.g. a device's CRC errors), for
        the message of :func:`check_counters`; empty when they say nothing more."""
        return ""

    def close(self) -> None:
        """Release the core (simulator process, serial port)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def check_counters(transport: Transport, counters: dict, sent: int, received: int) -> None:
    """Raise :class:`TransportError` naming the first loss ``counters`` show for ``sent``
    current writes and ``received`` spikes (the contract of :data:`COUNTERS`)."""
    name = transport.name
    missing = [k for k in COUNTERS if not isinstance(counters.get(k), (int, np.integer))]
    if missing:
        raise TransportError(f"{name}: the transport does not report {', '.join(missing)} "
                             f"(every transport reports {', '.join(COUNTERS)}); nothing can "
                             f"be checked")
    c = {k: int(counters[k]) for k in COUNTERS}
    detail = transport.loss_detail(counters)
    why = f" ({detail})" if detail else ""
    if c["frames_lost"]:
        raise TransportError(f"{name}: {c['frames_lost']} frame(s) lost or damaged on the "
                             f"link{why}")
    if c["writes"] != sent:
        raise TransportError(f"{name}: {c['writes']} of {sent} current writes were applied by "
                             f"the core ({sent - c['writes']} lost){why}")
    if c["spikes"] != received:
        raise TransportError(f"{name}: the transport counted {c['spikes']} spikes but "
                             f"delivered {received}{why}")
    if c["spikes_counted"] != received:
        raise TransportError(f"{name}: the core counted {c['spikes_counted']} spikes but "
                             f"{received} arrived (spikes lost on the way){why}")
    for k in ("overflow", "overrun", "late_writes"):
        if c[k]:
            raise TransportError(f"{name}: {k}: {c[k]} ({COUNTERS[k]}; nothing may be "
                                 f"lost){why}")


class SimulatedSerial:
    """The receiving half of a simulated serial port, read the way pyserial's is: ``_rx`` holds
    the bytes the device sent and the host has not read; :meth:`_fill` (a hook, nothing by
    default) lets the device run when the host reads an empty buffer."""

    _rx: bytearray

    def _fill(self) -> None:
        """Let the far end produce bytes before a read of an empty buffer."""

    def read(self, size: int = 1) -> bytes:
        if not self._rx:
            self._fill()
        out, self._rx = bytes(self._rx[:size]), self._rx[size:]
        return out

    @property
    def in_waiting(self) -> int:
        return len(self._rx)
