"""cuneate.boards: one module per board (``ulx3s``, ``icebreaker``, ``atlys``, ``arty``), the
registry of targets (``targets.TARGETS``), the board top and clock plans (``top``), sizing a core
to a device (``sizing``), builds and reports (``build``) and the host side of the link
(``uart.UartTransport``). The names below load on first use."""

from __future__ import annotations

from .. import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    ".targets": "TARGETS", ".build": "build_target", ".sizing": "size_core",
    ".uart": "UartTransport"})
