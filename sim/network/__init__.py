"""The on-chip afferent -> cuneate network in simulation: engines (:mod:`.engines`), the cocotb
bench (:mod:`.bench`, with the coincidence scoreboard) and the ``network`` commands
(:mod:`.cli`).

Importing this package declares the block's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative afferent updates (HDL: cycles) per second on a 2-core machine, for estimates
register_block("network", ("golden", "fixed", "amaranth", "icarus", "verilator", "board"),
               speed={"golden": 8e5, "fixed": 8e4, "amaranth": 5e3, "icarus": 5e3,
                      "verilator": 5e4, "board": 1e4})
