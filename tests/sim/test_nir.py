"""NIR graphs on the LIF cores: reading and refusals, the golden model against closed forms, the
twin against the Amaranth RTL (bit-exact), export and read-back of the skin and ridge second
layers, the commands' exit codes."""

import math

import h5py
import nir
import numpy as np
import pytest

from cuneate.golden.nir import NirLayer, simulate_layers
from cuneate.hdl.coincidence import CoincidenceConfig
from cuneate.sim.cli import main
from cuneate.sim.nir.crosscheck import crosscheck_graph
from cuneate.sim.nir.engines import run_network
from cuneate.sim.nir.export import ridge_from_graph, scene_graph, skin_from_graph
from cuneate.sim.nir.graph import NirError, layers_of, read_graph
from cuneate.sim.nir.mapping import map_graph
from cuneate.sim.scenes.scene import load_scene

EXAMPLES = __import__("pathlib").Path(__import__("cuneate.sim.scenes.examples",
                                                 fromlist=["x"]).__file__).parent
DT = 1e-4


def _lif(n, tau=1e-3, r=None, thr=1.0):
    full = lambda v: np.full(n, float(v))  # noqa: E731
    return nir.LIF(tau=full(tau), r=full(tau / DT if r is None else r), v_leak=full(0),
                   v_threshold=full(thr), v_reset=full(0))


def _spikes(steps, n, p, seed=0):
    return (np.random.default_rng(seed).random((steps, n)) < p).astype(float)


# ---------------------------------------------------------------------------------------------
# reading and refusals

def test_not_nir_and_truncated(tmp_path):
    bad = tmp_path / "bad.nir"
    bad.write_text("not a graph")
    with pytest.raises(NirError, match="not a NIR file"):
        read_graph(bad)
    good = tmp_path / "g.nir"
    nir.write(good, crosscheck_graph())
    cut = tmp_path / "cut.nir"
    cut.write_bytes(good.read_bytes()[:1500])
    with pytest.raises(NirError, match="truncated or damaged"):
        read_graph(cut)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.create_dataset("x", data=[1, 2])
    with pytest.raises(NirError, match="no 'node' group"):
        read_graph(other)
    with h5py.File(good, "r+") as f:
        del f["node/nodes/lif/type"]
        f["node/nodes/lif/type"] = np.bytes_("Izhikevich")
    with pytest.raises(NirError, match="node 'lif': type 'Izhikevich' is not a NIR node type"):
        read_graph(good)


@pytest.mark.parametrize("nodes,edges,match", [
    ({"in": nir.Input(input_type=np.array([4])),
      "conv": nir.Conv1d(input_shape=4, weight=np.ones((2, 1, 3)), stride=1, padding=0,
                         dilation=1, groups=1, bias=np.zeros(2)),
      "out": nir.Output(output_type=np.array([2]))},
     [("in", "conv"), ("conv", "out")], "node 'conv' \\(Conv1d\\): convolutions"),
    ({"in": nir.Input(input_type=np.array([3])), "w": nir.Linear(weight=np.eye(3)),
      "lif": _lif(3), "rec": nir.Linear(weight=np.eye(3)),
      "out": nir.Output(output_type=np.array([3]))},
     [("in", "w"), ("w", "lif"), ("lif", "rec"), ("rec", "lif"), ("lif", "out")],
     "node 'lif' \\(LIF\\): 2 inputs merge"),
    ({"in": nir.Input(input_type=np.array([3])), "lif": _lif(3), "a": _lif(3), "b": _lif(3),
      "out": nir.Output(output_type=np.array([3]))},
     [("in", "lif"), ("lif", "a"), ("lif", "b"), ("a", "out"), ("b", "out")],
     "node 'lif' \\(LIF\\): 2 successors"),
])
def test_shapes_the_chain_cannot_hold(nodes, edges, match):
    with pytest.raises(NirError, match=match):
        layers_of(nir.NIRGraph(nodes=nodes, edges=edges, type_check=False))


def test_hardware_refusals():
    n = 4
    g = nir.NIRGraph.from_list(nir.Input(input_type=np.array([n])), nir.Linear(weight=np.eye(n)),
                               nir.IF(r=np.ones(n), v_threshold=np.ones(n)),
                               nir.Output(output_type=np.array([n])))
    with pytest.raises(NirError, match="node 'if' \\(IF\\): no leak"):
        map_graph(layers_of(g))
    simulate_layers(layers_of(g).layers, _spikes(20, n, 0.5), DT)      # golden runs it
    g = nir.NIRGraph.from_list(nir.Input(input_type=np.array([n])),
                               nir.Delay(delay=np.full(n, 100 * DT)), nir.Linear(weight=np.eye(n)),
                               _lif(n), nir.Output(output_type=np.array([n])))
    with pytest.raises(NirError, match="node 'delay' \\(Delay\\): 100 ticks is longer"):
        map_graph(layers_of(g))
    g = nir.NIRGraph.from_list(nir.Input(input_type=np.array([n])),
                               nir.Linear(weight=np.eye(n) * 3.0), _lif(n),
                               nir.Output(output_type=np.array([n])))
    with pytest.raises(NirError, match="node 'lif': weight 3 saturates 4-bit weights of 3 "):
        map_graph(layers_of(g), weight_bits=4, weight_frac_bits=3, scheme="euler")


