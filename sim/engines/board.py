"""The ``board`` engine: a block behind the UART host link, the board top compiled by
Verilator behind a simulated serial line (:class:`~cuneate.sim.link.engines.BoardTransport`,
opened for the block's configuration), driven by the real host stack.

One class per block it runs, each registered with
:func:`~cuneate.sim.engines.registry.implements`: the Izhikevich core (and, in a scene, the
channel fan-out before it or the afferent -> cuneate network behind the link), the LIF core and
the network. Every run writes the block's currents through the transport for their ticks,
steps the ticks, reads the spike frames back and checks every counter of the transport
contract and the device's own error counters (:meth:`BoardEngine.stream`). The link carries
spikes alone: no clamp counts (``None``), no input spikes; each run's counters hold the line's
figures (``board_*``: cycles, bytes and frames each way).
"""

from __future__ import annotations

import numpy as np

from ..izhikevich.engines import IzhikevichEngine
from ..lif.engines import LifEngine, current_runs as lif_writes
from ..network.engines import NetworkEngine, current_runs as network_runs
from .engine import BlockEngine
from .registry import implements
from .run import times_from_pairs

__all__ = ["BoardEngine", "BoardIzhikevich", "BoardLif", "BoardNetwork"]


class BoardEngine(BlockEngine):
    """What the ``board`` engine's blocks share: the transport (``options``: more
    :class:`~cuneate.sim.link.engines.BoardTransport` keywords: ``port``, ``ahead``,
    ``corrupt``, ...), a run through it, the line's figures."""

    def __init__(self, name, build_dir=None, progress=None, waves=None, **options):
        super().__init__(name, build_dir, progress, waves)
        self.options = options

    def transport(self, **more):
        # the board top's simulation (amaranth.sim, the UART host stack) loads when a board
        # runs, not with the registry at `cuneate --help` (measured 20 ms)
        from ..link.engines import BoardTransport
        return BoardTransport(build_dir=self.build_dir, progress=self.progress,
                              waves=self.waves, **self.options, **more)

    def checked_counters(self, transport) -> dict:
        return transport.check()            # the host's refusals and the device's errors

    def closed(self, transport, counters) -> dict:
        return counters | {f"board_{k}": v for k, v in transport.figures().items()}


@implements("izhikevich", "board", speed=1e5)
class BoardIzhikevich(BoardEngine, IzhikevichEngine):
    """The core (:class:`~cuneate.hdl.link.LinkedCore`): the currents written once."""

    layer, fanout = "chip", True

    def sweeps(self, cfg, cur, n_sweeps, n):
        raw = np.asarray(cfg.I.to_raw(cur), dtype=np.int64)
        got, counters = self.stream(cfg, {0: [(0, raw)]}, n_sweeps)
        pairs = zip(got.tick.tolist(), got.neuron.tolist())
        return [t.tolist() for t in times_from_pairs(pairs, n, cfg.dt_ms)], None, None, counters

    def fanout_transport(self, fanout):
        return self.transport(fanout=fanout)


@implements("lif", "board", speed=1e3)
class BoardLif(BoardEngine, LifEngine):
    """The LIF core (:class:`~cuneate.hdl.link.LinkedLif`): the currents that change written
    for their sweep. A program with input spikes is refused."""

    def sweeps(self, cfg, cur, inputs):
        if inputs is not None and np.any(inputs):
            raise ValueError("the board engine's link carries no input spikes: a LIF program "
                             "on it has host currents alone")
        raw = np.asarray(cfg.I.to_raw(cur), dtype=np.int64)
        got, counters = self.stream(cfg, lif_writes(raw), raw.shape[0])
        steps: list[list[int]] = [[] for _ in range(cfg.n_neurons)]
        for k, i in zip(got.tick.tolist(), got.neuron.tolist()):
            steps[i].append(k)
        return steps, {}, {}, counters


@implements("network", "board", speed=1e4)
class BoardNetwork(BoardEngine, NetworkEngine):
    """The network (:class:`~cuneate.hdl.link.LinkedNetwork`): the changed currents written
    in lockstep; spike ids ``n_afferents + j`` are cuneate neuron ``j``."""

    def pairs(self, cfg, writes, n_ticks):
        runs = {k: network_runs(w) for k, w in writes.items()}
        got, counters = self.stream(cfg, runs, n_ticks)
        N = cfg.n_afferents
        pairs = list(zip(got.tick.tolist(), got.neuron.tolist()))
        return ([(t, i) for t, i in pairs if i < N], [(t, i - N) for t, i in pairs if i >= N],
                counters)
