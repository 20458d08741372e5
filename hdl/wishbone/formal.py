"""The Wishbone bank's handshake proof by k-induction (``wishbone``;
:func:`cuneate.hdl.axi.formal.prove_face` runs it): :class:`~cuneate.hdl.wishbone.bus
.WishboneRegisters` as it is, its master's signals and the register file's answers free.

Checked: ``wb_stall`` never set, so every request (``wb_cyc & wb_stb``) is taken in its cycle;
exactly one answer per request, in the next cycle, while ``wb_cyc`` lasts (``wb_ack`` or
``wb_err``, never both, never without a request, none after ``wb_cyc`` falls); the answer is
the register file's for that request (``wb_err`` its refusal, ``wb_dat_r`` a read's word); one
register access per request, with its address, data and byte selects. Assumed: ``wb_stb``
only within ``wb_cyc`` (B4 rule 3.25). Mutant (through the hook ``answered``): a write never
answered."""

from __future__ import annotations

from amaranth import Mux, Signal

from ..lib.formal import ClockedHarness, assert_all, assume_all
from ..lib.regmap import MAP_BYTES
from .bus import WishboneRegisters

__all__ = ["WishboneProof", "PROOFS"]


class _WritesUnanswered(WishboneRegisters):
    def answered(self, req):
        return req & ~self.we


class WishboneProof(ClockedHarness):
    """The Wishbone B4 pipelined slave (see the module docstring)."""

    def elaborate(self, platform):
        m = self.module()
        d, r = self.dut, self.dut.regs
        self.free(m, d.cyc, d.stb, d.we, d.adr, d.dat_w, d.sel, r.r_data, r.err)
        assume_all(m, [~d.stb | d.cyc])
        req = d.cyc & d.stb
        top = MAP_BYTES // 4
        word = Signal(range(top + 1), name="ref_word")
        m.d.comb += word.eq(Mux(d.adr < top, d.adr, top))
        due = self.reg(m, req, "ref_due")
        refused = self.reg(m, r.err, "ref_refused")
        read = self.reg(m, req & ~d.we, "ref_read")
        data = self.reg(m, r.r_data, "ref_data")
        answer = d.ack | d.err
        assert_all(m, [
            (d.stall == 0, "stall: never"),
            (~(d.ack & d.err), "answer: ACK or ERR, not both"),
            (~answer | d.cyc, "answer: only within the cycle"),
            (~answer | due, "answer: only to a request"),
            (~(due & d.cyc) | answer, "answer: every request, in the next cycle"),
            (~d.err | refused, "answer: ERR for what the file refused"),
            (~d.ack | ~refused, "answer: ACK for what the file took"),
            (~(d.ack & read) | (d.dat_r == data), "answer: a read's word"),
            (r.en == req, "access: one per request"),
            (~req | (r.w_en == d.we) & (r.addr == word) & (r.w_data == d.dat_w)
             & (r.w_strb == d.sel), "access: the request's address, data and selects"),
        ])
        return m


#: target -> (harness, component, its mutant, the mutant's name, k)
PROOFS = {"wishbone": (WishboneProof, WishboneRegisters, _WritesUnanswered,
                       "write_unanswered", 3)}
