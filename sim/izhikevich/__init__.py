"""The Izhikevich block in simulation: engines and transports (:mod:`.engines`), the cocotb
bench (:mod:`.bench`) and its per-sweep scoreboard (:mod:`.scoreboard`), the accuracy sweep's
points and batteries (:mod:`.sweep`) and the ``simulate``/``generate izhikevich`` commands
(:mod:`.cli`).

Importing this package declares the block's engines to the registry (and nothing else).
"""

from ..engines.registry import register_block

#: conservative neuron updates (HDL: cycles) per second on a 2-core machine, for estimates
register_block("izhikevich", ("golden", "fixed", "amaranth", "icarus", "verilator",
                              "verilator-fast", "board", "axi"),
               speed={"golden": 15e6, "fixed": 2e6, "amaranth": 4e3, "icarus": 2.5e3,
                      "verilator": 4e4, "verilator-fast": 1e6, "board": 1e5, "axi": 1e6})
