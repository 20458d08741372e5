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




def lazy_exports(package: str, modules: dict):
    """``(__getattr__, __dir__, __all__)`` for ``package`` whose public names load on first
    use (PEP 562), so importing a package stays cheap for the command line. ``modules``: module
    (absolute, or relative to ``package``) -> the names it exports, space-separated."""
    exports = {name: mod for mod, names in modules.items() for name in names.split()}

    def getattr_(name: str):
        if name in exports:
            return getattr(importlib.import_module(exports[name], package), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def dir_():
        import sys
        return sorted(set(vars(sys.modules[package])) | set(exports))
    return getattr_, dir_, sorted(exports)


__getattr__, __dir__, _public = lazy_exports(__name__, {
    "cuneate.hdl.izhikevich": "IzhikevichConfig IzhikevichTwin IzhikevichCore",
    "cuneate.hdl.lif": "LifConfig LifTwin LifCore",
    "cuneate.hdl.coincidence": "CoincidenceConfig CoincidenceTwin CoincidenceDetector",
    "cuneate.hdl.network": "NetworkConfig NetworkTwin",
    "cuneate.hdl.lib.config": "ConfigError",
    "cuneate.sim.scenes.scene": "load_scene parse_scene default_scene",
    "cuneate.sim.scenes.runner": "run_scene",
    "cuneate.sim.host.driver": "FbgDriver"})
__all__ = ["__version__", "lazy_exports", *_public]
