"""The coincidence block in simulation: engines (:mod:`.engines`), the cocotb bench
(:mod:`.bench`) and its scoreboard (:mod:`.scoreboard`), the word-width sweep (:mod:`.sweep`),
the ridge-angle experiment (:mod:`.experiments`) and the ``coincidence`` commands
(:mod:`.cli`).

Importing this package declares the block's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative target updates (HDL: cycles) per second on a 2-core machine, for estimates
register_block("coincidence", ("golden", "fixed", "amaranth", "icarus", "verilator"),
               speed={"golden": 8e5, "fixed": 8e4, "amaranth": 5e3, "icarus": 5e3,
                      "verilator": 5e4})
