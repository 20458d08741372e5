"""The host link in simulation: the cocotb bench of the linked core (:mod:`.bench`), the link
gateware behind a simulated serial port (:mod:`.engines`: the Amaranth simulator, and the
``board`` engine's compiled board top), that board top on a pseudo-terminal for host software
(:mod:`.pty`) and line faults (:mod:`.faults`). The host side of the
link (the UART transport) is :mod:`cuneate.sim.host.uart`."""
