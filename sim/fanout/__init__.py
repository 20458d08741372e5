"""The channel fan-out in simulation: its engines (:mod:`.engines`), the cocotb bench
(:mod:`.bench`) and its scoreboard (:mod:`.scoreboard`).

Importing this package declares the block's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative afferent currents (HDL: cycles) per second on a 2-core machine, for estimates
register_block("fanout", ("golden", "fixed", "icarus", "verilator"),
               speed={"golden": 2e7, "fixed": 1e7, "icarus": 5e3, "verilator": 5e4})
