"""The host link in simulation: the cocotb bench of the linked core (:mod:`.bench`). The host
side of the link (the UART transport) lives with the boards (:mod:`cuneate.boards.uart`)."""
