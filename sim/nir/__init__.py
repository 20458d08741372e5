"""NIR graphs on cuneate's hardware: reading and mapping (:mod:`.graph`, :mod:`.mapping`),
engines (:mod:`.engines`), the cocotb bench (:mod:`.bench`), export of cuneate's own networks
(:mod:`.export`), the cross-check against an independent NIR simulator (:mod:`.crosscheck`),
the SpikeTouch experiment (:mod:`.spiketouch`) and the ``nir`` commands (:mod:`.cli`).

Importing this package declares the network's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative neuron updates (HDL: cycles) per second on a 2-core machine, for estimates
register_block("nir", ("golden", "fixed", "amaranth", "icarus", "verilator"),
               speed={"golden": 2e6, "fixed": 2e5, "amaranth": 3e3, "icarus": 3e3,
                      "verilator": 3e4})
