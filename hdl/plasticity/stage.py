"""The learning stage: every synapse's state in block RAM and the pipeline that applies one
operation a cycle to it.

A synapse word holds ``(w, c_d, c_r, L)`` (:attr:`PlasticityConfig.synapse_fields`). An
operation issued in cycle ``c`` (``op_valid``, ``op``, ``op_addr`` and its operands) reads the
word, and in cycle ``c + 3`` writes back (:data:`~cuneate.hdl.plasticity.config.OPS`):

``integrate`` (every synapse, every tick; operands ``op_spike``: the afferent spiked this tick,
``op_late``: it spiked ``latency`` ticks ago, ``op_z``: the CN's zero-offset main calcium)::

    L' = clamp(L + round(round(c_d - c_r) Z))        c' = y - round(k round(y)),  y = c + w s_late

``read``: nothing written (the word leaves on ``fetch_*``); ``learn`` (a window's end;
``op_total``: the sum of the CN's drives, ``op_apply``)::

    w' = clamp(w + round(D table[bin(w), D > 0]))  if op_apply,   D = round(K L - total)
    L' = 0                                          (c_d, c_r kept)

``write`` (the host's; ``op_weight``): ``(op_weight, 0, 0, 0)``.

Timing: the word as fetched leaves on ``fetch_*`` in cycle ``c + 1`` (``contrib`` = ``w`` when
``op_spike``, the CN's input sum's term); the new word on ``upd_*`` in cycle ``c + 4``, with the
clamps that acted (``upd_clamp``, bit order ``drive_low, drive_high, weight_low,
weight_high``). Two operations on one synapse must be issued at least
:data:`~cuneate.hdl.plasticity.config.STAGE_LATENCY` (4) cycles apart; an operation issued to a
synapse whose write-back is still in flight is counted in ``hazard_count`` (the layer's
schedule never does it). ``busy``: an operation is in flight.

The arithmetic is the stage functions of :mod:`cuneate.hdl.plasticity.datapath` and the
synaptic traces of :mod:`cuneate.hdl.lib.synapses`; the step table is a ROM. ``observe=True``
(proofs) adds ``obs_addr`` / ``obs_word``, a combinational read of any synapse word, and
``obs_steps``, the ROM's every entry.
"""

from __future__ import annotations

from amaranth import Cat, Module, Mux, Signal, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..lib.synapses import trace_products, trace_update
from . import datapath as dp
from .config import OPS, SYNAPSE_CLAMP_KINDS, PlasticityConfig

__all__ = ["SynapseStage", "pack", "unpack", "COUNTER_BITS"]

COUNTER_BITS = 32


def pack(values, formats) -> int:
    """Raw values packed into one unsigned word (first at the LSB)."""
    word, pos = 0, 0
    for raw, fmt in zip(values, formats):
        word |= (int(raw) & ((1 << fmt.width) - 1)) << pos
        pos += fmt.width
    return word


def unpack(word, formats) -> list:
    """Fields of a word as Amaranth values (signed where the format is) or ints."""
    out, pos = [], 0
    for fmt in formats:
        if isinstance(word, int):
            x = (word >> pos) & ((1 << fmt.width) - 1)
            if fmt.signed and x >> (fmt.width - 1):
                x -= 1 << fmt.width
        else:
            x = word[pos:pos + fmt.width]
            x = x.as_signed() if fmt.signed else x
        out.append(x)
        pos += fmt.width
    return out


