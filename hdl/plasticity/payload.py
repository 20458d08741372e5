"""The learning layer as a payload (:mod:`cuneate.hdl.lib.payload`): every face (the UART link,
AXI, Wishbone) streams its afferent spikes, its window ends and its weights through the one
write stream, and reads the weights back on the spike stream.

Write addresses (``S`` afferents, ``M`` CNs of ``K`` synapses; :func:`write_addresses`), each
write a raw value in the weight's format ``W``:

``0 .. S - 1``                      afferent ``a``'s spike when the value is not 0 (stamped by
                                    the next tick, as :class:`LearningLayer`'s ``in_source``)
``S .. S + M K - 1``                the weight of synapse ``a - S`` (``j K + m``; its calcium and
                                    drive restart)
``S + M K``                         a window's end (``learn``), the step applied when bit 0 of
                                    the value is 1
``S + M K + 1 .. S + M K + M C``    a readout request of part ``c`` of CN ``j``
                                    (``a - S - M K - 1 = j C + c``)

Sweeps: a tick with no readout pending is one of the layer's ticks: the spikes of CN ``j``
are ids ``j``. A tick while readouts are pending is a *readout sweep* instead (the layer does
not tick, its pending afferent spikes wait): the lowest request's synapses, part ``c`` of CN
``j`` (its synapses ``c R .. min(K, (c + 1) R) - 1``, ``R`` the spec's ``readout_synapses``,
``C = ceil(K / R)`` parts), leave as ``B`` spikes each (``B`` bytes a weight,
:data:`READOUT_DIGIT`): byte ``d`` of synapse ``m`` (value ``x``) is the id
``M + (m B + d) 256 + x``. A host reads a CN's weights back from which ids of that
population its ``C`` readout sweeps sent (:func:`weights_from_ids`), whatever order its
face delivers them in. ``R`` bounds a readout sweep's spikes (``R B``): a UART link's spike
batch holds 79 (beyond it they are dropped and counted).

``busy`` covers a write on offer, a pending window end, a tick and a readout;
``overflow`` a CN spike that found the spike FIFO full, ``overrun`` a tick or a window end the
layer could not take (counted by the layer, never while the face honours ``busy``); the
clamp flags are the layer's (:data:`~cuneate.hdl.plasticity.config.CLAMP_KINDS`).
"""

from __future__ import annotations

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal
from amaranth.lib.fifo import SyncFIFOBuffered

from ..lib.config import ConfigError
from ..lib.payload import BlockPayload, BlockSpec, PayloadInfo, PayloadTwin, implements
from .config import CLAMP_KINDS, STAGE_LATENCY, PlasticityConfig
from .core import LearningLayer
from .twin import PlasticityTwin

__all__ = ["LearningSpec", "LearningPayload", "write_addresses", "WRITE_MEANINGS", "readout_ids",
           "weights_from_ids", "readout_parts", "readout_bytes", "READOUT_DIGIT", "SWEEP_WIDTH"]

#: values of one readout digit (a weight leaves byte by byte)
READOUT_DIGIT = 256
#: bits of the payload's sweep numbers
SWEEP_WIDTH = 16


#: what a write to each range of :func:`write_addresses` does (the register map states it)
WRITE_MEANINGS = {
    "spike": "afferent (address - first) spikes before the next tick when the value is not 0",
    "weight": "synapse (address - first) = CN * K + m takes the value as its raw weight (its "
              "calcium and drive restart)",
    "learn": "a window's end; bit 0 of the value: apply the steps",
    "readout": "request a readout sweep of part c of CN j (address - first = j C + c): at a "
               "tick, instead of ticking, the layer sends the weights of synapses c R .. "
               "(c + 1) R - 1 byte by byte as ids M + (m B + d) 256 + byte (B bytes a weight)",
}


