"""The LIF block in simulation: engines (:mod:`.engines`), the cocotb bench (:mod:`.bench`) and
its scoreboard (:mod:`.scoreboard`), the word-width sweep (:mod:`.sweep`), the skin and
quantization experiments (:mod:`.experiments`) and the ``lif`` commands (:mod:`.cli`).
"""
