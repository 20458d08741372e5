"""A NIR graph with Input -> Delay -> Affine -> CubaLIF -> Affine -> LIF -> Output on the chained
LIF cores, on Icarus and Verilator: every update of every layer checked every cycle against the
bit-exact twin (zero mismatches) and the float64 golden step (within its bound), the output
stream equal to the last layer's spikes and to the fixed engine's."""

import json

import numpy as np
import pytest

from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.nir.crosscheck import crosscheck_graph
from cuneate.sim.nir.engines import run_network
from cuneate.sim.nir.graph import layers_of
from cuneate.sim.nir.mapping import map_graph


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_scoreboard(simulator, build_root):
    mapped = map_graph(layers_of(crosscheck_graph(n_in=6, n_hidden=10, n_out=4)),
                       scheme="exact")
    assert mapped.config.layers[0].syn_alpha is not None
    assert mapped.config.layers[0].max_input_delay > 0
    x = (np.random.default_rng(5).random((40, 6)) < 0.35).astype(float)
    run = run_network(simulator, mapped, x, build_dir=build_root / f"nir_{simulator}",
                      scoreboard=True)
    rep = run.clamp_counts
    print(f"\n{simulator}: " + json.dumps({k: rep[k] for k in ("layers", "failures",
                                                              "stream_matches")}))
    assert rep["failures"] == [] and rep["stream_matches"]
    for lay, cfg in zip(rep["layers"], mapped.config.layers):
        assert lay["sweeps_checked"] == 40 and lay["updates_checked"] == 40 * cfg.n_neurons
        assert lay["twin_mismatches"] == 0 and lay["golden_bound_violations"] == 0
        assert lay["spike_disagreements"] == 0 and lay["spikes"] > 0
    assert rep["layers"][0]["trace_bound_violations"] == 0
    fixed = run_network("fixed", mapped, x)
    assert np.array_equal(fixed.spikes, run.spikes)