def readout_parts(cfg: PlasticityConfig, readout_synapses: int | None = None) -> int:
    """``C``: the readout sweeps of one CN at ``readout_synapses`` synapses each (all ``K``
    when ``None``)."""
    K = cfg.n_synapses
    R = K if readout_synapses is None else int(readout_synapses)
    if not 1 <= R <= K:
        raise ConfigError(f"readout_synapses must be 1 .. {K} (synapses a readout sweep sends), "
                          f"not {readout_synapses}")
    return -(-K // R)


def write_addresses(cfg: PlasticityConfig, readout_synapses: int | None = None) -> dict:
    """The write stream's address map: name -> ``(first, count)`` (module docstring)."""
    S, M, K = cfg.n_sources, cfg.n_targets, cfg.n_synapses
    return {"spike": (0, S), "weight": (S, M * K), "learn": (S + M * K, 1),
            "readout": (S + M * K + 1, M * readout_parts(cfg, readout_synapses))}


def readout_bytes(cfg: PlasticityConfig) -> int:
    """``B``: the bytes (readout spikes) of one weight."""
    return -(-cfg.W.width // 8)


def readout_ids(cfg: PlasticityConfig, weights_raw, first: int = 0) -> np.ndarray:
    """The ids a readout sweep of a CN's synapses ``first, first + 1, ...`` whose weights are
    ``weights_raw`` (raw) sends, in the order the payload sends them."""
    M, B = cfg.n_targets, readout_bytes(cfg)
    return np.asarray([M + (m * B + d) * READOUT_DIGIT + (int(w) >> (8 * d)) % READOUT_DIGIT
                       for m, w in enumerate(weights_raw, first) for d in range(B)],
                      dtype=np.int64)


def weights_from_ids(cfg: PlasticityConfig, ids) -> np.ndarray:
    """The ``K`` raw weights of one CN's readout sweeps' ids (any order); refuses ids that
    do not hold each synapse's every byte once."""
    M, K, B = cfg.n_targets, cfg.n_synapses, readout_bytes(cfg)
    slot, value = np.divmod(np.asarray(ids, dtype=np.int64) - M, READOUT_DIGIT)
    if np.any(slot < 0) or np.any(slot >= K * B) or len(np.unique(slot)) != K * B \
            or len(slot) != K * B:
        raise ValueError(f"a readout sweep holds each of the {K} synapses' {B} bytes once; got "
                         f"{len(slot)} readout ids")
    byte = np.zeros(K * B, dtype=np.int64)
    byte[slot] = value
    return (byte.reshape(K, B) << (8 * np.arange(B))).sum(axis=1)


def readout_cycles(cfg: PlasticityConfig, synapses: int) -> int:
    """A readout sweep's cycles at worst (per synapse: the read's wait for the stage, its
    answer, its bytes), the spike FIFO keeping up."""
    return synapses * (STAGE_LATENCY + 4 + readout_bytes(cfg)) + 4


@implements(PlasticityConfig)
class LearningSpec(BlockSpec):
    """The learning layer of ``config``, its readout sweeps sending ``readout_synapses``
    synapses each (all ``K`` when ``None``). A tick keeps it busy, at worst, for a burst
    writing every weight, a window's end, and its tick or a readout sweep."""

    def __init__(self, config: PlasticityConfig, readout_synapses: int | None = None):
        self.config = c = config
        S, M, K = c.n_sources, c.n_targets, c.n_synapses
        self.parts = readout_parts(c, readout_synapses)
        self.readout_synapses = R = K if readout_synapses is None else int(readout_synapses)
        amap = write_addresses(c, R)
        n_written = sum(n for _, n in amap.values())
        busy = (M * K * (STAGE_LATENCY + 2) + c.learn_cycles
                + max(c.cycles_needed, readout_cycles(c, R)) + M + 8)
        self.info = PayloadInfo(
            block="learning_layer", written="spike, weight, window end or readout",
            n_written=n_written, value_format=c.W,
            populations=(("cuneate", 0, M), ("weight", M, K * readout_bytes(c) * READOUT_DIGIT)),
            sweep_width=SWEEP_WIDTH, clock_hz=c.clock_hz, update_hz=c.update_hz,
            cycles_per_tick=c.cycles_per_tick, busy_cycles=busy, clamp_kinds=CLAMP_KINDS,
            rounding="truncate",
            parts=({"block": "learning_layer", "afferents": S, "cns": M, "synapses": K},),
            write_map=tuple((k, first, n, WRITE_MEANINGS[k]) for k, (first, n) in amap.items()))

    def config_from(self, kw: dict) -> PlasticityConfig:
        return PlasticityConfig.from_kwargs(kw)

    def options(self) -> dict:
        return {"readout_synapses": self.readout_synapses}

    def component(self) -> "LearningPayload":
        return LearningPayload(self)

    def twin(self) -> "LearningPayloadTwin":
        return LearningPayloadTwin(self.config, self.readout_synapses)


class LearningPayloadTwin(PayloadTwin):
    """The layer's twin (:class:`~cuneate.hdl.plasticity.twin.PlasticityTwin`, attribute
    ``model``) as the payload's writes and sweeps drive it."""

    def __init__(self, cfg: PlasticityConfig, readout_synapses: int):
        self.cfg, self.R = cfg, readout_synapses
        self.parts = readout_parts(cfg, readout_synapses)
        self.model = PlasticityTwin(cfg, kernel="stages")
        self.amap = write_addresses(cfg, readout_synapses)
        self.readouts: set[int] = set()

    def write(self, addr: int, raw: int) -> None:
        kind, off = _decode(self.amap, int(addr))
        if kind == "spike":
            if raw:
                self.model.spike_in(off)
        elif kind == "weight":
            self.model.write_weight(off, raw)
        elif kind == "learn":
            self.model.learn(bool(raw & 1))
        else:
            self.readouts.add(off)

    def sweep(self) -> np.ndarray:
        if self.readouts:
            i = min(self.readouts)
            self.readouts.discard(i)
            j, c = divmod(i, self.parts)
            return readout_ids(self.cfg, self.model.w[j, c * self.R:(c + 1) * self.R],
                               c * self.R)
        return np.flatnonzero(self.model.tick())

    def clamp_flags(self) -> int:
        return int(self.model.clamp_sticky)


def _decode(amap: dict, addr: int) -> tuple[str, int]:
    for kind, (first, count) in amap.items():
        if first <= addr < first + count:
            return kind, addr - first
    raise ValueError(f"write address {addr} is outside the learning layer's map")


class LearningPayload(BlockPayload):
    """:class:`~cuneate.hdl.plasticity.core.LearningLayer` (attribute ``layer``) behind the
    payload signature (module docstring); its spikes and a readout's bytes pass through a
    FIFO of ``M + 2`` entries, each tagged with its sweep."""

    def __init__(self, spec: LearningSpec):
        super().__init__(spec, layer=LearningLayer(spec.config))

    def elaborate(self, platform):
        m = Module()
        cfg = self.spec.config
        M, K, B = cfg.n_targets, cfg.n_synapses, readout_bytes(cfg)
        m.submodules.layer = layer = self.layer
        ib = len(self.spikes.payload.index)
        m.submodules.fifo = fifo = SyncFIFOBuffered(width=ib + SWEEP_WIDTH, depth=M + 2)
        sweep = Signal(SWEEP_WIDTH)
        push, push_id = Signal(), Signal(ib)
        m.d.comb += [fifo.w_en.eq(push), fifo.w_data.eq(Cat(push_id, sweep)),
                     self.spikes.valid.eq(fifo.r_rdy), fifo.r_en.eq(self.spikes.ready),
                     self.spikes.payload.eq(fifo.r_data)]
        idle = Signal()
        C, R = self.spec.parts, self.spec.readout_synapses
        readouts = Signal(M * C)               # pending requests, bit j C + c
        requested = self._writes(m, layer, idle)
        syn, last, digit = Signal(range(K + 1)), Signal(range(K)), Signal(range(B + 1))
        word = Signal(8 * B)
        base = Signal(range(M * K + 1))        # the CN's first synapse (j K)
        pick = Signal(M * C)                   # the lowest pending request, one-hot
        m.d.comb += pick.eq(readouts & (~readouts + 1))
        take = Signal(M * C)
        part = [divmod(i, C) for i in range(M * C)]
        with m.FSM(name="payload_fsm"):
            with m.State("IDLE"):
                m.d.comb += idle.eq(1)
                with m.If(self.tick & (readouts != 0)):
                    m.d.comb += take.eq(pick)
                    m.d.sync += [base.eq(_select(pick, [j * K for j, _ in part])),
                                 syn.eq(_select(pick, [c * R for _, c in part])),
                                 last.eq(_select(pick, [min(K, (c + 1) * R) - 1
                                                        for _, c in part]))]
                    m.next = "READ"
                with m.Elif(self.tick):
                    m.d.comb += layer.tick.eq(1)
                    m.next = "START"
            with m.State("START"):             # the layer takes the tick
                with m.If(layer.busy):
                    m.next = "TICK"
            with m.State("TICK"):              # its last CN's spike is pushed as it ends
                with m.If(~layer.busy):
                    m.next = "DONE"
            with m.State("READ"):
                m.d.comb += [layer.w_rd_valid.eq(1), layer.w_rd_addr.eq(base + syn)]
                with m.If(layer.w_rd_ready):
                    m.next = "ANSWER"
            with m.State("ANSWER"):
                with m.If(layer.w_rd_resp_valid):
                    m.d.sync += [word.eq(layer.w_rd_resp_data), digit.eq(0)]
                    m.next = "EMIT"
            with m.State("EMIT"):
                slot = syn * B + digit
                m.d.comb += [push.eq(fifo.w_rdy),
                             push_id.eq(M + slot * READOUT_DIGIT + word.word_select(digit, 8))]
                with m.If(fifo.w_rdy):
                    m.d.sync += digit.eq(digit + 1)
                    with m.If(digit == B - 1):
                        m.d.sync += syn.eq(syn + 1)
                        m.next = "READ"
                        with m.If(syn == last):
                            m.next = "DONE"
            with m.State("DONE"):
                m.d.comb += self.sweep_done.eq(1)
                m.d.sync += sweep.eq(sweep + 1)
                m.next = "IDLE"
        with m.If(layer.spike_valid):
            m.d.comb += [push.eq(1), push_id.eq(layer.spike_target)]
        # readout requests: set by their writes, cleared as their readout starts
        m.d.sync += readouts.eq((readouts & ~take) | requested)
        overflow, overrun = Signal(), Signal()
        m.d.sync += [overflow.eq(overflow | (layer.spike_valid & ~fifo.w_rdy)),
                     overrun.eq(overrun | (self.tick & ~idle))]
        m.d.comb += [
            self.busy.eq(~idle | layer.busy | self.write.valid),
            self.clamp_flags.eq(layer.clamp_flags), layer.clamp_clear.eq(self.clamp_clear),
            self.overflow.eq(overflow),
            self.overrun.eq(overrun | layer.tick_overrun | (layer.learn_overrun_count != 0)),
        ]
        return m

    def _writes(self, m, layer, idle):
        """The write stream's addresses onto the layer's ports (module docstring); returns
        the readout request written now (one-hot over the requests)."""
        amap = write_addresses(self.spec.config, self.spec.readout_synapses)
        w = self.write
        a, v = w.payload.addr, w.payload.value
        (s0, ns), (w0, nw), (l0, _), (r0, nr) = (amap[k] for k in
                                                  ("spike", "weight", "learn", "readout"))
        is_weight = (a >= w0) & (a < w0 + nw)
        is_learn = a == l0
        is_read = (a >= r0) & (a < r0 + nr)
        m.d.comb += [
            w.ready.eq(1),
            layer.in_valid.eq(w.valid & (a < s0 + ns) & (v != 0)), layer.in_source.eq(a),
            layer.w_wr_addr.eq((a - w0).as_unsigned()), layer.w_wr_data.eq(v),
            layer.learn_apply.eq(v[0]),
        ]
        with m.If(is_weight):
            m.d.comb += [w.ready.eq(idle & layer.w_wr_ready),
                         layer.w_wr_valid.eq(w.valid & idle)]
        with m.If(is_learn):
            m.d.comb += [w.ready.eq(idle & ~layer.busy),
                         layer.learn.eq(w.valid & idle & ~layer.busy)]
        requested = Signal(nr, name="requested")
        with m.If(w.valid & is_read):
            m.d.comb += requested.eq(Const(1, nr) << (a - r0).as_unsigned())
        return requested


def _select(onehot, values):
    """``values[i]`` for the set bit ``i`` of a one-hot value (a sum of constants: no
    multiplier, no index)."""
    return sum((Mux(onehot[i], v, 0) for i, v in enumerate(values) if v),
               Const(0, range(max(values) + 1)))
