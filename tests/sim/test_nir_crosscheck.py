"""The cross-check lane (``make crosscheck``): the Done-when graph (Input -> Delay -> Affine ->
CubaLIF -> Affine -> LIF -> Output) on cuneate's golden and fixed engines against snnTorch, an
independent NIR consumer in its own environment, spike counts per output neuron within the
stated tolerances (:data:`cuneate.sim.nir.crosscheck.TOLERANCE`)."""

import json

import numpy as np
import pytest

from cuneate.sim.nir.crosscheck import compare, crosscheck_graph, peer_python

pytestmark = pytest.mark.crosscheck


@pytest.fixture(scope="module")
def peer():
    py, why = peer_python()
    if py is None:
        pytest.fail(f"snnTorch's environment is not available: {why}")
    return py


@pytest.mark.parametrize("seed", [0, 1])
def test_against_snntorch(peer, seed):
    x = (np.random.default_rng(seed).random((400, 8)) < 0.15).astype(float)
    res = compare(peer, crosscheck_graph(seed=3 + seed), x, engines=("golden", "fixed"))
    print("\n" + json.dumps(res))
    assert sum(res["snntorch_counts"]) > 50
    # the same recursion in float64: identical counts
    assert res["pairs"]["golden-euler"]["identical"], res["pairs"]["golden-euler"]
    for key, pair in res["pairs"].items():
        assert pair["within_tolerance"], (key, pair)
