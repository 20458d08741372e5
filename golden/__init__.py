"""cuneate.golden: the float64 reference models, one model per file, each stating its scheme.

``izhikevich`` (and ``behaviours``, Izhikevich's published panels), ``lif``, ``synapses``,
``coincidence`` (cuneate neurons as coincidence detectors), ``encoders`` (SA/FA), ``fbg`` (the
Bragg shift and the front-end filters), ``tactile`` (contact physics and sensor effects),
``metrics`` (spike-train metrics). The names below load on first use.
"""

from __future__ import annotations

from .. import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    ".izhikevich": "simulate IzhikevichParams PRESETS DivergenceError",
    ".behaviours": "BEHAVIOURS",
    ".lif": "simulate_lif simulate_discrete_lif",
    ".coincidence": "simulate_cuneate",
    ".metrics": "victor_purpura compare_trains compare_populations"})
