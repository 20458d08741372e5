"""The engine interface: how one engine runs one block.

Each block defines its engine class (``IzhikevichEngine``, ``LifEngine``, ``CoincidenceEngine``,
``NetworkEngine``, ``FanoutEngine`` and, for the fan-out in front of another block,
``FanoutFront``, ``NirEngine`` in ``cuneate.sim.<block>.engines``), a
:class:`BlockEngine` whose ``run`` takes the block's configuration and inputs and returns one
:class:`~cuneate.sim.engines.run.EngineRun`. An engine implements the block by subclassing it
and registering the subclass (:func:`~cuneate.sim.engines.registry.implements`); the registry
builds it with a run's options (:func:`~cuneate.sim.engines.registry.engine_for`):

``build(...)``
    the configuration the engine simulates for the block's configuration (padded to the
    fewest neurons, external tick, a board's link around it, ...); the block's default serves
    most engines.
``run(config, inputs)``
    the block's inputs on the engine: one :class:`~cuneate.sim.engines.run.EngineRun`.
``transport()``
    for an engine that reaches the block through a host transport
    (:class:`~cuneate.sim.host.transport.Transport`: the host driver's path, a board's link,
    a bus), that transport, to be opened for the block's configuration; :meth:`stream`
    drives a write schedule through it with every counter checked.
"""

from __future__ import annotations

from pathlib import Path

from ..host.transport import SpikeBatch, Transport, check_counters
from .cocotb import run_engine_bench

__all__ = ["BlockEngine", "WAVE_ENGINES"]

#: The engines that write waveforms (their simulators dump the RTL's signals).
WAVE_ENGINES = ("amaranth", "icarus", "verilator")


class BlockEngine:
    """One engine's implementation of one block.

    ``name``: the engine (a row of :data:`~cuneate.sim.engines.registry.ENGINES`);
    ``build_dir``: where a simulator builds (a scratch directory when ``None``); ``progress``:
    called with the ticks done; ``waves``: a :class:`~cuneate.sim.engines.waves.Waves` window,
    refused by engines that write none (:attr:`writes_waves`).
    """

    #: the block this class runs (set by the block's engine class)
    block: str = ""
    #: whether the engine dumps a waveform window
    writes_waves: bool = False

    def __init__(self, name: str, build_dir: Path | None = None, progress=None, waves=None):
        if waves and not self.writes_waves:
            raise ValueError(f"engine {name!r} writes no waveforms (those that do: "
                             f"{', '.join(WAVE_ENGINES)})")
        self.name = name
        self.build_dir = Path(build_dir) if build_dir is not None else None
        self.progress = progress
        self.waves = waves

    def run(self, config, *inputs):
        """The block's inputs on this engine: an :class:`~cuneate.sim.engines.run.EngineRun`
        (each block's engine class states its inputs)."""
        raise NotImplementedError

    def engine_bench(self, verilog_of, toplevel: str, config: dict) -> dict:
        """The report of the ``engine`` test of the block's cocotb bench on this engine's
        simulator, ``verilog_of(lowered)`` its Verilog (Icarus: the yosys-lowered netlist)."""
        return run_engine_bench(self.name, verilog_of, toplevel, self.block, config,
                                self.build_dir)

    def transport(self) -> Transport:
        """The engine's host transport, not yet opened; refused by an engine without one."""
        raise ValueError(f"engine {self.name!r} has no transport for the {self.block} block")

    def stream(self, config, writes: dict, n_ticks: int,
               transport: Transport | None = None) -> tuple[SpikeBatch, dict]:
        """Drive ``writes`` (``{tick: [(first, raw values), ...]}``) and ``n_ticks`` ticks
        through ``transport`` (by default :meth:`transport`) opened for ``config``; every
        counter of the transport contract checked
        (:func:`~cuneate.sim.host.transport.check_counters`). Returns the spikes and the
        counters."""
        tr = self.transport() if transport is None else transport
        try:
            tr.open(config)
            for k in sorted(writes):
                for first, raw in writes[k]:
                    tr.write_currents(k, first, raw)
            tr.run(n_ticks)
            got = tr.collect()
            counters = self.checked_counters(tr)
            check_counters(tr, counters, sum(map(len, writes.values())), len(got))
        finally:
            tr.close()
        return got, self.closed(tr, counters)

    def checked_counters(self, transport: Transport) -> dict:
        """The transport's counters, after any check of its own (a link's device errors)."""
        return transport.counters()

    def closed(self, transport: Transport, counters: dict) -> dict:
        """The run's counters once the transport is closed (what it adds then: a line's
        totals)."""
        return counters
