"""The LIF block in simulation: engines (:mod:`.engines`), the cocotb bench (:mod:`.bench`) and
its scoreboard (:mod:`.scoreboard`), the word-width sweep (:mod:`.sweep`), the skin and
quantization experiments (:mod:`.experiments`) and the ``lif`` commands (:mod:`.cli`).

Importing this package declares the block's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative neuron updates (HDL: cycles) per second on a 2-core machine, for estimates
register_block("lif", ("golden", "fixed", "amaranth", "icarus", "verilator", "board"),
               speed={"golden": 8e5, "fixed": 3e5, "amaranth": 3.3e3, "icarus": 3.3e3,
                      "verilator": 3.3e4, "board": 1e3})
