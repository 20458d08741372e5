"""The plasticity block in simulation: engines (:mod:`.engines`), the cocotb bench
(:mod:`.bench`) and its scoreboard (:mod:`.scoreboard`), the compiled Verilator run of whole
protocols (:mod:`.fast`), the learning scene's protocol (:mod:`.protocol`).

Its engines register themselves (:mod:`.engines`).
"""
