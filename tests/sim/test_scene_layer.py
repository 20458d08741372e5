"""An afferent scene's cuneate layer (a ``model = "cuneate"`` population and its projections):
its fixed engine is the on-chip network's twin bit for bit, its golden engine the float64
cuneate model; the layer is decoded, compared between engines and written to the spike files
and the report; what is wrong with it is refused in one line; on the board engine it runs on
chip with the afferents and its trains equal fixed."""

import json

import numpy as np
import pytest

from cuneate.golden import coincidence as gcun
from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.sim import cli
from cuneate.sim.network.engines import run_network
from cuneate.sim.network.scene import CuneateLayer, layer_network, run_layer
from cuneate.sim.scenes import afferent, parse_scene
from cuneate.sim.scenes.schema import SceneError
from cuneate.sim.spikes import load_spikes
from layered_scene import LAYER, layered_text


def test_the_layer_runs_on_golden_and_fixed_is_decoded_and_reported(tmp_path):
    text = layered_text().replace('neighbours = 3', 'neighbours = 1\npopulation = "cn"')
    scene = parse_scene(text, "slide_layer.toml")
    run = afferent.run(scene)
    lay = run.layer
    # two cuneate neurons a trial (a field of one grating each), three classes of two trials
    assert lay["trial"] == [t for t in range(6) for _ in range(2)]
    assert lay["index"] == [0, 1] * 6
    block = next(b for b in run.ran["blocks"] if b["block"] == "coincidence_detector")
    assert block["fields"] == [[0], [1]] and block["fan_in"] == [2]
    assert block["delays_ms"] == [0.0, 1.0, 2.0] and block["synapses"] == 12 * 2
    for e in ("golden", "fixed"):
        assert sum(map(len, lay["spikes"][e])) > 20, e
    agr = run.agreement["cn: golden vs fixed"]
    assert agr["neurons"] == 12 and agr["spikes_a"] > 20
    # the decoder read the layer: two cuneate neurons a trial, four features each
    assert run.decoded["fixed"].accuracy is not None
    html = afferent.write_report(run, tmp_path).read_text()
    assert "features of cn" in html and "cuneate layer cn (12 cuneate neurons" in html
    summ = json.loads((tmp_path / "run.json").read_text())
    assert summ["decoded_population"] == "cn"
    assert summ["layer"]["spike_counts"] == {e: sum(map(len, lay["spikes"][e]))
                                             for e in ("golden", "fixed")}
    f = load_spikes(tmp_path / "spikes_fixed.npz")
    n_aff = len(run.neurons)
    assert len(f) == n_aff + 12 and list(f.population[n_aff:]) == ["cn"] * 12
    assert all(np.array_equal(a, b) for a, b in zip(f.trains()[n_aff:], lay["spikes"]["fixed"]))
    assert "cuneate layer cn: 12 neurons" in afferent.format_run(run)


def small_layer(seed=3, n=12, m=3):
    rng = np.random.default_rng(seed)
    core = IzhikevichConfig(n_neurons=n, clock_hz=16e3 * n, update_hz=16e3,
                            param_sets=("RS", "IB"), neuron_sets=[i % 2 for i in range(n)],
                            tick_source="external")
    weights = np.where(rng.random((m, n)) < 0.6, rng.uniform(10.0, 20.0, (m, n)), 0.0)
    delays = rng.integers(0, 24, (m, n))
    net = layer_network(core, delays, weights, "RS")
    layer = CuneateLayer("cn", m, [[0]] * m, [0] * m, list(range(m)), delays, weights, "RS",
                         net)
    # eight 12.5 ms steps of random afferent currents
    return layer, np.repeat(rng.uniform(0.0, 14.0, (8, n)), 200, axis=0)


def test_the_layers_fixed_engine_is_the_networks_twin():
    layer, currents = small_layer()
    ref = run_network("fixed", layer.network, currents)
    got, counters = run_layer("fixed", layer, ref.population("afferent"), len(currents))
    want = ref.population("cuneate")
    assert sum(map(len, want)) > 10
    assert all(np.array_equal(a, b) for a, b in zip(got, want))
    assert counters["spikes"] == sum(map(len, want)) and counters["events"] > 30


def test_the_layers_golden_engine_is_the_float_cuneate_model():
    layer, currents = small_layer(seed=4)
    aff = run_network("golden", layer.network, currents).population("afferent")
    got, _ = run_layer("golden", layer, aff, len(currents))
    det = layer.network.det
    want = gcun.simulate_cuneate(aff, layer.delays * det.dt_ms, len(currents) * det.dt_ms,
                                 dt_ms=det.dt_ms, J=1.0, weights=layer.weights, params="RS",
                                 tau_rise_ms=det.tau_rise_ms, tau_decay_ms=det.tau_decay_ms)
    assert sum(map(len, want.spikes_ms)) > 5
    assert all(np.array_equal(a, b) for a, b in zip(got, want.spikes_ms))


