"""A block behind a bus face, with the standard port names (:class:`BusTop`): the block's
payload, the :class:`~cuneate.hdl.axi.face.StreamFace` and a register bus bridge.

:class:`AxiTop`: ``s_axis_*`` (writes), ``m_axis_*`` (spikes), ``s_axil_*`` (AXI4-Lite
registers). :class:`~cuneate.hdl.wishbone.top.WishboneTop` has ``wb_*`` in place of
``s_axil_*``. Clock ``clk`` and synchronous reset ``rst`` (active high) as every top of the
project.
"""

from __future__ import annotations

from amaranth import Module, ResetInserter
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..flow.verilog import verilog_text
from ..lib.config import ConfigError
from ..lib.payload import PayloadSpec
from ..lib.regmap import regmap_dict
from .face import StreamFace
from .lite import ADDR_BITS, AxiLiteRegisters
from .stream import axis_in_layout, axis_out_layout

__all__ = ["BusTop", "AxiTop", "top_verilog", "PORT_MEANINGS"]

#: what the streams' and the buses' ports mean (the Verilog header's column)
PORT_MEANINGS = {
    "s_axis_tdata": "write beat: value (low field, sign-extended), address (high field)",
    "s_axis_tvalid": "write beat offered", "s_axis_tready": "write beat taken",
    "s_axis_tlast": "the burst's last beat",
    "m_axis_tdata": "spike beat: id (low field), sweep number (high field)",
    "m_axis_tvalid": "spike beat offered", "m_axis_tready": "spike beat taken",
    "m_axis_tlast": "the sweep's last beat", "m_axis_tuser": "an empty sweep's marker beat",
    "s_axil_awaddr": "AXI4-Lite write address (bytes)", "s_axil_awvalid": "write address valid",
    "s_axil_awready": "write address taken", "s_axil_wdata": "write data",
    "s_axil_wstrb": "write byte enables", "s_axil_wvalid": "write data valid",
    "s_axil_wready": "write data taken", "s_axil_bresp": "write response (0 OKAY, 2 SLVERR)",
    "s_axil_bvalid": "write response valid", "s_axil_bready": "write response taken",
    "s_axil_araddr": "AXI4-Lite read address (bytes)", "s_axil_arvalid": "read address valid",
    "s_axil_arready": "read address taken", "s_axil_rdata": "read data",
    "s_axil_rresp": "read response (0 OKAY, 2 SLVERR)", "s_axil_rvalid": "read data valid",
    "s_axil_rready": "read data taken",
    "wb_cyc": "Wishbone cycle", "wb_stb": "request strobe", "wb_we": "write enable",
    "wb_adr": "word address (byte offset / 4)", "wb_dat_w": "write data",
    "wb_sel": "byte selects", "wb_dat_r": "read data", "wb_ack": "request answered",
    "wb_err": "request refused (see the register map)", "wb_stall": "always 0 (no wait)",
}


class BusTop(wiring.Component):
    """The block of ``spec`` behind a :class:`StreamFace` whose registers a ``bridge`` (a
    component with a ``regs`` port and its bus signals) serves; the bus signals become ports
    named ``<prefix><signal>``. Parts: the attributes ``payload``, ``face``, ``bridge``."""

    #: the bus's name in the register map's description and its addressing
    BUS: dict = {}
    PORT_MEANINGS = PORT_MEANINGS

    def __init__(self, spec: PayloadSpec, bridge, prefix: str):
        if not isinstance(spec, PayloadSpec) or not spec.external:
            raise ConfigError("a bus face drives the block's ticks: give a payload spec with "
                              "an external tick (PayloadSpec.retimed())")
        info = spec.info
        if info.cycles_per_tick < info.busy_cycles:
            raise ConfigError(f"a sweep of {info.cycles_per_tick} cycles cannot hold the "
                              f"{info.block}'s {info.busy_cycles} cycles of work a tick")
        self.spec, self.info, self.prefix = spec, info, prefix
        self.payload = spec.build()
        self.face = StreamFace(info)
        self.bridge = bridge
        wi, wo = axis_in_layout(info)["tdata"].shape, axis_out_layout(info)["tdata"].shape
        members = {"s_axis_tdata": In(wi), "s_axis_tvalid": In(1), "s_axis_tready": Out(1),
                   "s_axis_tlast": In(1),
                   "m_axis_tdata": Out(wo), "m_axis_tvalid": Out(1), "m_axis_tready": In(1),
                   "m_axis_tlast": Out(1), "m_axis_tuser": Out(1)}
        for name, member in bridge.signature.members.items():
            if name != "regs":
                members[prefix + name] = member
        super().__init__(members)

    def regmap(self) -> dict:
        """The register map of this top (:func:`~cuneate.hdl.lib.regmap.regmap_dict`)."""
        return regmap_dict(self.info, {"TICK_DIVIDER": self.info.cycles_per_tick}, self.BUS)

    def elaborate(self, platform):
        m = Module()
        face, bridge = self.face, self.bridge
        m.submodules.payload = ResetInserter(face.soft_reset)(self.payload)
        m.submodules.face, m.submodules.bridge = face, bridge
        wiring.connect(m, face.payload, self.payload)
        wiring.connect(m, bridge.regs, face.regs)
        s, o = face.s_axis, face.m_axis
        m.d.comb += [s.payload.tdata.eq(self.s_axis_tdata), s.valid.eq(self.s_axis_tvalid),
                     s.payload.tlast.eq(self.s_axis_tlast), self.s_axis_tready.eq(s.ready),
                     self.m_axis_tdata.eq(o.payload.tdata), self.m_axis_tvalid.eq(o.valid),
                     self.m_axis_tlast.eq(o.payload.tlast), self.m_axis_tuser.eq(o.payload.tuser),
                     o.ready.eq(self.m_axis_tready)]
        for name, member in bridge.signature.members.items():
            if name == "regs":
                continue
            mine, theirs = getattr(self, self.prefix + name), getattr(bridge, name)
            m.d.comb += theirs.eq(mine) if member.flow == In else mine.eq(theirs)
        return m


class AxiTop(BusTop):
    """The block of ``spec`` behind the AXI face: ``s_axis_*``, ``m_axis_*``, ``s_axil_*``."""

    BUS = {"name": "axi4-lite", "data_bits": 32, "addr_bits": ADDR_BITS,
           "text": f"AXI4-Lite (s_axil_*), 32-bit data, {ADDR_BITS}-bit byte addresses"}

    def __init__(self, spec: PayloadSpec):
        super().__init__(spec, AxiLiteRegisters(), "s_axil_")


def top_verilog(top: BusTop, name: str) -> str:
    """The Verilog of a bus top (no header; :func:`~cuneate.hdl.flow.verilog.write_block`
    writes it with one)."""
    return verilog_text(top, name)