# ---------------------------------------------------------------------------------------------
# the golden model against closed forms

def test_golden_lif_closed_forms():
    """One input spike of weight w at step 0: exact scheme v[k] = alpha^(k+1) dt r w / tau,
    Euler v[k] = (1 - dt/tau)^k dt r w / tau; a CubaLIF's exact response is the difference of
    exponentials r w_in dt/tau_s * tau_s/(tau_s - tau_m) (e^-t/tau_s - e^-t/tau_m)."""
    tau, r, w = 2e-3, 3.0, 0.4
    lay = NirLayer("LI", np.array([[w]]), np.zeros(1), tau=np.array([tau]), r=np.array([r]),
                   v_leak=np.zeros(1))
    x = np.zeros((30, 1))
    x[0] = 1
    k = np.arange(30)
    v = simulate_layers([lay], x, DT, "exact")[0].v[:, 0]
    assert np.allclose(v, math.exp(-DT / tau) ** (k + 1) * DT * r * w / tau, rtol=1e-12)
    v = simulate_layers([lay], x, DT, "euler")[0].v[:, 0]
    assert np.allclose(v, (1 - DT / tau) ** k * DT * r * w / tau, rtol=1e-12)
    ts, tm, win = 5e-4, 2e-3, 2.0
    cl = NirLayer("CubaLI", np.array([[w]]), np.zeros(1), tau=np.array([tm]), r=np.array([r]),
                  v_leak=np.zeros(1), tau_syn=np.array([ts]), w_in=np.array([win]))
    v = simulate_layers([cl], x, DT, "exact")[0].v[:, 0]
    t = (k + 1) * DT
    I0 = DT * win * w / ts
    ref = r * I0 * ts / (ts - tm) * (np.exp(-t / ts) - np.exp(-t / tm))
    assert np.allclose(v, ref, rtol=1e-10)


def test_golden_lif_constant_drive_isi():
    """A bias b drives u to r b (1 - alpha^k) (exact: impulses of area dt b each step sum to the
    same geometric series): the first spike comes at the first k with u > threshold."""
    tau, r, b = 1e-3, 1.0, 2.0
    lay = NirLayer("LIF", np.zeros((1, 1)), np.array([b]), tau=np.array([tau]),
                   r=np.array([r]), v_leak=np.zeros(1), v_threshold=np.array([1.0]),
                   v_reset=np.zeros(1))
    s = simulate_layers([lay], np.zeros((200, 1)), DT, "euler")[0].spikes[:, 0]
    a = 1 - DT / tau
    # u_k = (dt r b / tau) (1 - a^(k+1)) / (1 - a) = r b (1 - a^(k+1))
    k_first = next(k for k in range(200) if r * b * (1 - a ** (k + 1)) > 1.0)
    assert np.flatnonzero(s)[0] == k_first
    isi = np.diff(np.flatnonzero(s))
    assert np.all(isi == k_first + 1)


# ---------------------------------------------------------------------------------------------
# engines: fixed against golden (bounded), fixed against the Amaranth RTL (exact)

def _small():
    return map_graph(layers_of(crosscheck_graph(n_in=6, n_hidden=10, n_out=4)), scheme="euler")


def test_fixed_matches_amaranth_and_tracks_golden():
    m = _small()
    x = _spikes(40, 6, 0.3, seed=2)
    fixed = run_network("fixed", m, x)
    rtl = run_network("amaranth", m, x)
    assert np.array_equal(fixed.spikes, rtl.spikes)
    assert fixed.spikes.sum() > 5
    gold = run_network("golden", m, x)
    assert np.abs(fixed.counts() - gold.counts()).max() <= 3


def test_graded_input_needs_a_threshold():
    m = _small()
    with pytest.raises(NirError, match="values other than 0 and 1"):
        run_network("fixed", m, np.full((5, 6), 0.5))
    n = 3
    g = nir.NIRGraph.from_list(nir.Input(input_type=np.array([n])),
                               nir.Threshold(threshold=np.full(n, 0.5)),
                               nir.Linear(weight=np.eye(n) * 0.5), _lif(n),
                               nir.Output(output_type=np.array([n])))
    m = map_graph(layers_of(g))
    x = np.tile([0.2, 0.7, 1.5], (30, 1))
    r = run_network("fixed", m, x)
    assert r.counts()[0] == 0 and r.counts()[1] > 0 and r.counts()[2] > 0


