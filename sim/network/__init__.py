"""The on-chip afferent -> cuneate network in simulation: engines (:mod:`.engines`), the cocotb
bench (:mod:`.bench`, with the coincidence scoreboard) and the ``network`` commands
(:mod:`.cli`).
"""
