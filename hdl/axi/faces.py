"""Every face a block can be generated behind (:data:`FACES`) and the files it is written as
(:func:`write_face`): ``uart`` (:class:`~cuneate.hdl.link.LinkedTop`, the board link),
``axi`` (:class:`~cuneate.hdl.axi.top.AxiTop`) and ``wishbone``
(:class:`~cuneate.hdl.wishbone.top.WishboneTop`)."""

from __future__ import annotations

import json
from pathlib import Path

from ..flow.verilog import write_block
from ..lib.payload import payload_spec
from ..lib.regmap import regmap_lines, regmap_markdown, stream_format, write_map_lines
from .face import FACE_IDLE_CYCLES, face_cycles
from .top import AxiTop

__all__ = ["FACES", "write_face", "face_description"]

#: face name -> what it is
FACES = {"uart": "the UART host link (COBS frames, CRC-32; the board top)",
         "axi": "AXI4-Stream writes and spikes, AXI4-Lite registers",
         "wishbone": "AXI4-Stream writes and spikes, Wishbone B4 pipelined registers"}


def _top(face: str, spec):
    if face == "axi":
        return AxiTop(spec)
    if face == "wishbone":
        from ..wishbone.top import WishboneTop
        return WishboneTop(spec)
    from ..link import LinkConfig, LinkedTop
    return LinkedTop(LinkConfig(spec))


def face_description(face: str, spec, top) -> dict:
    """What the face's JSON says beyond the block: the face, the payload, and for a bus face
    the streams' formats, the cycles a sweep takes behind it and whether the configured
    divider holds them (``free_running_fits``)."""
    info = spec.info
    d = {"block": f"{info.block} behind the {face} face", "face": face,
         "face_summary": FACES[face], "payload": info.to_dict(),
         "clock_hz": info.clock_hz, "update_hz": info.update_hz,
         "cycles_per_tick": info.cycles_per_tick}
    if face == "uart":
        d["link"] = top.lcfg.to_dict()
        return d
    need = face_cycles(info)
    d |= {"streams": stream_format(info), "face_idle_cycles": FACE_IDLE_CYCLES,
          "cycles_per_sweep": need, "free_running_fits": info.cycles_per_tick >= need,
          "register_map": top.regmap()}
    return d


def write_face(out, config, face: str, name: str, **spec_options) -> dict:
    """Write the block of ``config`` (a block configuration or payload spec; ``spec_options``
    to :func:`~cuneate.hdl.lib.payload.payload_spec`) behind ``face`` into ``out``:
    ``<name>.v`` (its header stating the ports and, for a bus face, the register map),
    ``<name>.json``, and for a bus face ``<name>.regmap.json`` and ``<name>.regmap.md``. The
    block's tick is the face's (external). Returns ``{"files": [...], "description": ...}``."""
    if face not in FACES:
        raise ValueError(f"unknown face {face!r}; known: {', '.join(FACES)}")
    spec = payload_spec(config, **spec_options)
    spec = spec if spec.external else spec.retimed()
    top = _top(face, spec)
    desc = face_description(face, spec, top)
    out = Path(out)
    if face == "uart":
        from ..link.codec import COUNTER_NAMES
        sections = {"the UART face's counters (READ_COUNTERS, in order)":
                    ["  " + ", ".join(COUNTER_NAMES)]}
        if spec.info.write_map:
            sections["write addresses (a WRITE frame's first + i)"] = write_map_lines(spec.info)
        return {"files": write_block(out, top, desc, name, sections), "description": desc}
    resets = {"TICK_DIVIDER": spec.info.cycles_per_tick}
    sections = {f"register map ({top.BUS['text']}; offset, name, access, meaning)":
                regmap_lines(spec.info, resets)}
    files = write_block(out, top, desc, name, sections)
    rj, rm = out / f"{name}.regmap.json", out / f"{name}.regmap.md"
    rj.write_text(json.dumps(desc["register_map"], indent=2) + "\n")
    rm.write_text(regmap_markdown(spec.info, resets, top.BUS, name))
    return {"files": files + [rj, rm], "description": desc}
