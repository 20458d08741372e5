"""cuneate.boards: one module per board (``ulx3s``, ``icebreaker``, ``atlys``, ``arty``), the
registry of targets (``targets.TARGETS``), the board top and clock plans (``top``), sizing a core
to a device (``sizing``), builds and reports (``build``) and the host side of the link
(``uart.UartTransport``). The names below load on first use."""

from __future__ import annotations

import importlib

_EXPORTS = {"TARGETS": ".targets", "build_target": ".build", "size_core": ".sizing",
            "UartTransport": ".uart"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
