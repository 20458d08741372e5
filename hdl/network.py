"""On-chip afferent -> cuneate network: the Izhikevich core's spikes drive the coincidence
detector, with its bit-exact twin.

:class:`AfferentCuneateNetwork` holds an :class:`~cuneate.hdl.izhikevich.IzhikevichCore`
(``n_afferents`` afferent neurons, currents written by the host) and a
:class:`~cuneate.hdl.cuneate.CoincidenceDetector` whose source ``s`` is afferent neuron
``first_source + s`` (other afferents drive no detector input). Both share one tick:

* **Link.** Every afferent update leaves the core on ``upd_*`` at most one per cycle; a spike
  of a source neuron is one detector input event in that same cycle (``in_valid``,
  ``in_source``). The link has no buffer and no back-pressure, so it can neither drop nor
  duplicate an event: the detector accepts one event per cycle, the core emits at most one.
* **Sweep boundary.** A tick (external ``tick`` or the internal divider) is held in
  ``tick_pending`` until the core's previous sweep is complete (its ``sweep_done``, after the
  last update is on ``upd_*``) and the detector is idle; then the core starts sweep ``T`` and
  the detector stamps tick ``T`` in the same cycle. Every spike of sweep ``T - 1`` was an event
  before that cycle, so it is stamped with tick ``T`` - never ``T + 1``, never twice. A tick
  that arrives while one is pending is counted in ``overrun_count`` (not silently lost).

Latency, afferent update to PSP onset: the update of afferent ``s`` in sweep ``k`` (reported at
``(k + 1) dt``) is stamped with detector tick ``k + 1``, enters target ``t``'s input sum at tick
``k + 1 + delay[t, s]`` and first changes its PSP current at tick ``k + 2 + delay[t, s]`` (the
PSP kernel is 0 at lag 0). In cycles, the event reaches the detector
``PIPELINE_DEPTH + 1`` cycles after the neuron's fetch.

Output: one spike stream (``out_valid``/``out_ready``, ``out_population`` 0 = afferent,
1 = cuneate, ``out_index``, ``out_tick`` = sweep/tick number modulo ``2**sweep_number_width``;
both populations report the update of tick ``T`` as tick ``T``, i.e. at ``(T + 1) dt``).
Cuneate spikes go through a FIFO of ``cuneate_fifo_depth`` and have priority; the afferent spikes
through the core's own FIFO (``2 n_afferents`` deep). A full FIFO drops and says so
(``cuneate_overflow_count``, sticky ``afferent_overflow``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from amaranth import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from .cuneate import CoincidenceConfig, CoincidenceDetector, CoincidenceTwin
from .izhikevich import IzhikevichConfig, IzhikevichCore, IzhikevichTwin
from .izhikevich_config import PIPELINE_DEPTH, ConfigError
from .tick import tick_strobe

__all__ = ["NetworkConfig", "NetworkTwin", "AfferentCuneateNetwork", "ConfigError",
           "network_verilog", "generate_network", "POPULATIONS"]

POPULATIONS = ("afferent", "cuneate")
COUNTER_BITS = 32
#: cycles from ``go`` to a sweep's ``sweep_done`` beyond one per afferent (pipeline and flags)
SWEEP_EXTRA = PIPELINE_DEPTH + 3


@dataclass
class NetworkConfig:
    """An afferent core and a coincidence detector on one tick.

    Parameters
    ----------
    n_afferents
        Afferent neurons on the core (>= the core's pipeline depth, 5).
    detector
        Constructor keywords of :class:`~cuneate.hdl.cuneate.CoincidenceConfig` (its clock and
        tick settings are the network's).
    first_source
        Detector source ``s`` is afferent neuron ``first_source + s``.
    afferent_param_sets, afferent_sets
        Izhikevich parameter sets of the afferents and each afferent's set (default RS).
    clock_hz, update_hz, tick_source
        One clock and one tick for both blocks.
    cuneate_fifo_depth
        Depth of the cuneate spike FIFO on the output stream.
    """

    n_afferents: int = 8
    detector: dict = field(default_factory=dict)
    first_source: int = 0
    afferent_param_sets: tuple = ("RS",)
    afferent_sets: list | None = None
    clock_hz: float = 40e6
    update_hz: float = 16e3
    tick_source: str = "internal"
    cuneate_fifo_depth: int = 16

    def __post_init__(self):
        if self.tick_source not in ("internal", "external"):
            raise ConfigError("tick_source must be 'internal' or 'external'")
        N = self.n_afferents
        if not isinstance(N, (int, np.integer)) or N < PIPELINE_DEPTH:
            raise ConfigError(f"n_afferents must be an integer >= {PIPELINE_DEPTH} (the core's "
                              f"pipeline depth), got {N!r}")
        det = dict(self.detector)
        for k in ("clock_hz", "update_hz", "tick_source"):
            if k in det:
                raise ConfigError(f"detector.{k} is the network's own setting; give it to the "
                                  f"network")
        try:
            self.det = CoincidenceConfig(**det, clock_hz=self.clock_hz,
                                         update_hz=self.update_hz, tick_source="external")
        except ConfigError as exc:
            raise ConfigError(f"network detector refused: {exc}") from None
        S, F = self.det.n_sources, self.first_source
        if not isinstance(F, (int, np.integer)) or F < 0 or F + S > N:
            raise ConfigError(f"the detector's {S} sources from afferent {F!r} on do not fit "
                              f"the core's {N} afferents (source s is afferent first_source + "
                              f"s)")
        sets = [0] * N if self.afferent_sets is None else list(self.afferent_sets)
        try:
            self.core = IzhikevichConfig(
                n_neurons=N, clock_hz=self.clock_hz, update_hz=self.update_hz,
                param_sets=tuple(self.afferent_param_sets), neuron_sets=sets,
                tick_source="external", spike_fifo_depth=max(16, 2 * N))
        except ConfigError as exc:
            raise ConfigError(f"network afferent core refused: {exc}") from None
        if not isinstance(self.cuneate_fifo_depth, (int, np.integer)) or \
                self.cuneate_fifo_depth < self.det.n_targets:
            raise ConfigError(f"cuneate_fifo_depth must be an integer >= n_targets "
                              f"({self.det.n_targets})")
        self.dt_ms = 1000.0 / self.update_hz
        self.cycles_per_tick = self.core.cycles_per_tick
        # a tick is taken once the previous sweep is done and the detector idle
        self.cycles_needed = max(N + SWEEP_EXTRA, self.det.cycles_needed) + 2
        if self.cycles_needed > self.cycles_per_tick:
            raise ConfigError(f"the network needs {self.cycles_needed} cycles per tick "
                              f"({N} afferents, detector {self.det.cycles_needed}); "
                              f"{self.clock_hz:g} Hz / {self.update_hz:g} Hz gives "
                              f"{self.cycles_per_tick}")
        self.tick_width = self.core.sweep_number_width

    @property
    def n_sources(self) -> int:
        return self.det.n_sources

    @property
    def n_targets(self) -> int:
        return self.det.n_targets

    def to_kwargs(self) -> dict:
        det = self.det.to_kwargs()
        for k in ("clock_hz", "update_hz", "tick_source"):
            det.pop(k)
        return {"n_afferents": int(self.n_afferents), "detector": det,
                "first_source": int(self.first_source),
                "afferent_param_sets": [p if isinstance(p, str) else dict(p)
                                        for p in self.afferent_param_sets],
                "afferent_sets": list(self.core.neuron_sets), "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "tick_source": self.tick_source,
                "cuneate_fifo_depth": int(self.cuneate_fifo_depth)}

    def latency(self) -> dict:
        return {
            "afferent_update_to_stamp_ticks": 1,
            "afferent_update_to_input_sum_ticks": "1 + delay[t, s]",
            "afferent_update_to_psp_onset_ticks": "2 + delay[t, s]",
            "fetch_to_detector_event_cycles": PIPELINE_DEPTH + 1,
            "text": "the update of afferent s in sweep k is stamped with detector tick k + 1, "
                    "enters target t's input sum at tick k + 1 + delay[t, s] and first changes "
                    "its PSP current at tick k + 2 + delay[t, s]",
        }

    def to_dict(self) -> dict:
        core = self.core.to_dict()
        return {"block": "AfferentCuneateNetwork", "clock_hz": self.clock_hz,
                "update_hz": self.update_hz, "dt_ms": self.dt_ms,
                "tick_source": self.tick_source, "cycles_per_tick": self.cycles_per_tick,
                "cycles_needed": self.cycles_needed, "n_afferents": self.n_afferents,
                "first_source": self.first_source,
                "n_sources": self.n_sources, "n_targets": self.n_targets,
                "populations": list(POPULATIONS), "out_tick_bits": self.tick_width,
                "latency": self.latency(),
                "afferent_core": {k: core[k] for k in ("formats", "param_sets", "constants",
                                                       "proven_range", "clamps")
                                  if k in core},
                "detector": self.det.to_dict(),
                "multipliers": 4 + self.det.to_dict()["multipliers"]}


# ----------------------------------------------------------------------------------------------
class NetworkTwin:
    """Bit-exact model of :class:`AfferentCuneateNetwork` composed of the two blocks' twins."""

    def __init__(self, config: NetworkConfig):
        self.cfg = config
        self.core = IzhikevichTwin(config.core)
        self.det = CoincidenceTwin(config.det)
        self.ticks = 0
        self.last_inputs = np.zeros(config.n_targets, dtype=np.int64)

    def set_currents(self, values, index=None):
        return self.core.set_currents(values, index)

    def tick(self):
        """One tick: the detector stamps the previous sweep's afferent spikes and updates, the
        core sweeps; returns ``(afferent spikes, cuneate spikes)`` of this tick."""
        cun = self.det.tick()
        self.det.ticks -= 1                       # the input sums this tick used
        self.last_inputs = self.det.inputs()
        self.det.ticks += 1
        aff = self.core.sweep()
        F = self.cfg.first_source
        src = np.flatnonzero(aff[F:F + self.cfg.n_sources])
        if src.size:
            self.det.spike_in(src)
        self.ticks += 1
        return aff, cun


# ----------------------------------------------------------------------------------------------
class AfferentCuneateNetwork(wiring.Component):
    """The network as RTL (see the module docstring).

    Ports: ``i_wr_en/i_wr_addr/i_wr_data`` (host currents of the afferents, format of the core),
    ``tick`` (external tick), ``out_valid/out_ready/out_population/out_index/out_tick`` (spike
    stream), ``tick_count``, ``link_count`` (afferent spikes passed to the detector),
    ``afferent_spike_count``, ``cuneate_spike_count``, ``overrun_count``,
    ``cuneate_overflow_count`` and ``afferent_overflow`` (sticky: the core's FIFO dropped a
    spike), ``merged_count`` (events the detector merged: 0 by construction),
    ``clamp_flags`` (core | detector, sticky), ``busy``.
    """

    def __init__(self, config: NetworkConfig):
        self.cfg = cfg = config
        N, M = cfg.n_afferents, cfg.n_targets
        sig = {"i_wr_en": In(1), "i_wr_addr": In(range(N)), "i_wr_data": In(cfg.core.I.shape()),
               "out_valid": Out(1), "out_ready": In(1), "out_population": Out(1),
               "out_index": Out(range(max(N, M))), "out_tick": Out(cfg.tick_width),
               "tick_count": Out(COUNTER_BITS), "link_count": Out(COUNTER_BITS),
               "afferent_spike_count": Out(COUNTER_BITS),
               "cuneate_spike_count": Out(COUNTER_BITS), "overrun_count": Out(COUNTER_BITS),
               "cuneate_overflow_count": Out(COUNTER_BITS), "afferent_overflow": Out(1),
               "merged_count": Out(COUNTER_BITS),
               "clamp_flags": Out(5), "busy": Out(1)}
        if cfg.tick_source == "external":
            sig["tick"] = In(1)
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        N, S, M = cfg.n_afferents, cfg.n_sources, cfg.n_targets
        m = Module()
        m.submodules.core = core = IzhikevichCore(cfg.core)
        m.submodules.det = det = CoincidenceDetector(cfg.det)
        self.core, self.det = core, det
        m.d.comb += [core.i_wr_en.eq(self.i_wr_en), core.i_wr_addr.eq(self.i_wr_addr),
                     core.i_wr_data.eq(self.i_wr_data), core.sel_wr_en.eq(0),
                     det.clamp_clear.eq(0), core.clamp_clear.eq(0)]

        # ---- tick: held until the previous sweep is complete and the detector idle
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        pending = Signal()
        inflight = Signal()            # a core sweep started and its sweep_done not yet seen
        go = Signal()
        m.d.comb += go.eq((pending | tick) & ~inflight & ~det.busy & ~core.sweep_done)
        m.d.comb += [core.tick.eq(go), det.tick.eq(go)]
        with m.If(go):
            m.d.sync += [pending.eq(0), inflight.eq(1), self.tick_count.eq(self.tick_count + 1)]
        with m.Else():
            with m.If(tick):
                m.d.sync += pending.eq(1)
                with m.If(pending):
                    m.d.sync += self.overrun_count.eq(self.overrun_count + 1)
            with m.If(core.sweep_done):
                m.d.sync += inflight.eq(0)
        m.d.comb += self.busy.eq(inflight | det.busy | pending)

        # ---- link: one afferent update per cycle -> at most one detector event per cycle
        link = Signal()
        F = cfg.first_source
        m.d.comb += link.eq(core.upd_valid & core.upd_spike & (core.upd_index >= F)
                            & (core.upd_index < F + S))
        m.d.comb += [det.in_valid.eq(link), det.in_source.eq(core.upd_index - F)]
        with m.If(link):
            m.d.sync += self.link_count.eq(self.link_count + 1)
        with m.If(core.upd_valid & core.upd_spike):
            m.d.sync += self.afferent_spike_count.eq(self.afferent_spike_count + 1)
        with m.If(det.spike_valid):
            m.d.sync += self.cuneate_spike_count.eq(self.cuneate_spike_count + 1)
        m.d.comb += [self.merged_count.eq(det.merged_count),
                     self.clamp_flags.eq(core.clamp_flags | det.clamp_flags)]

        # ---- output stream: cuneate FIFO first, then the core's spike FIFO
        iw = max(1, (M - 1).bit_length())
        tw = cfg.tick_width
        m.submodules.cun_fifo = fifo = SyncFIFOBuffered(width=iw + tw,
                                                        depth=cfg.cuneate_fifo_depth)
        m.d.comb += [fifo.w_en.eq(det.spike_valid),
                     fifo.w_data.eq(Cat(det.spike_target[:iw], det.spike_tick[:tw]))]
        with m.If(det.spike_valid & ~fifo.w_rdy):
            m.d.sync += self.cuneate_overflow_count.eq(self.cuneate_overflow_count + 1)
        m.d.comb += self.afferent_overflow.eq(core.spike_overflow)
        cun = fifo.r_rdy
        m.d.comb += [
            self.out_valid.eq(cun | core.spike_valid),
            self.out_population.eq(cun),
            self.out_index.eq(Mux(cun, fifo.r_data[:iw], core.spike_index)),
            self.out_tick.eq(Mux(cun, fifo.r_data[iw:], core.spike_sweep)),
            fifo.r_en.eq(self.out_ready & cun),
            core.spike_ready.eq(self.out_ready & ~cun),
        ]
        return m


def network_verilog(cfg: NetworkConfig, name: str = "afferent_cuneate_network",
                    lowered: bool = False) -> str:
    """Verilog of the network; ``lowered`` gives the yosys-lowered netlist for Icarus 11 (see
    :func:`cuneate.hdl.generate.lowered_verilog`), here without ``opt_clean`` so the blocks'
    internal update outputs (``core.upd_*``, ``det.upd_*``) stay visible to a scoreboard."""
    top = AfferentCuneateNetwork(cfg)
    if lowered:
        from amaranth._toolchain.yosys import find_yosys
        from amaranth.back import rtlil
        il = rtlil.convert(top, name=name, emit_src=False)
        yosys = find_yosys(lambda ver: ver >= (0, 40))
        return yosys.run(["-q", "-"], f"read_rtlil <<rtlil\n{il}\nrtlil\nproc\n"
                                      f"write_verilog -noattr\n")
    from amaranth.back import verilog
    return verilog.convert(top, name=name, emit_src=False)


def generate_network(out, cfg: NetworkConfig, name: str = "afferent_cuneate_network") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json``; returns the paths."""
    from .generate import write_block
    return write_block(out, AfferentCuneateNetwork(cfg), cfg.to_dict(), name)
