"""cuneate.hdl: the hardware blocks, each in its own folder, and the machinery they share.

Blocks: :mod:`.izhikevich` (the afferent core), :mod:`.lif`, :mod:`.coincidence` (cuneate
neurons), :mod:`.network` (afferents -> coincidence detector on chip), :mod:`.link` (the host
link). Shared: :mod:`.lib` (fixed point, configuration errors, tick, bookkeeping, traces, kernel
helpers, UART), :mod:`.flow` (Verilog, tools, synthesis, SymbiYosys).

The names below are importable from here (``from cuneate.hdl import IzhikevichConfig``); each is
loaded on first use, so importing this package is cheap.
"""

from __future__ import annotations

import importlib

#: public name -> the module that defines it
_EXPORTS = {
    "ConfigError": ".lib.config", "QFormat": ".lib.fixed",
    "IzhikevichConfig": ".izhikevich", "IzhikevichTwin": ".izhikevich",
    "IzhikevichCore": ".izhikevich", "izhikevich_verilog": ".izhikevich",
    "generate_izhikevich": ".izhikevich",
    "LifConfig": ".lif", "LifTwin": ".lif", "LifCore": ".lif", "lif_verilog": ".lif",
    "generate_lif": ".lif",
    "CoincidenceConfig": ".coincidence", "CoincidenceTwin": ".coincidence",
    "CoincidenceDetector": ".coincidence", "coincidence_verilog": ".coincidence",
    "generate_coincidence": ".coincidence",
    "NetworkConfig": ".network", "NetworkTwin": ".network",
    "AfferentCuneateNetwork": ".network", "network_verilog": ".network",
    "generate_network": ".network",
    "LinkConfig": ".link", "LinkedCore": ".link", "link_config": ".link",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
