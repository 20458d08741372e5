"""The plasticity block in simulation: engines (:mod:`.engines`), the cocotb bench
(:mod:`.bench`) and its scoreboard (:mod:`.scoreboard`), the compiled Verilator run of whole
protocols (:mod:`.fast`), the learning scene's protocol (:mod:`.protocol`).

Importing this package declares the block's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative synapse updates (HDL: cycles) per second on a 2-core machine, for estimates
register_block("plasticity", ("golden", "fixed", "amaranth", "icarus", "verilator",
                              "verilator-fast"),
               speed={"golden": 5e7, "fixed": 3e7, "amaranth": 2e3, "icarus": 5e3,
                      "verilator": 3e4, "verilator-fast": 1e6}, unit="cycles")
