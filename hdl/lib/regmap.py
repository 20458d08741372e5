"""The bus faces' register map, described once (:data:`REGISTERS`): the AXI4-Lite and Wishbone
banks decode it (:class:`RegisterFile` behind :func:`register_port`), and the Verilog header,
the JSON and the markdown register map are written from it (:func:`regmap_dict`,
:func:`regmap_markdown`, :func:`regmap_lines`).

Registers are 32 bits at byte offsets multiple of 4 (a Wishbone bus addresses words:
``offset / 4``). Access kinds:

``const``  read only, a value of the block's configuration (:class:`~cuneate.hdl.lib.payload
           .PayloadInfo`), fixed when the Verilog is generated
``ro``     read only, live state of the face or the block
``rw``     read and write (byte enables honoured); a write outside ``minimum`` .. 2**32 - 1 is
           refused
``cmd``    a write gives a command (its data, the bytes not enabled read as 0); a read returns
           the register's status (``CONTROL``: 0)

A write to a ``const`` or ``ro`` register or outside the map, a read outside the map and a
refused ``rw`` value change nothing and answer an error (AXI4-Lite ``SLVERR``, Wishbone
``ERR``): nothing is silently ignored. Reads have no side effects.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

from amaranth import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["Field", "Register", "REGISTERS", "REGMAP_VERSION", "MAGIC", "MAP_BYTES",
           "WORD_BITS", "COUNTERS", "register", "register_port", "RegisterFile",
           "constants", "regmap_dict", "regmap_markdown", "regmap_lines", "write_map_lines",
           "stream_format"]

#: the map's version (major << 16 | minor): a driver checks it with ``MAGIC``
REGMAP_VERSION = (1 << 16) | 0
#: ``ID``: the bytes "cune" read as a little-endian word
MAGIC = int.from_bytes(b"cune", "little")
#: bytes the map spans (word addresses below ``MAP_BYTES / 4`` are decoded)
MAP_BYTES = 0x80
WORD_BITS = 32


@dataclass(frozen=True)
class Field:
    """Bits ``lsb`` .. ``lsb + width - 1`` of a register."""

    name: str
    lsb: int
    width: int
    doc: str


@dataclass(frozen=True)
class Register:
    name: str
    offset: int
    access: str
    doc: str
    fields: tuple = field(default=())
    minimum: int = 0


def _f(*spec) -> tuple:
    return tuple(Field(*s) for s in spec)


#: the face's counters (saturating at 2**32 - 1, cleared by ``CONTROL.CLEAR_COUNTERS``), in
#: register order from ``0x60``
COUNTERS = (
    ("writes", "values taken on s_axis and handed to the block"),
    ("bursts", "write bursts ended (beats with TLAST taken)"),
    ("writes_refused", "beats refused: address >= N_WRITTEN or a value outside its format"),
    ("spikes", "spike beats sent on m_axis"),
    ("sweeps", "sweeps closed (beats with TLAST sent)"),
    ("empty_sweeps", "sweeps without a spike (their marker beat sent)"),
    ("ticks", "ticks given to the block (sweeps started)"),
    ("tick_overruns", "ticks lost: due while the previous one still waited"),
)

#: the map
REGISTERS: tuple[Register, ...] = (
    Register("ID", 0x00, "const", "the bytes 'cune' (0x656e7563)"),
    Register("VERSION", 0x04, "const", "the register map's version: major << 16 | minor"),
    Register("BLOCK", 0x08, "const", "CRC-32 of the block's name (the JSON names it)"),
    Register("N_WRITTEN", 0x0C, "const", "addresses a write takes (neurons or channels)"),
    Register("N_SPIKE_IDS", 0x10, "const", "spike ids the block sends (0 .. N_SPIKE_IDS - 1)"),
    Register("VALUE_FORMAT", 0x14, "const", "a written value's fixed-point format", _f(
        ("width", 0, 8, "bits"), ("frac_bits", 8, 8, "fraction bits"),
        ("signed", 16, 1, "two's complement"),
        ("channel_sample", 17, 1, "1: a channel sample (a fan-out in front), 0: a current"))),
    Register("STREAM_FORMAT", 0x18, "const", "the streams' beats", _f(
        ("write_field_bytes", 0, 8, "s_axis: value in the low, address in the high field"),
        ("spike_field_bytes", 8, 8, "m_axis: id in the low, sweep in the high field"),
        ("sweep_width", 16, 8, "bits of a sweep number (it wraps)"))),
    Register("CLOCK_HZ", 0x1C, "const", "the clock the configuration was sized for (Hz)"),
    Register("UPDATE_HZ", 0x20, "const", "sweeps a second at TICK_DIVIDER's reset value"),
    Register("CYCLES_PER_TICK", 0x24, "const", "TICK_DIVIDER's reset value"),
    Register("BUSY_CYCLES", 0x28, "const", "cycles one sweep keeps the block busy at worst"),
    Register("POPULATIONS", 0x2C, "const", "spike id populations and clamp kinds", _f(
        ("populations", 0, 8, "populations of spike ids"),
        ("clamp_kinds", 8, 8, "bits of CLAMP_FLAGS"))),
    Register("SECOND_FIRST", 0x30, "const",
             "first id of the second population (N_SPIKE_IDS when there is one)"),
    Register("CONTROL", 0x40, "cmd", "commands (write 1 to a bit; reads 0)", _f(
        ("start", 0, 1, "run sweeps freely, one every TICK_DIVIDER cycles"),
        ("stop", 1, 1, "stop after the sweep in flight (the state after reset)"),
        ("clear_counters", 2, 1, "zero every counter"),
        ("clear_clamps", 3, 1, "clear CLAMP_FLAGS"),
        ("soft_reset", 4, 1, "stop, wait until the streams and the block are idle, then "
                             "reset the face and the block's registers (see the docs)"))),
    Register("STEP", 0x44, "cmd", "write N: run N sweeps, then stop; read: sweeps left"),
    Register("TICK_DIVIDER", 0x48, "rw", "cycles from one tick to the next (>= 1)",
             minimum=1),
    Register("STATUS", 0x4C, "ro", "the face and the block now", _f(
        ("running", 0, 1, "ticks are due (free running or steps left)"),
        ("free", 1, 1, "free running"), ("pending", 2, 1, "a tick waits"),
        ("busy", 3, 1, "the block works on a sweep or a burst"),
        ("burst_open", 4, 1, "a write burst has begun and not ended (ticks held)"),
        ("sweep_open", 5, 1, "a sweep's spikes are not all sent (ticks held)"),
        ("overflow", 6, 1, "sticky: the block's spike FIFO was full and lost a spike"),
        ("overrun", 7, 1, "sticky: the block lost a tick (never while the face paces it)"),
        ("reset_pending", 8, 1, "a soft reset waits for the face to be idle"))),
    Register("SWEEP", 0x50, "ro", "sweeps started: a burst taken now applies from this sweep"),
    Register("CLAMP_FLAGS", 0x54, "ro", "sticky clamp flags, one bit per kind (the JSON names "
                                        "them); cleared by CONTROL.clear_clamps"),
) + tuple(Register(name.upper(), 0x60 + 4 * i, "ro", doc) for i, (name, doc) in
          enumerate(COUNTERS))


def register(name: str) -> Register:
    """The register called ``name``."""
    for r in REGISTERS:
        if r.name == name:
            return r
    raise KeyError(name)


def _field_bytes(*widths: int) -> int:
    """Bytes of each of two equal fields that hold ``widths`` bits: a power of two >= 2."""
    b = 2
    while any(w > 8 * b for w in widths):
        b *= 2
    return b


def stream_format(info) -> dict:
    """The streams' beat layouts for the block of ``info``: the write beat's two fields
    (value, address) and the spike beat's two (id, sweep), each ``*_field_bytes`` wide
    (a power of two >= 2: every field a C integer), TDATA twice that. The spike id field holds
    ``N_SPIKE_IDS`` itself: its all-ones value is no neuron's (an empty sweep's marker)."""
    addr_bits = max(info.n_written - 1, 1).bit_length()
    id_bits = info.n_spike_ids.bit_length()
    wb = _field_bytes(info.value_width, addr_bits)
    sb = _field_bytes(id_bits, info.sweep_width)
    return {"write_field_bytes": wb, "write_tdata_bits": 16 * wb,
            "spike_field_bytes": sb, "spike_tdata_bits": 16 * sb,
            "marker_id": (1 << (8 * sb)) - 1}


def constants(info) -> dict:
    """The ``const`` registers' values for the block of ``info``."""
    fmt = info.value_format
    sf = stream_format(info)
    pops = info.populations
    return {
        "ID": MAGIC, "VERSION": REGMAP_VERSION,
        "BLOCK": zlib.crc32(info.block.encode()),
        "N_WRITTEN": info.n_written, "N_SPIKE_IDS": info.n_spike_ids,
        "VALUE_FORMAT": fmt.width | fmt.frac_bits << 8 | int(fmt.signed) << 16
        | int(info.written == "channel sample") << 17,
        "STREAM_FORMAT": sf["write_field_bytes"] | sf["spike_field_bytes"] << 8
        | info.sweep_width << 16,
        "CLOCK_HZ": int(round(info.clock_hz)), "UPDATE_HZ": int(round(info.update_hz)),
        "CYCLES_PER_TICK": info.cycles_per_tick, "BUSY_CYCLES": info.busy_cycles,
        "POPULATIONS": len(pops) | len(info.clamp_kinds) << 8,
        "SECOND_FIRST": pops[1][1] if len(pops) > 1 else info.n_spike_ids,
    }


