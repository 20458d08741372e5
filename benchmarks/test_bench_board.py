"""The ``board`` engine on the shipped afferent scenes: what running the board top (UART link +
core, Verilator) through its simulated serial line costs, and what the link carries.

Per scene and host mode (writes sent ahead, lockstep): wall time of the stream, simulated
cycles and cycles a second, the device's cycles against its sweeps at the tick rate (1: it never
waited for the host), frames and bytes each way per second of scene time and the load at
3 Mbaud. The peer, measured in the same run: the bare core compiled with the ``verilator-fast``
harness, free-running at the same cycles per sweep (the cost of the link, the UART line model
and the host's Python). Printed and written to ``benchmarks/results/board_engine.json``; asserts
only that every run equals the twin.
"""

import time

import numpy as np
import pytest

from cuneate.sim.engines.verilator_fast import raw_cycle_rate
from cuneate.sim.izhikevich.engines import TwinTransport
from cuneate.sim.link.engines import BoardTransport
from cuneate.sim.scenes import afferent
from cuneate.sim.scenes.scene import default_scene, example_path, load_scene

from .conftest import report

pytestmark = pytest.mark.benchmark

SCENES = ("default", "pulse_amplitudes", "slide_texture")


def _prepare(name):
    scene = default_scene() if name == "default" else load_scene(example_path(name))
    _, _, traces, infos, _ = afferent.synthesize(scene)
    neurons = afferent.build_neurons(scene, len(traces))
    cfg, _ = afferent.build_izhikevich(scene, neurons)
    drv, currents, _ = afferent.front_end(scene, neurons, traces, infos, cfg)
    raw, _ = drv.quantize(currents)
    return scene, cfg, drv, raw, currents.shape[0] * drv.hold_ticks


def test_board_engine_on_the_shipped_scenes():
    rows = []
    for name in SCENES:
        scene, cfg, drv, raw, n_ticks = _prepare(name)
        tw = TwinTransport()
        tw.open(cfg)
        ref = drv.stream(tw, None, n_ticks, raw=raw).spikes
        seconds = n_ticks / cfg.update_hz
        for ahead in (True, False):
            tr = BoardTransport(ahead=ahead)
            tr.open(cfg)
            t0 = time.perf_counter()
            try:
                got = drv.stream(tr, None, n_ticks, raw=raw).spikes
            finally:
                tr.close()
            wall = time.perf_counter() - t0
            f = tr.figures()
            assert np.array_equal(got.tick, ref.tick) and np.array_equal(got.neuron, ref.neuron)
            rows.append({
                "scene": name, "host": "ahead" if ahead else "lockstep",
                "neurons": len(drv.encodings), "sweeps": n_ticks, "wall_s": wall,
                "cycles": f["cycles"], "cycles_per_s": f["cycles_per_s"],
                "x_sweep_time": f["cycles_per_sweep_rate"],
                "frames_in_per_s": f["frames_to_device"] / seconds,
                "frames_out_per_s": f["frames_from_device"] / seconds,
                "bytes_in_per_s": f["bytes_to_device"] / seconds,
                "bytes_out_per_s": f["bytes_from_device"] / seconds,
                "load_3M_in_pct": 100 * f["bytes_to_device"] / seconds * 10 / 3e6,
                "spikes": len(ref)})
        peer = raw_cycle_rate(tr.lcfg.core, 2_000_000)
        rows[-1]["peer_bare_core_cycles_per_s"] = peer["cycles_per_s"]
        rows[-2]["peer_bare_core_cycles_per_s"] = peer["cycles_per_s"]
    for r in rows:
        r["x_slower_than_bare_core"] = r["peer_bare_core_cycles_per_s"] / r["cycles_per_s"]
    report("board_engine", "board engine: the shipped afferent scenes through the simulated "
           "serial line (peer: the bare core compiled, free-running)", rows)
