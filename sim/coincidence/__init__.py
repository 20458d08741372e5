"""The coincidence block in simulation: engines (:mod:`.engines`), the cocotb bench
(:mod:`.bench`) and its scoreboard (:mod:`.scoreboard`), the word-width sweep (:mod:`.sweep`),
the ridge-angle experiment (:mod:`.experiments`) and the ``coincidence`` commands
(:mod:`.cli`).
"""
