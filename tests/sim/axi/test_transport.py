"""The ``axi`` engine (:class:`cuneate.sim.axi.transport.AxiTransport`): a scene through the block
behind the AXI face (Verilator, the C++ bus harness) gives the fixed engine's spikes, spike for
spike, with every counter of the driver's contract clean: the slide-texture example cut to one
trial of 60 ms, fixed against axi, and the whole default scene, fixed, board and axi (``cuneate
run --engines fixed,board,axi``); and the learning layer's protocol, its weights read back
after learning equal to the fixed engine's. All in the long lane (the harness's Verilator
build alone takes most of a minute)."""

import numpy as np
import pytest

from cuneate.sim.plasticity.engines import run_learning
from cuneate.sim.scenes import afferent, default_scene, example_path, parse_scene
from learning_case import small_layer


def _same(run, engines):
    ref = run.spikes[engines[0]]
    assert sum(map(len, ref)) > 0
    for e in engines[1:]:
        assert all(np.array_equal(a, b) for a, b in zip(ref, run.spikes[e])), e
        assert len(run.spikes[e]) == len(ref)
    c = run.counters["axi"]
    assert c["frames_lost"] == 0 and c["overflow"] == 0 and c["overrun"] == 0
    assert c["device_writes_refused"] == 0 and c["spikes_counted"] == c["spikes"]
    assert c["device_sweeps"] == c["sweeps_received"] > 0


@pytest.mark.long
def test_axi_engine_runs_a_short_scene_as_fixed():
    text = (example_path("slide_texture.toml").read_text()
            .replace("duration_ms = 500", "duration_ms = 60").replace("trials = 8", "trials = 1"))
    run = afferent.run(parse_scene(text, "short_slide.toml"), engines=["fixed", "axi"])
    _same(run, ["fixed", "axi"])


@pytest.mark.long
def test_fixed_board_and_axi_run_the_default_scene_alike():
    run = afferent.run(default_scene(), engines=["fixed", "board", "axi"])
    _same(run, ["fixed", "board", "axi"])


@pytest.mark.long
def test_the_learning_layer_learns_on_the_axi_engine_as_the_twin():
    """The layer's payload behind the AXI face: CN spikes and the weights read back after
    learning equal the fixed engine's (its twin)."""
    cfg, pres = small_layer()
    flags = [True, False]
    axi, fixed = (run_learning(e, cfg, pres, flags) for e in ("axi", "fixed"))
    assert fixed.spike_cn.size > 0 and not np.array_equal(fixed.weights_raw, cfg.weights_raw)
    assert np.array_equal(axi.weights_raw, fixed.weights_raw)
    for k in ("spike_pres", "spike_tick", "spike_cn", "counts"):
        assert np.array_equal(getattr(axi, k), getattr(fixed, k)), k
    c = axi.extra["counters"]
    assert c["device_writes_refused"] == 0 and c["device_sweeps"] == pres.n * pres.n_ticks + 2