def register_port() -> wiring.Signature:
    """A bus bridge's side of the register file: an access (``addr`` a word address, ``w_en``
    for a write with ``w_data`` and byte enables ``w_strb``, a read otherwise) is offered while
    ``en``; the file answers in the same cycle with ``r_data`` and ``err`` (combinational) and
    acts on the clock edge."""
    return wiring.Signature({
        "en": Out(1), "addr": Out(range(MAP_BYTES // 4 + 1)), "w_en": Out(1),
        "w_data": Out(WORD_BITS), "w_strb": Out(WORD_BITS // 8),
        "r_data": In(WORD_BITS), "err": In(1),
    })


class RegisterFile(wiring.Component):
    """The map's decoder: the constants of ``info``; for every ``ro`` and ``cmd`` register an
    input ``r_<name>`` (what a read returns; ``CONTROL`` reads 0); for every ``rw`` register
    an output ``<name>`` (reset to ``resets[name]``); for every ``cmd`` register the outputs
    ``<name>_write`` (a pulse in the cycle of the write) and ``<name>_data``. The bus side is
    ``bus`` (flipped :func:`register_port`)."""

    def __init__(self, info, resets: dict):
        self.info, self.resets = info, dict(resets)
        members = {"bus": In(register_port())}
        for r in REGISTERS:
            if r.access == "ro" or (r.access == "cmd" and r.name != "CONTROL"):
                members[f"r_{r.name}"] = In(WORD_BITS)
            if r.access == "rw":
                members[r.name] = Out(WORD_BITS, init=self.resets[r.name])
            if r.access == "cmd":
                members[f"{r.name}_write"] = Out(1)
                members[f"{r.name}_data"] = Out(WORD_BITS)
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        b = self.bus
        const = constants(self.info)
        mask = Signal(WORD_BITS)
        m.d.comb += mask.eq(Cat(b.w_strb[i].replicate(8) for i in range(WORD_BITS // 8)))
        data = b.w_data & mask
        with m.Switch(b.addr):
            for r in REGISTERS:
                with m.Case(r.offset // 4):
                    self._decode(m, r, const, data, mask)
            with m.Default():
                m.d.comb += b.err.eq(b.en)
        return m

    def _decode(self, m, r: Register, const: dict, data, mask) -> None:
        b = self.bus
        write = b.en & b.w_en
        if r.access == "const":
            m.d.comb += [b.r_data.eq(const[r.name]), b.err.eq(write)]
        elif r.access == "ro":
            m.d.comb += [b.r_data.eq(getattr(self, f"r_{r.name}")), b.err.eq(write)]
        elif r.access == "rw":
            reg = getattr(self, r.name)
            new = (reg & ~mask) | data
            bad = new < r.minimum
            m.d.comb += [b.r_data.eq(reg), b.err.eq(write & bad)]
            with m.If(write & ~bad):
                m.d.sync += reg.eq(new)
        else:
            if r.name != "CONTROL":
                m.d.comb += b.r_data.eq(getattr(self, f"r_{r.name}"))
            m.d.comb += [getattr(self, f"{r.name}_write").eq(write),
                         getattr(self, f"{r.name}_data").eq(data)]


# ---------------------------------------------------------------------------- descriptions

def regmap_dict(info, resets: dict, bus: dict) -> dict:
    """The register map of the block of ``info`` as JSON-ready data: every register with its
    offset, access, fields, and its value (``const``) or reset value (``rw``); the streams'
    formats, the clamp kinds and populations by name; ``bus`` (the face's bus and its
    addressing)."""
    const = constants(info)
    regs = []
    for r in REGISTERS:
        d = {"name": r.name, "offset": r.offset, "access": r.access, "doc": r.doc,
             "fields": [{"name": f.name, "lsb": f.lsb, "width": f.width, "doc": f.doc}
                        for f in r.fields]}
        if r.access == "const":
            d["value"] = const[r.name]
        if r.access == "rw":
            d["reset"] = resets[r.name]
            d["minimum"] = r.minimum
        regs.append(d)
    return {"version": REGMAP_VERSION, "map_bytes": MAP_BYTES, "word_bits": WORD_BITS,
            "bus": bus, "block": info.block, "registers": regs,
            "clamp_kinds": list(info.clamp_kinds),
            "populations": [{"name": n, "first": f, "count": c}
                            for n, f, c in info.populations],
            "streams": stream_format(info), "write_map": info.to_dict()["write_map"]}


def regmap_lines(info, resets: dict) -> list[str]:
    """The map in a few lines per register (the Verilog header's)."""
    const = constants(info)
    out = []
    for r in REGISTERS:
        val = (f" = {const[r.name]:#x}" if r.access == "const" else
               f" (reset {resets[r.name]})" if r.access == "rw" else "")
        out.append(f"  {r.offset:#04x} {r.name:16s} {r.access:5s} {r.doc}{val}")
        out += [f"         [{f.lsb + f.width - 1}:{f.lsb}] {f.name}: {f.doc}" if f.width > 1
                else f"         [{f.lsb}] {f.name}: {f.doc}" for f in r.fields]
    kinds = ", ".join(f"{i}: {k}" for i, k in enumerate(info.clamp_kinds))
    out.append(f"  CLAMP_FLAGS bits: {kinds or 'none'}")
    return out + write_map_lines(info)


def write_map_lines(info) -> list[str]:
    """The block's write address ranges, a line each (none when every address is a value)."""
    return [f"  write addresses {f} .. {f + c - 1}: {n}: {d}" for n, f, c, d in info.write_map]


def regmap_markdown(info, resets: dict, bus: dict, name: str) -> str:
    """The map as a markdown document for the block of ``info``."""
    d = regmap_dict(info, resets, bus)
    s = d["streams"]

    def cell(text: str) -> str:
        return text.replace("|", "\\|")
    lines = [f"# {name}: register map", "",
             f"Block `{info.block}`; register map version {REGMAP_VERSION >> 16}."
             f"{REGMAP_VERSION & 0xFFFF}; {bus['text']}.", "",
             "| offset | name | access | value / reset | meaning |",
             "| --- | --- | --- | --- | --- |"]
    for r in d["registers"]:
        v = (f"`{r['value']:#x}`" if "value" in r else
             f"reset {r['reset']}" if "reset" in r else "")
        doc = cell(r["doc"]) + "".join(
            f"<br>`[{f['lsb'] + f['width'] - 1}:{f['lsb']}]` {f['name']}: {cell(f['doc'])}"
            if f["width"] > 1 else f"<br>`[{f['lsb']}]` {f['name']}: {cell(f['doc'])}"
            for f in r["fields"])
        lines.append(f"| `{r['offset']:#04x}` | {r['name']} | {r['access']} | {v} | {doc} |")
    lines += ["", "Clamp flags: " + (", ".join(f"bit {i} `{k}`" for i, k in
                                                enumerate(info.clamp_kinds)) or "none") + ".",
              "", "Populations of spike ids: " + ", ".join(
                  f"`{p['name']}` {p['first']} .. {p['first'] + p['count'] - 1}"
                  for p in d["populations"]) + ".", "",
              f"Streams: a write beat is {s['write_tdata_bits']} bits (value in bytes 0 .. "
              f"{s['write_field_bytes'] - 1}, sign-extended; address in bytes "
              f"{s['write_field_bytes']} .. {2 * s['write_field_bytes'] - 1}); a spike beat "
              f"is {s['spike_tdata_bits']} bits (id in bytes 0 .. {s['spike_field_bytes'] - 1},"
              f" sweep in bytes {s['spike_field_bytes']} .. {2 * s['spike_field_bytes'] - 1}); "
              f"an empty sweep's marker has id {s['marker_id']:#x} and TUSER = 1."]
    if info.write_map:
        lines += ["", "Write addresses:", ""] + [
            f"- `{f}` .. `{f + c - 1}` {n}: {cell(d)}" for n, f, c, d in info.write_map]
    return "\n".join(lines) + "\n"
