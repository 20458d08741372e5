"""cuneate: FPGA hardware for neuromorphic touch, generated with Amaranth HDL and proven cycle by
cycle.

Packages: :mod:`cuneate.golden` (float64 models), :mod:`cuneate.hdl` (the blocks: configuration,
datapath, twin, RTL), :mod:`cuneate.sim` (engines, host driver, scenes, sweeps, the ``cuneate``
command), :mod:`cuneate.boards` (board targets and builds). docs/architecture.md is the map.

What a notebook user needs is importable from here and loads on first use::

    from cuneate import IzhikevichConfig, IzhikevichTwin, load_scene, run_scene
"""

from __future__ import annotations

import importlib

try:
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as _dist_version
    __version__ = _dist_version("cuneate")
except PackageNotFoundError:           # pragma: no cover - a source tree that is not installed
    __version__ = "0+unknown"

#: public name -> the module that defines it
_EXPORTS = {
    "IzhikevichConfig": "cuneate.hdl.izhikevich", "IzhikevichTwin": "cuneate.hdl.izhikevich",
    "IzhikevichCore": "cuneate.hdl.izhikevich",
    "LifConfig": "cuneate.hdl.lif", "LifTwin": "cuneate.hdl.lif", "LifCore": "cuneate.hdl.lif",
    "CoincidenceConfig": "cuneate.hdl.coincidence",
    "CoincidenceTwin": "cuneate.hdl.coincidence",
    "CoincidenceDetector": "cuneate.hdl.coincidence",
    "NetworkConfig": "cuneate.hdl.network", "NetworkTwin": "cuneate.hdl.network",
    "ConfigError": "cuneate.hdl.lib.config",
    "load_scene": "cuneate.sim.scenes.scene", "parse_scene": "cuneate.sim.scenes.scene",
    "default_scene": "cuneate.sim.scenes.scene", "run_scene": "cuneate.sim.scenes.runner",
    "FbgDriver": "cuneate.sim.host.driver",
}

__all__ = ["__version__", *sorted(_EXPORTS)]


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'cuneate' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
