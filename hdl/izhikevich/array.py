"""An array of Izhikevich cores behind one host write port and one spike stream.

:class:`IzhikevichArray` holds ``n_cores`` copies of :class:`~cuneate.hdl.izhikevich.core
.IzhikevichCore` built from one configuration (``n_neurons`` each, one table of parameter sets
and one set of formats), each with its own state, current and set memories and its own
multipliers. Neuron ids are global: neuron ``n`` of core ``k`` is ``k * n_neurons + n``.

**Parameter sets shared or per core.** Every core holds the configuration's table of parameter
sets; which set a neuron runs is its own (the set memory, written by the host like a current).
By default every core starts with the configuration's ``neuron_sets``; ``neuron_sets`` given to
the array (one set index per global id) starts each core with its own slice
(:func:`core_configs`): core 0 all RS afferents, core 1 all FS interneurons, core 2 a mix.
The formats are the table's (proven over every set), so the cores differ only in their set
memories' and state memories' initial words.

* **Host writes** (``i_wr_*``, ``sel_wr_*``) take a global id; the array registers the write
  and hands it to the owning core one cycle later (so a write reaches the core's RAM two cycles
  after it was presented, one more than on a single core).
* **One tick for all cores**: with ``tick_source="external"`` the ``tick`` input goes to every
  core through a register of its own (a sweep starts one cycle after the tick; ``busy`` is
  high from the cycle after the tick, as on a single core); with the internal divider every
  core runs its own, identical, divider from the same reset. The cores sweep in lock step:
  ``busy`` is core 0's; ``sweep_done`` and ``sweep_number`` are core 0's one cycle later,
  beside ``sweep_count``, the sum over the cores, and ``overrun``, ``spike_overflow`` and the
  sticky ``clamp_flags``, ORs over the cores
  (``clamp_clear`` goes to every core).
* **Spike order**: each core queues its spikes in its own FIFO in its update order (sweep, then
  index). Each core's head moves into a register of the array (its global id formed there);
  a four-entry FIFO takes, whenever it has room (one spike a cycle), the lowest-numbered
  core's head register that holds a spike, and the stream is that FIFO's output, with
  ``spike_index`` the global id and ``spike_sweep`` the sweep. So the spikes of
  one core keep their order; between cores the order follows the arbitration (the cores update
  their neurons ``n`` in the same cycle, so with the stream always ready a sweep's spikes leave
  roughly by local index, ties to the lower core). A host needing one global order sorts by
  (``spike_sweep``, ``spike_index``): every spike carries both.

The array's bit-exact model is :class:`~cuneate.hdl.izhikevich.twin.IzhikevichArrayTwin`
(one twin per core). With ``probes=True`` the array also has each core's update ports as its
own outputs (``p<k>_valid``, ``p<k>_index``, ``p<k>_v``, ``p<k>_u``, ``p<k>_spike``,
``p<k>_clamp``, ``p<k>_current``: core ``k``'s ``upd_*``, local index), for the per-cycle
scoreboard of the generated Verilog (:func:`izhikevich_array_verilog`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from amaranth import Cat, Module, Mux, Signal
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..flow.verilog import verilog_text
from .config import CLAMP_KINDS, ConfigError, IzhikevichConfig
from .core import IzhikevichCore

__all__ = ["IzhikevichArray", "izhikevich_array_verilog", "core_configs", "PROBES"]

#: the per-core update ports an array built with ``probes=True`` brings out
PROBES = ("valid", "index", "v", "u", "spike", "clamp", "current")


def core_configs(config: IzhikevichConfig, n_cores: int,
                 neuron_sets=None) -> list[IzhikevichConfig]:
    """The configuration of each core of an array of ``n_cores`` cores of ``config``: ``config``
    itself, or, with ``neuron_sets`` (one parameter-set index per global neuron id, ``n_cores *
    config.n_neurons`` of them), ``config`` with each core's slice as its ``neuron_sets`` (its
    initial states follow its sets unless ``config`` gives them). Refused (:class:`ConfigError`)
    when ``n_cores`` is not an integer >= 1, or ``neuron_sets`` has the wrong length or names a
    set the table does not have."""
    if isinstance(n_cores, bool) or not isinstance(n_cores, int) or n_cores < 1:
        raise ConfigError(f"n_cores must be an integer >= 1, got {n_cores!r}")
    if neuron_sets is None:
        return [config] * n_cores
    N = config.n_neurons
    sets = list(neuron_sets)
    if len(sets) != n_cores * N:
        raise ConfigError(f"neuron_sets must give one set per neuron of the array "
                          f"({n_cores} x {N} = {n_cores * N}), got {len(sets)}")
    n_sets = len(config.param_sets)
    bad = [s for s in sets if isinstance(s, bool) or not isinstance(s, (int, np.integer))
           or not 0 <= s < n_sets]
    if bad:
        raise ConfigError(f"neuron_sets must be set indices 0..{n_sets - 1}, got {bad[0]!r}")
    if all(sets[k * N:(k + 1) * N] == sets[:N] for k in range(1, n_cores)) and \
            list(config.neuron_sets) == sets[:N]:
        return [config] * n_cores
    return [dataclasses.replace(config, neuron_sets=[int(s) for s in sets[k * N:(k + 1) * N]])
            for k in range(n_cores)]


class IzhikevichArray(wiring.Component):
    """``n_cores`` Izhikevich cores of ``config``, one host write port and one spike stream
    over global neuron ids (see the module's documentation for the order and timing).

    Attributes
    ----------
    cores
        The :class:`~cuneate.hdl.izhikevich.core.IzhikevichCore` instances, core ``k`` holding
        the global ids ``k * n_neurons .. (k + 1) * n_neurons - 1`` (their ``upd_*`` ports are
        the per-core update probes).
    """

    def __new__(cls, config: IzhikevichConfig, n_cores: int, probes: bool = False,
                neuron_sets=None):
        # refused (core_configs) before the component exists: a component created and never
        # elaborated would be reported as unused
        configs = core_configs(config, n_cores, neuron_sets)
        self = super().__new__(cls, src_loc_at=1)
        self._core_configs = configs
        return self

    def __init__(self, config: IzhikevichConfig, n_cores: int, probes: bool = False,
                 neuron_sets=None):
        self.cfg, self.n_cores = config, n_cores
        self.cores = [IzhikevichCore(c) for c in self._core_configs]
        total = config.n_neurons * n_cores
        kinds = len(CLAMP_KINDS)
        sig = {
            "i_wr_en": In(1), "i_wr_addr": In(range(total)), "i_wr_data": In(config.I.shape()),
            "sel_wr_en": In(1), "sel_wr_addr": In(range(total)),
            "sel_wr_data": In(config.sel_bits),
            "spike_valid": Out(1), "spike_ready": In(1), "spike_index": Out(range(total)),
            "spike_sweep": Out(config.sweep_number_width), "spike_overflow": Out(1),
            "clamp_flags": Out(kinds), "clamp_clear": In(1),
            "sweep_done": Out(1), "sweep_count": Out(range(total + 1)),
            "sweep_number": Out(config.sweep_number_width), "overrun": Out(1), "busy": Out(1),
        }
        if config.tick_source == "external":
            sig["tick"] = In(1)
        if probes:
            core = self.cores[0]
            for k in range(n_cores):
                sig |= {f"p{k}_{n}": Out(getattr(core, f"upd_{n}").shape()) for n in PROBES}
        super().__init__(sig)
        self.n_total, self.probes = total, probes

    def _route_write(self, m: Module, en, addr, data, port: str):
        """Register a host write and hand it to the core owning the global id ``addr``."""
        N = self.cfg.n_neurons
        r_en, r_addr = Signal(name=f"{port}_en_r"), Signal.like(addr, name=f"{port}_addr_r")
        r_data = Signal.like(data, name=f"{port}_data_r")
        m.d.sync += [r_en.eq(en), r_addr.eq(addr), r_data.eq(data)]
        for k, core in enumerate(self.cores):
            mine = (r_addr >= k * N) & (r_addr < (k + 1) * N)
            m.d.comb += [getattr(core, f"{port}_en").eq(r_en & mine),
                         getattr(core, f"{port}_addr").eq(r_addr - k * N),
                         getattr(core, f"{port}_data").eq(r_data)]

    def elaborate(self, platform):
        m = Module()
        N = self.cfg.n_neurons
        external = self.cfg.tick_source == "external"
        ticks = []
        for k, core in enumerate(self.cores):
            m.submodules[f"core{k}"] = core
            m.d.comb += core.clamp_clear.eq(self.clamp_clear)
            if external:
                # a register per core, so that the tick's fan-out across the device is one
                # net into each core's own register (the sweep starts a cycle later)
                t = Signal(name=f"tick{k}")
                m.d.sync += t.eq(self.tick)
                m.d.comb += core.tick.eq(t)
                ticks.append(t)
        self._route_write(m, self.i_wr_en, self.i_wr_addr, self.i_wr_data, "i_wr")
        self._route_write(m, self.sel_wr_en, self.sel_wr_addr, self.sel_wr_data, "sel_wr")

        # the spike stream in registered steps, so that no path crosses the device through
        # more than one level of logic: each core's head moves into a register of its own
        # (its global id formed there); a four-entry FIFO (one spike a cycle) takes the
        # lowest-numbered core's head whenever it has room (its room a register, not the
        # consumer's ready); the consumer reads the FIFO
        iw, sw = len(self.spike_index), len(self.spike_sweep)
        m.submodules.spike_out = out = SyncFIFOBuffered(width=iw + sw, depth=4)
        take = out.w_rdy
        heads = []
        earlier = 0
        for k, core in enumerate(self.cores):
            hv = Signal(name=f"spike_head{k}_valid")
            hi = Signal.like(self.spike_index, name=f"spike_head{k}_index")
            hs = Signal.like(self.spike_sweep, name=f"spike_head{k}_sweep")
            grant = Signal(name=f"spike_grant{k}")
            m.d.comb += grant.eq(take & hv & ~earlier)
            earlier = earlier | hv
            load = ~hv | grant
            m.d.comb += core.spike_ready.eq(load)
            with m.If(load):
                m.d.sync += [hv.eq(core.spike_valid), hi.eq(core.spike_index + k * N),
                             hs.eq(core.spike_sweep)]
            heads.append((hv, hi, hs))
        valid, index, sweep = 0, 0, 0
        for hv, hi, hs in reversed(heads):
            valid, index, sweep = Mux(hv, 1, valid), Mux(hv, hi, index), Mux(hv, hs, sweep)
        m.d.comb += [out.w_en.eq(take & valid), out.w_data.eq(Cat(index, sweep)),
                     self.spike_valid.eq(out.r_rdy), self.spike_index.eq(out.r_data[:iw]),
                     self.spike_sweep.eq(out.r_data[iw:]), out.r_en.eq(self.spike_ready)]

        if self.probes:
            for k, core in enumerate(self.cores):
                m.d.comb += [getattr(self, f"p{k}_{n}").eq(getattr(core, f"upd_{n}"))
                             for n in PROBES]
        # the per-sweep figures one cycle after core 0's (the sum of the cores' counts and
        # the ORed flags registered beside them)
        c0 = self.cores[0]
        total = 0
        overrun = overflow = flags = 0
        for core in self.cores:
            total = total + core.sweep_count
            overrun, overflow = overrun | core.overrun, overflow | core.spike_overflow
            flags = flags | core.clamp_flags
        m.d.sync += [self.sweep_done.eq(c0.sweep_done), self.sweep_number.eq(c0.sweep_number),
                     self.sweep_count.eq(total), self.overrun.eq(overrun),
                     self.spike_overflow.eq(overflow), self.clamp_flags.eq(flags)]
        # busy from the cycle after a tick, as on a single core (the tick waits a cycle in the
        # cores' tick registers)
        m.d.comb += self.busy.eq(c0.busy | (ticks[0] if external else 0))
        return m


def izhikevich_array_verilog(config: IzhikevichConfig, n_cores: int, probes: bool = False,
                             name: str = "izhikevich_array", neuron_sets=None) -> str:
    """Verilog text of an array of ``n_cores`` cores (``probes``: with the per-core update
    ports, for the scoreboard; ``neuron_sets``: each global id's initial parameter set)."""
    return verilog_text(IzhikevichArray(config, n_cores, probes, neuron_sets), name)
