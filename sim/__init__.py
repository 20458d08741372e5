"""cuneate.sim: running the hardware and the models.

One folder per block (``izhikevich``, ``lif``, ``coincidence``, ``network``, ``link``: engines,
bench, scoreboard, sweep, experiments, commands), and the shared machinery: ``engines`` (the
engine registry, cocotb, Amaranth, the Verilator harness), ``host`` (transports, the host
driver, traces), ``scenes`` (schema, kinds, runner), ``cli`` (the ``cuneate`` command),
``sweep`` (the accuracy sweep framework), ``report``, ``decode``. The names below load on first
use.
"""

from __future__ import annotations

from .. import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    ".scenes.runner": "run_scene",
    ".scenes.scene": "load_scene parse_scene default_scene",
    ".host.driver": "FbgDriver AfferentEncoding",
    ".host.transport": "SpikeBatch Transport",
    ".izhikevich.engines": "make_transport run_engine",
    ".engines.registry": "ENGINES"})
