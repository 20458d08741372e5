"""The channel fan-out in simulation: its engines (:mod:`.engines`), the cocotb bench
(:mod:`.bench`) and its scoreboard (:mod:`.scoreboard`).
"""
