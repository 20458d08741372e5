"""The Izhikevich block in simulation: engines and transports (:mod:`.engines`), the cocotb
bench (:mod:`.bench`) and its per-sweep scoreboard (:mod:`.scoreboard`), the accuracy sweep's
points and batteries (:mod:`.sweep`) and the ``simulate``/``generate izhikevich`` commands
(:mod:`.cli`).
"""