@pytest.mark.parametrize("edit, key, reason", [
    (("size = 2", "size = 3"), "population[2].size", "at most one cuneate neuron a grating"),
    (('inputs = ["sa", "fa"]', 'inputs = ["sa", "sa"]'), "population[2].inputs[1]",
     "distinct afferent (Izhikevich) populations"),
    (("delays_ms = [1, 2]", "delays_ms = [1, 2, 3]"), "projection[1].delays_ms",
     "one per cuneate neuron (2), got 3"),
    (("delays_ms = [1, 2]", "delays_ms = [1.01]"), "projection[1].delays_ms",
     "not a whole number of ticks"),
    (('source = "fa"', 'source = "sa"'), "projection[1]", "one projection from each input"),
    (("weight = 10.0\ndelays", "weight = 0\ndelays"), "projection[1].weight", "must be > 0"),
    (('encoding = "FA"\ngain = 30', 'encoding = "FA"\ngain = 30\n[[projection]]\nsource = "fa"'
      '\ntarget = "sa"'), "projection[0]", "one projection from each input"),
])
def test_a_wrong_layer_is_refused_in_one_line(edit, key, reason):
    text = layered_text().replace(*edit)
    with pytest.raises(SceneError) as exc:
        parse_scene(text, "bad.toml")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"bad.toml: {key}: ") and reason in msg, msg


@pytest.mark.parametrize("edit, key, reason", [
    ((('encoding = "SA"', 'encoding = "SA"\ngratings = [0]'),
      ('encoding = "FA"', 'encoding = "FA"\ngratings = [0]')), "population[2].gratings",
     "cuneate neuron 1's field (gratings 1) holds none of its inputs' afferents"),
    ((("weight = 10.0\ndelays", "weight = 1e6\ndelays"),), "population[2]",
     "the cuneate layer's detector is refused: "),
    ((('engines = ["golden", "fixed"]', 'engines = ["golden", "fixed", "verilator"]'),),
     "run.engines[2]", "engine 'verilator' does not run the cuneate layer"),
])
def test_a_layer_its_detector_or_its_engines_cannot_hold_is_refused_at_parse(edit, key,
                                                                             reason):
    text = layered_text()
    for e in edit:
        text = text.replace(*e)
    with pytest.raises(SceneError) as exc:
        parse_scene(text, "bad.toml")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"bad.toml: {key}: ") and reason in msg, msg


def test_a_missing_projection_and_an_unknown_decoded_population_are_refused():
    no_fa = LAYER[:LAYER.index('[[projection]]\nsource = "fa"')]
    with pytest.raises(SceneError, match=r"^bad.toml: projection: the cuneate layer needs a "
                                         r"projection from 'fa' to 'cn'"):
        parse_scene(layered_text(no_fa), "bad.toml")
    text = layered_text().replace("neighbours = 3", 'neighbours = 3\npopulation = "cuneate"')
    with pytest.raises(SceneError, match=r"decoder.population: 'cuneate': an afferent scene "
                                         r"decodes one of its populations \(sa, fa, cn\)"):
        parse_scene(text, "bad.toml")


def test_an_engine_without_the_layer_is_refused(tmp_path, capsys):
    p = tmp_path / "layer.toml"
    p.write_text(layered_text())
    assert cli.main(["run", str(p), "--engines", "fixed,verilator", "-q",
                     "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"cuneate run: {p}: population model \"cuneate\": engine 'verilator' does "
                   f"not run the cuneate layer (engines that do: golden, fixed, board)"]


@pytest.mark.long
def test_the_layer_on_board_runs_on_chip_and_equals_fixed():
    scene = parse_scene(layered_text(duration_ms=150, trials=1,
                                     engines='["fixed", "board"]'), "slide_layer.toml")
    run = afferent.run(scene)
    lay = run.layer
    a, b = lay["spikes"]["fixed"], lay["spikes"]["board"]
    assert sum(map(len, a)) > 5
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert all(np.array_equal(x, y) for x, y in zip(run.spikes["fixed"], run.spikes["board"]))
    # the board's counters hold both populations' spikes, none lost
    c = run.counters["board"]
    assert c["frames_lost"] == 0
    assert c["spikes"] == sum(map(len, run.spikes["board"])) + sum(map(len, b))
