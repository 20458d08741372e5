"""What the link's tests (Amaranth simulator, cocotb) expect of a run: the protocol model's
spike frames and the twin's spikes with the currents switched at one sweep."""

import numpy as np

from cuneate.hdl.izhikevich import IzhikevichTwin
from cuneate.hdl.link.codec import FrameDecoder


def model_frames(model, frames, sweeps):
    """``(tick, payload)`` of every frame ``model`` (a :class:`LinkModel`) answers to
    ``frames`` (the host's encoded frames) and ``sweeps`` sweeps."""
    ref = model.feed(b"".join(frames))
    model.advance(sweeps)
    ref += model.feed(b"")
    return [(m.tick, m.payload) for m in FrameDecoder().feed(ref)]


def twin_spikes(core, cur0, cur1, switched, at, sweeps):
    """``(sweep, neuron)`` of every spike of the twin of ``core`` over ``sweeps`` sweeps, its
    currents ``cur0``, the neurons ``switched`` (a slice) taking ``cur1``'s from sweep ``at``."""
    twin = IzhikevichTwin(core)
    twin.I[:] = cur0
    spikes = []
    for k in range(sweeps):
        if k == at:
            twin.I[switched] = cur1[switched]
        spikes += [(k, int(n)) for n in np.flatnonzero(twin.sweep())]
    return spikes
