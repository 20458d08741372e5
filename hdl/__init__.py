"""cuneate.hdl: the hardware blocks, each in its own folder, and the machinery they share.

Blocks: :mod:`.izhikevich` (the afferent core), :mod:`.lif`, :mod:`.coincidence` (cuneate
neurons), :mod:`.network` (afferents -> coincidence detector on chip), :mod:`.link` (the host
link). Shared: :mod:`.lib` (fixed point, configuration errors, tick, bookkeeping, traces, kernel
helpers, UART), :mod:`.flow` (Verilog, tools, synthesis, SymbiYosys).

The names below are importable from here (``from cuneate.hdl import IzhikevichConfig``); each is
loaded on first use, so importing this package is cheap.
"""

from __future__ import annotations

from .. import lazy_exports

#: public name -> the module that defines it
__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    ".lib.config": "ConfigError", ".lib.fixed": "QFormat",
    ".izhikevich": "IzhikevichConfig IzhikevichTwin IzhikevichCore izhikevich_verilog "
                   "generate_izhikevich",
    ".lif": "LifConfig LifTwin LifCore lif_verilog generate_lif",
    ".coincidence": "CoincidenceConfig CoincidenceTwin CoincidenceDetector coincidence_verilog "
                    "generate_coincidence",
    ".network": "NetworkConfig NetworkTwin AfferentCuneateNetwork network_verilog "
                "generate_network",
    ".link": "LinkConfig LinkedTop link_config"})
