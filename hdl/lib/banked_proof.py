"""The banked, prefetched memory (:func:`cuneate.hdl.lib.banked.prefetched_memory`) against its
per-cycle contract, for every sequence of reads and writes (k-induction with SymbiYosys).

**Why a proof of its own.** A core proof (:mod:`cuneate.hdl.lib.core_proof`) with memories in
several banks does not close in the solver's time (a two-bank core of 8 neurons ran for more
than 10 minutes at k = 7 where the one-bank core closes in seconds; the default configuration's
five state banks and three current banks timed out at 40 minutes). A core touches its memories
only through the read address, the write port and ``data``, and the one-bank memory the core
proofs use is the same :func:`prefetched_memory` with one bank. So the proof is split: the core
proofs with each memory in one bank, and this proof that a memory of any number of banks meets
the one contract both satisfy.

**The contract** (the module docstring of :mod:`cuneate.hdl.lib.banked`). A write issued in
cycle ``c`` lands at the end of ``c`` (``c + 1`` with ``write_register``); the address on
``read_addr`` in cycle ``c`` is sampled at the end of ``c``, and ``data`` in cycle ``c + 2`` is
the word at that address *after* the writes landing at the end of ``c`` (the bypass, with
``bypass=True``; without it a write landing as the address is sampled is not seen, and the
harness does not let one happen).

**How.** One tracked address ``t`` (a free constant: the proof holds for every ``t``); the
reference word follows the writes to ``t`` at their landing. Invariants: the RAM's word at
``t`` (read in the bank that holds it) equals the reference in every cycle; every read of
``t`` returns the reference as the contract says. Read addresses, writes and their data are
free inputs (addresses below the depth); the RAM starts with any contents.
"""

from __future__ import annotations

from pathlib import Path

from amaranth import Array, ClockDomain, Elaboratable, Module, Mux, Signal
from amaranth.asserts import AnyConst, AnySeq

from .banked import bank_word, prefetched_memory
from .formal import ProofResult, assert_all, assume_all, delay_line, harness_rtlil, run_proof

__all__ = ["BankedMemoryProof", "prove_banked", "MUTANTS", "ABSTRACTIONS"]

#: faults the harness can build into the memory (never into the product): the bank of a word
#: read one bank off (the memory built with a wrong ``pick``), the bypass left out
MUTANTS = ("wrong_bank", "no_bypass")
ABSTRACTIONS = ["read addresses and writes free every cycle", "memory with free initial "
                                                              "contents"]


def _next_bank_word(words, bank):
    """The word of the bank after ``bank``: each word read from the wrong bank."""
    words = list(words)
    return bank_word(words[1:] + words[:1], bank)


class BankedMemoryProof(Elaboratable):
    """Harness: a ``depth``-word memory of ``width`` bits in banks of ``bank_depth`` words
    (the block shape ``(bank_depth, width)``), with the write bypass and optionally a
    registered write, against its contract; ``memory``: the function that builds it
    (:func:`~cuneate.hdl.lib.banked.prefetched_memory`, or a faulty one: a test of the
    proof)."""

    def __init__(self, depth: int, bank_depth: int, width: int = 3,
                 write_register: bool = False, bypass: bool = True,
                 mutant: str | None = None, memory=prefetched_memory):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
        self.depth, self.bank_depth, self.width = depth, bank_depth, width
        self.write_register, self.bypass, self.mutant = write_register, bypass, mutant
        self.memory = memory
        self.cd = ClockDomain("sync", reset_less=True)
        self.ports = [self.cd.clk]
        self.n_banks = None

    def elaborate(self, platform):
        m = Module()
        m.domains.sync = self.cd
        N, W = self.depth, self.width
        t = Signal(range(N), name="tracked")
        m.d.comb += t.eq(AnyConst(range(N)))
        read_addr = Signal(range(N), name="read_addr")
        wr_en, wr_addr = Signal(name="wr_en"), Signal(range(N), name="wr_addr")
        wr_data = Signal(W, name="wr_data")
        m.d.comb += [read_addr.eq(AnySeq(len(read_addr))), wr_en.eq(AnySeq(1)),
                     wr_addr.eq(AnySeq(len(wr_addr))), wr_data.eq(AnySeq(W))]
        assume_all(m, [t < N, read_addr < N, wr_addr < N])
        pick = _next_bank_word if self.mutant == "wrong_bank" else bank_word
        mem = self.memory(m, "mem", W, N, [], read_addr, ((self.bank_depth, W),),
                          bypass=self.bypass and self.mutant != "no_bypass",
                          write_register=self.write_register, pick=pick)
        self.n_banks = len(mem.banks)
        m.d.comb += [mem.wr_en.eq(wr_en), mem.wr_addr.eq(wr_addr), mem.wr_data.eq(wr_data)]
        data = mem.data

        # the landing write (the contract's, from the inputs)
        if self.write_register:
            l_en, l_addr, l_data = (delay_line(m, s, 1, f"land_{s.name}")[1]
                                    for s in (wr_en, wr_addr, wr_data))
        else:
            l_en, l_addr, l_data = wr_en, wr_addr, wr_data
        lands = l_en & (l_addr == t)

        # the RAM's word at t, in its bank (an asynchronous read port, observation only)
        ports = [bank.read_port(domain="comb") for bank in mem.banks]
        if len(ports) == 1:
            m.d.comb += ports[0].addr.eq(t)
            seen = ports[0].data
        else:
            lo = (mem.bank_depth - 1).bit_length()
            for p in ports:
                m.d.comb += p.addr.eq(t[:lo])
            seen = Signal(W, name="seen")
            m.d.comb += seen.eq(Array(p.data for p in ports)[t[lo:]])

        primed = Signal(name="primed")
        m.d.sync += primed.eq(1)
        ref = Signal(W, name="ref")
        now = Signal(W, name="ref_now")
        m.d.comb += now.eq(Mux(primed, ref, seen))
        after = Signal(W, name="ref_after")            # the word after this cycle's landing
        m.d.comb += after.eq(Mux(lands, l_data, now))
        m.d.sync += ref.eq(after)
        read_t = delay_line(m, (read_addr == t) & primed, 2, "read_t")
        expect = delay_line(m, after, 2, "expect")
        checks = [(seen == now, "the RAM's word at t"),
                  (~read_t[2] | (data == expect[2]), "a read of t two cycles on")]
        if not self.bypass:
            assume_all(m, [~(lands & (read_addr == t))])
        assert_all(m, checks)
        return m


def prove_banked(workdir: Path, depth: int = 10, bank_depth: int = 4, width: int = 3,
                 write_register: bool = False, mode: str = "prove", k: int | None = None,
                 mutant: str | None = None, timeout_s: float = 600,
                 memory=prefetched_memory) -> ProofResult:
    """k-induction (``mode="prove"``) or a bounded check (``"bmc"``) of a ``depth``-word
    memory in banks of ``bank_depth`` against its contract; ``k`` default 4 (two cycles from
    a read to its word, one of a registered write, one more); ``memory``: see
    :class:`BankedMemoryProof`."""
    top = BankedMemoryProof(depth, bank_depth, width, write_register, mutant=mutant,
                            memory=memory)
    il = harness_rtlil(top, "banked_eq", ("mem",))
    return run_proof("banked memory meets its contract", il, workdir, "banked_eq", mode,
                     k or 4, timeout_s, "smtbmc", ABSTRACTIONS)
