"""cuneate.golden: the float64 reference models, one model per file, each stating its scheme.

``izhikevich`` (and ``behaviours``, Izhikevich's published panels), ``lif``, ``synapses``,
``coincidence`` (cuneate neurons as coincidence detectors), ``encoders`` (SA/FA), ``fbg`` (the
Bragg shift and the front-end filters), ``tactile`` (contact physics and sensor effects),
``metrics`` (spike-train metrics). The names below load on first use.
"""

from __future__ import annotations

import importlib

_EXPORTS = {"simulate": ".izhikevich", "IzhikevichParams": ".izhikevich",
            "PRESETS": ".izhikevich", "DivergenceError": ".izhikevich",
            "BEHAVIOURS": ".behaviours", "simulate_lif": ".lif",
            "simulate_discrete_lif": ".lif", "simulate_cuneate": ".coincidence",
            "victor_purpura": ".metrics", "compare_trains": ".metrics",
            "compare_populations": ".metrics"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
