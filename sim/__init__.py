"""cuneate.sim: running the hardware and the models.

One folder per block (``izhikevich``, ``lif``, ``coincidence``, ``network``, ``link``: engines,
bench, scoreboard, sweep, experiments, commands), and the shared machinery: ``engines`` (the
engine registry, cocotb, Amaranth, the Verilator harness), ``host`` (transports, the host
driver, traces), ``scenes`` (schema, kinds, runner), ``cli`` (the ``cuneate`` command),
``sweep`` (the accuracy sweep framework), ``report``, ``decode``. The names below load on first
use.
"""

from __future__ import annotations

import importlib

_EXPORTS = {"run_scene": ".scenes.runner", "load_scene": ".scenes.scene",
            "parse_scene": ".scenes.scene", "default_scene": ".scenes.scene",
            "FbgDriver": ".host.driver", "AfferentEncoding": ".host.driver",
            "SpikeBatch": ".host.transport", "Transport": ".host.transport",
            "make_transport": ".izhikevich.engines", "run_engine": ".izhikevich.engines",
            "ENGINES": ".engines.registry"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