class SynapseStage(wiring.Component):
    """The synapse memory and its four-cycle pipeline (see the module docstring)."""

    def __init__(self, config: PlasticityConfig, observe: bool = False):
        self.cfg = cfg = config
        self.observe = observe
        fmts = [f for _, f in cfg.synapse_fields]
        self.word_width = sum(f.width for f in fmts)
        n = cfg.n_targets * cfg.n_synapses
        sig = {
            "op_valid": In(1), "op": In(2), "op_addr": In(range(max(2, n))),
            "op_spike": In(1), "op_late": In(1), "op_z": In(cfg.Z.shape()),
            "op_total": In(signed(cfg.total_bits)), "op_apply": In(1),
            "op_weight": In(cfg.W.shape()),
            "fetch_valid": Out(1), "fetch_op": Out(2), "fetch_w": Out(cfg.W.shape()),
            "fetch_l": Out(cfg.L.shape()), "contrib": Out(cfg.W.shape()),
            "upd_valid": Out(1), "upd_op": Out(2), "upd_addr": Out(range(max(2, n))),
            "upd_w": Out(cfg.W.shape()), "upd_cd": Out(cfg.calcium[0].T.shape()),
            "upd_cr": Out(cfg.calcium[1].T.shape()), "upd_l": Out(cfg.L.shape()),
            "upd_clamp": Out(len(SYNAPSE_CLAMP_KINDS)),
            "busy": Out(1), "hazard_count": Out(COUNTER_BITS),
        }
        if observe:
            sig |= {"obs_addr": In(range(max(2, n))), "obs_word": Out(self.word_width),
                    "obs_steps": Out(len(cfg.step_table) * cfg.step_bits)}
        super().__init__(sig)
        init = [pack((cfg.weights_raw.reshape(-1)[a], 0, 0, 0), fmts) for a in range(n)]
        self.synapses = Memory(shape=unsigned(self.word_width), depth=n, init=init)
        self.steps = Memory(shape=unsigned(cfg.step_bits), depth=len(cfg.step_table),
                            init=cfg.step_table) if cfg.plastic else None

    def elaborate(self, platform):
        cfg = self.cfg
        if not cfg.plastic:
            return self._elaborate_frozen()
        m = Module()
        m.submodules.synapses = mem = self.synapses
        fmts = [f for _, f in cfg.synapse_fields]
        rd, wr = mem.read_port(), mem.write_port()
        m.submodules.steps = rom = self.steps
        rom_rd = rom.read_port()
        if self.observe:
            for k in range(len(cfg.step_table)):
                p = rom.read_port(domain="comb")
                m.d.comb += [p.addr.eq(k),
                             self.obs_steps[k * cfg.step_bits:(k + 1) * cfg.step_bits].eq(p.data)]
        if self.observe:
            obs = mem.read_port(domain="comb")
            m.d.comb += [obs.addr.eq(self.obs_addr), self.obs_word.eq(obs.data)]

        def reg(name, value, shape=None):
            s = Signal(shape if shape is not None else value.shape(), name=name)
            m.d.sync += s.eq(value)
            return s

        # ---- issue (cycle c): the read, and the operation's tag
        m.d.comb += rd.addr.eq(self.op_addr)
        a_valid = reg("a_valid", self.op_valid, 1)
        a_op, a_addr = reg("a_op", self.op), reg("a_addr", self.op_addr)
        a_spike, a_late = reg("a_spike", self.op_spike), reg("a_late", self.op_late)
        a_z, a_total = reg("a_z", self.op_z), reg("a_total", self.op_total)
        a_apply, a_weight = reg("a_apply", self.op_apply), reg("a_weight", self.op_weight)

        # ---- stage A (c + 1): the word as fetched
        w, cd, cr, L = unpack(rd.data, fmts)
        C, ys = dp.calcium_input(cfg, cd, cr, w, a_late)
        dq = dp.compensated(cfg, L, a_total)
        m.d.comb += [rom_rd.addr.eq(self._step_index(dp.step_index(cfg, w, dq))),
                     self.fetch_valid.eq(a_valid), self.fetch_op.eq(a_op),
                     self.fetch_w.eq(w), self.fetch_l.eq(L),
                     self.contrib.eq(dp.contribution(0, a_spike & (a_op == OPS["integrate"]),
                                                     w))]
        b_valid, b_op, b_addr = reg("b_valid", a_valid), reg("b_op", a_op), reg("b_addr", a_addr)
        b_apply, b_weight = reg("b_apply", a_apply), reg("b_weight", a_weight)
        b_w, b_cd, b_cr, b_L = reg("b_w", w), reg("b_cd", cd), reg("b_cr", cr), reg("b_L", L)
        b_C, b_z, b_dq = reg("b_C", C), reg("b_z", a_z), reg("b_dq", dq)
        b_ys = [reg(f"b_y{k}", y) for k, y in enumerate(ys)]

        # ---- stage B (c + 2): the products
        ps = trace_products(cfg.cview, b_ys)
        q = dp.drive_product(cfg, b_C, b_z)
        dw = dp.weight_delta(cfg, b_dq, rom_rd.data)
        c_valid, c_op, c_addr = reg("c_valid", b_valid), reg("c_op", b_op), reg("c_addr", b_addr)
        c_apply, c_weight = reg("c_apply", b_apply), reg("c_weight", b_weight)
        c_w, c_cd, c_cr, c_L = reg("c_w", b_w), reg("c_cd", b_cd), reg("c_cr", b_cr), \
            reg("c_L", b_L)
        c_ys = [reg(f"c_y{k}", y) for k, y in enumerate(b_ys)]
        c_ps = [reg(f"c_p{k}", p) for k, p in enumerate(ps)]
        c_q, c_dw = reg("c_q", q), reg("c_dw", dw)

        # ---- stage C (c + 3): the new word, written back
        cds, crs = trace_update(cfg.cview, c_ys, c_ps)
        L_new, d_low, d_high = dp.integrate(cfg, c_L, c_q)
        w_new, w_low, w_high = dp.weight_update(cfg, c_w, c_dw)
        is_int, is_learn = c_op == OPS["integrate"], c_op == OPS["learn"]
        is_write = c_op == OPS["write"]
        stepped = is_learn & c_apply
        nw = Signal(cfg.W.shape(), name="new_w")
        ncd = Signal(cfg.calcium[0].T.shape(), name="new_cd")
        ncr = Signal(cfg.calcium[1].T.shape(), name="new_cr")
        nL = Signal(cfg.L.shape(), name="new_L")
        m.d.comb += [
            nw.eq(Mux(is_write, c_weight, Mux(stepped, w_new, c_w))),
            ncd.eq(Mux(is_int, cds, Mux(is_write, 0, c_cd))),
            ncr.eq(Mux(is_int, crs, Mux(is_write, 0, c_cr))),
            nL.eq(self._new_drive(is_int, L_new, c_L)),
        ]
        clamp = self._clamp_bits(Cat(is_int & d_low, is_int & d_high, stepped & w_low,
                                     stepped & w_high))
        writes = c_valid & (c_op != OPS["read"])
        m.d.comb += [wr.en.eq(self._write_enable(m, writes)), wr.addr.eq(c_addr),
                     wr.data.eq(Cat(nw, ncd, ncr, nL))]
        m.d.sync += [self.upd_valid.eq(c_valid), self.upd_op.eq(c_op),
                     self.upd_addr.eq(c_addr), self.upd_w.eq(nw), self.upd_cd.eq(ncd),
                     self.upd_cr.eq(ncr), self.upd_l.eq(Mux(c_op == OPS["read"], c_L, nL)),
                     self.upd_clamp.eq(Mux(c_valid, clamp, 0))]

        # ---- bookkeeping: in flight, hazards
        m.d.comb += self.busy.eq(a_valid | b_valid | c_valid)
        pending = [(a_valid & (a_op != OPS["read"]), a_addr),
                   (b_valid & (b_op != OPS["read"]), b_addr),
                   (c_valid & (c_op != OPS["read"]), c_addr)]
        clash = Signal(name="hazard")
        m.d.comb += clash.eq(self.op_valid & Cat(*[v & (ad == self.op_addr)
                                                   for v, ad in pending]).any())
        with m.If(clash):
            m.d.sync += self.hazard_count.eq(self.hazard_count + 1)
        return m

    def _elaborate_frozen(self):
        """The stage of a layer that does not learn (``plastic=False``, the baseline the cost
        of learning is measured against): the weight alone, read for the input sum, written by
        the host; the same ports and timing, every other field 0."""
        m = Module()
        m.submodules.synapses = mem = self.synapses
        rd, wr = mem.read_port(), mem.write_port()
        m.d.comb += rd.addr.eq(self.op_addr)
        tags = [(self.op_valid, "valid"), (self.op, "op"), (self.op_addr, "addr"),
                (self.op_spike, "spike"), (self.op_weight, "weight")]
        stages = []
        for k in range(3):
            regs = {}
            for value, name in tags:
                r = Signal(value.shape(), name=f"{'abc'[k]}_{name}")
                m.d.sync += r.eq(value)
                regs[name] = r
            stages.append(regs)
            tags = [(regs[n], n) for _, n in tags]
        a, c = stages[0], stages[2]
        w = rd.data[:self.cfg.W.width]
        c_w = Signal(self.cfg.W.shape(), name="c_w")
        b_w = Signal(self.cfg.W.shape(), name="b_w")
        m.d.sync += [b_w.eq(w), c_w.eq(b_w)]
        m.d.comb += [self.fetch_valid.eq(a["valid"]), self.fetch_op.eq(a["op"]),
                     self.fetch_w.eq(w),
                     self.contrib.eq(dp.contribution(0, a["spike"] &
                                                     (a["op"] == OPS["integrate"]), w))]
        is_write = c["op"] == OPS["write"]
        nw = Mux(is_write, c["weight"], c_w)
        m.d.comb += [wr.en.eq(c["valid"] & is_write), wr.addr.eq(c["addr"]), wr.data.eq(nw)]
        m.d.sync += [self.upd_valid.eq(c["valid"]), self.upd_op.eq(c["op"]),
                     self.upd_addr.eq(c["addr"]), self.upd_w.eq(nw)]
        m.d.comb += self.busy.eq(Cat(*[st["valid"] for st in stages]).any())
        clash = self.op_valid & Cat(*[st["valid"] & (st["op"] == OPS["write"]) &
                                      (st["addr"] == self.op_addr) for st in stages]).any()
        with m.If(clash):
            m.d.sync += self.hazard_count.eq(self.hazard_count + 1)
        return m

    # hooks a proof's mutant overrides (the product keeps these)
    def _write_enable(self, m, en):
        """The write-back's enable."""
        return en

    def _new_drive(self, is_int, L_int, L):
        """The drive written back: the integrated one, else 0 (a learn or a write)."""
        return Mux(is_int, L_int, 0)

    def _clamp_bits(self, bits):
        """The clamp flags of an update."""
        return bits

    def _step_index(self, index):
        """The step table's address."""
        return index

