"""NIR graphs on cuneate's hardware: reading and mapping (:mod:`.graph`, :mod:`.mapping`),
engines (:mod:`.engines`), the cocotb bench (:mod:`.bench`), export of cuneate's own networks
(:mod:`.export`), the cross-check against an independent NIR simulator (:mod:`.crosscheck`),
the SpikeTouch experiment (:mod:`.spiketouch`) and the ``nir`` commands (:mod:`.cli`).
"""