def test_readout_layer_membrane():
    n_in, n = 3, 2
    g = nir.NIRGraph.from_list(nir.Input(input_type=np.array([n_in])),
                               nir.Linear(weight=np.full((n, n_in), 0.3)),
                               nir.LI(tau=np.full(n, 1e-3), r=np.full(n, 10.0),
                                      v_leak=np.zeros(n)),
                               nir.Output(output_type=np.array([n])))
    m = map_graph(layers_of(g), scheme="euler")
    x = _spikes(25, n_in, 0.4)
    gold, fixed = run_network("golden", m, x), run_network("fixed", m, x)
    # 8-bit weights: 0.3 is held as 0.296875 (1 %), the rest of the state error is far below
    assert np.abs(gold.values - fixed.values).max() < 0.012 * np.abs(gold.values).max()
    assert np.abs(gold.values).max() > 1.0


# ---------------------------------------------------------------------------------------------
# export and read-back

def test_skin_and_ridge_round_trip(tmp_path):
    skin = load_scene(EXAMPLES / "skin_3x3.toml")
    nir.write(tmp_path / "skin.nir", scene_graph(skin))
    back = skin_from_graph(read_graph(tmp_path / "skin.nir"))
    fe = skin["frontend"]
    assert back["n_taxels"] == 9 and back["k1"] == fe["force_offset_mV"]
    assert back["k2"] == fe["force_gain_mV_per_N"]
    assert back["lif"] == {"tau_m_ms": 20.0, "v_th": 18.0, "v_reset": 11.0, "v_rest": 0.0,
                           "t_ref_ms": 2.0}
    from cuneate.sim.coincidence.experiments import detector_config
    from cuneate.sim.scenes.ridge import spec_of
    ridge = load_scene(EXAMPLES / "ridge_angle.toml")
    cfg = detector_config(spec_of(ridge))
    nir.write(tmp_path / "ridge.nir", scene_graph(ridge))
    kw = ridge_from_graph(read_graph(tmp_path / "ridge.nir"))
    back = CoincidenceConfig(**kw)
    assert np.array_equal(back.delays, cfg.delays)
    assert np.array_equal(back.weights_real, cfg.weights_real)
    assert (back.tau_rise_ms, back.tau_decay_ms) == (cfg.tau_rise_ms, cfg.tau_decay_ms)
    assert list(back.param_sets) == list(cfg.param_sets) and back.update_hz == cfg.update_hz
    with pytest.raises(NirError, match="izhikevich.*NIR has no Izhikevich"):
        scene_graph(load_scene(EXAMPLES / "slide_texture.toml"))


# ---------------------------------------------------------------------------------------------
# commands

def test_commands(tmp_path, capsys):
    g = tmp_path / "g.nir"
    nir.write(g, crosscheck_graph(n_in=6, n_hidden=10, n_out=4))
    assert main(["nir", "import", str(g), "--out", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "nir_network.v").exists()
    assert "layer 0 cubalif (CubaLIF)" in capsys.readouterr().out
    np.save(tmp_path / "x.npy", _spikes(30, 6, 0.3))
    assert main(["simulate", "nir", str(g), "--engine", "fixed", "--input",
                 str(tmp_path / "x.npy")]) == 0
    assert "output 3" in capsys.readouterr().out
    bad = tmp_path / "bad.nir"
    bad.write_text("x")
    for argv in (["nir", "import", str(bad), "--out", str(tmp_path / "o")],
                 ["simulate", "nir", str(g), "--input", str(tmp_path / "x.npy"),
                  "--weight-bits", "4", "--weight-frac-bits", "4"],
                 ["nir", "export", str(EXAMPLES / "slide_texture.toml"), "--out",
                  str(tmp_path / "a.nir")]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith("cuneate"), err


def test_a_learned_layer_round_trips_through_nir(tmp_path):
    """The learning layer with learned weights (one of them 0, still a synapse) written as a
    NIR file and read back: the same configuration, weight for weight in its format."""
    from cuneate.golden.aidp import AidpParams
    from cuneate.hdl.plasticity import PlasticityConfig
    from cuneate.sim.nir.export import learning_from_graph, learning_graph
    cfg = PlasticityConfig(n_sources=5, sources=[[0, 3, 4], [1, 2, 3]],
                           rule=AidpParams(eta=3e-6, w_max=5.0), g_inh=0.25,
                           clock_hz=2000.0 * 60)
    learned = np.array([[4.9, 0.0, 0.37], [1.25, 2.0, 4.0]])
    nir.write(tmp_path / "layer.nir", learning_graph(cfg, learned))
    back = PlasticityConfig.from_kwargs(learning_from_graph(read_graph(tmp_path /
                                                                       "layer.nir")))
    assert np.array_equal(back.src, cfg.src) and np.array_equal(back.weights_real, learned)
    assert np.array_equal(back.weights_raw, cfg.W.to_raw(learned))
    assert back.rule == cfg.rule and back.g_inh == 0.25 and back.update_hz == 2000.0
    assert back.step_table == cfg.step_table and list(back.param_sets) == ["RS"]
    g = learning_graph(cfg, learned)
    g.nodes["synapses"].weight[0, 1] = 1.0                  # a weight where no synapse is
    with pytest.raises(NirError, match="a weight where no synapse is"):
        learning_from_graph(g)
