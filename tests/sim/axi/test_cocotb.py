"""Every block that runs on the board engine, behind the bus faces, on Icarus and Verilator with
the cocotbext-axi bus models (:mod:`cuneate.sim.axi.bench`): writes from an AxiStreamSource with
random gaps, spikes into an AxiStreamSink with random back-pressure, registers over an
AxiLiteMaster (cocotbext-wishbone's WishboneMaster on the Wishbone face). Checked against the
block's payload twin (:func:`cuneate.sim.axi.scoreboard.check_face`): every sweep's spike ids
and its TLAST, the empty sweeps' markers, the constants, every counter, the refusals answered
with an error, the clamp flags as the twin's (a clamp provoked) and cleared over the bus.

The learning layer behind the AXI and Wishbone faces: its protocol streamed as writes, every
sweep's ids as the payload twin's and the weights of its readout sweeps equal to the fixed
engine's after learning (AXI on Icarus in the default lane; Verilator and the Wishbone face in
the long lane).

Default lane: the LIF core behind the AXI face and behind the Wishbone face, on both
simulators. Long lane: the Izhikevich array and the network behind the AXI face, and the channel
fan-out in front of the array, the LIF core and the network.
"""

import numpy as np
import pytest

from cuneate.hdl.fanout import FanoutConfig
from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.hdl.lif import LifConfig
from cuneate.hdl.lib.regmap import stream_format
from cuneate.hdl.network import NetworkConfig
from cuneate.hdl.plasticity.payload import LearningSpec, weights_from_ids
from cuneate.sim.axi.scoreboard import check_face, run_face
from cuneate.sim.axi.transport import axi_spec
from cuneate.sim.engines.toolchain import SIMULATORS
from cuneate.sim.plasticity.engines import face_schedule, run_learning
from learning_case import small_layer

SWEEPS = 24
N_NET, S_NET, M_NET = 12, 8, 2


def _izhikevich():
    return axi_spec(IzhikevichConfig(n_neurons=8, clock_hz=16e3, update_hz=1e3,
                                     spike_fifo_depth=16,
                                     current_range=(-5.0, 100.0)), n_cores=2)


def _lif():
    return axi_spec(LifConfig(n_neurons=8, update_hz=1e3,
                                  current_range=(-5.0, 100.0)))


def _network():
    rng = np.random.default_rng(3)
    return axi_spec(NetworkConfig(
        n_afferents=N_NET, first_source=2,
        detector=dict(n_sources=S_NET, n_targets=M_NET,
                      delays_ticks=rng.integers(0, 4, (M_NET, S_NET)).tolist(),
                      weights=np.round(rng.uniform(6, 12, (M_NET, S_NET)), 2).tolist(),
                      max_delay_ticks=4),
        clock_hz=4e3 * 50, update_hz=4e3, tick_source="external"))


def _fanout(inner):
    """Four channels in front of ``inner``'s afferents (gains that saturate a current at
    the largest samples)."""
    spec = inner()
    n = spec.info.n_written
    rng = np.random.default_rng(4)
    I = spec.info.value_format
    fan = FanoutConfig(n_channels=4, channel=[i % 4 for i in range(n)],
                       gain=[float(g) for g in np.round(rng.uniform(6, 0.4 * I.max_value, n), 2)],
                       current_format=I,
                       rectify=["positive", "abs", "none", "positive"] * (n // 4),
                       sample_max=4.0, sample_width=12)
    return axi_spec(spec, fanout=fan)


#: block -> (its spec, the written values' range (a current, or a channel sample), the extreme
#: value that provokes a clamp: the largest or the smallest raw value)
BLOCKS = {
    "izhikevich_array": (_izhikevich, (10.0, 60.0), "max"),
    "lif": (_lif, (20.0, 90.0), "max"),
    "network": (_network, (10.0, 60.0), "min"),
    "fanout+izhikevich_array": (lambda: _fanout(_izhikevich), (-1.5, 3.0), "max"),
    "fanout+lif": (lambda: _fanout(_lif), (-0.5, 2.0), "max"),
    "fanout+network": (lambda: _fanout(_network), (-1.5, 3.0), "max"),
}


def schedule(spec, lo, hi, extreme, seed=2) -> dict:
    """Every value at sweep 0, a part of them at sweep 9 (two bursts), and at sweep 16 the
    ``extreme`` value of the format (a clamp) for the first two, a burst."""
    info = spec.info
    fmt, n = info.value_format, info.n_written
    rng = np.random.default_rng(seed)
    raw = lambda k: [int(v) for v in np.atleast_1d(fmt.to_raw(rng.uniform(lo, hi, k)))]
    return {0: [(0, raw(n))], 9: [(1, raw(3)), (n // 2, raw(2))], 16: [(0, [getattr(fmt, f"{extreme}_raw")] * 2)]}


def _check(simulator, block, face, build_root):
    make, (lo, hi), extreme = BLOCKS[block]
    spec = make()
    sched = schedule(spec, lo, hi, extreme)
    report = run_face(simulator, spec, face, sched, SWEEPS,
                      build_root / f"{face}_{block}_{simulator}", seed=7)
    got = check_face(spec, sched, SWEEPS, report)
    print(f"\n{simulator} {face} {block}: {got}")
    assert got["spikes"] > 0
    # the network's twin flags no clamp under these writes; every other block is made to clamp
    assert got["clamp_flags"] != 0 or block == "network"


#: the default lane's block (the cheapest Verilator build); the others run in the long lane
DEFAULT = "lif"
LONG = [b for b in BLOCKS if b != DEFAULT]


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_axi_face(simulator, build_root):
    _check(simulator, DEFAULT, "axi", build_root)


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_wishbone_face(simulator, build_root):
    _check(simulator, DEFAULT, "wishbone", build_root)


@pytest.mark.cocotb
@pytest.mark.long
@pytest.mark.parametrize("simulator", SIMULATORS)
@pytest.mark.parametrize("block", LONG)
def test_axi_face_long(simulator, block, build_root):
    _check(simulator, block, "axi", build_root)


def _learning():
    """Two CNs of three synapses learning over two short presentations, behind the face;
    two synapses a readout sweep (two sweeps a CN)."""
    cfg, pres = small_layer()
    return axi_spec(LearningSpec(cfg, readout_synapses=2)), pres


@pytest.mark.cocotb
# AXI on Icarus in the default lane; Verilator's build (about a minute) and the Wishbone face
# in the long lane
@pytest.mark.parametrize("face, simulator", [
    pytest.param(f, s, marks=pytest.mark.long) if (f, s) != ("axi", "icarus") else (f, s)
    for f in ("axi", "wishbone") for s in SIMULATORS])
def test_the_learning_layer_learns_behind_the_bus_faces(face, simulator, build_root):
    """The layer's protocol streamed on s_axis (afferent spikes, window ends, readout
    requests): every sweep's ids, counters (over the face's AXI4-Lite or Wishbone registers)
    and clamp flags as the payload twin's, and the weights read back in the readout sweeps
    equal the fixed engine's after learning."""
    spec, pres = _learning()
    cfg, C = spec.config, spec.parts
    flags = np.array([True, True])
    plan = face_schedule(cfg, pres, flags, readout_synapses=spec.readout_synapses)
    sched = {k: [(first, raw.tolist()) for first, raw in rows]
             for k, rows in plan.writes.items()}
    report = run_face(simulator, spec, face, sched, plan.n_sweeps,
                      build_root / f"{face}_learning_{simulator}", seed=7)
    got = check_face(spec, sched, plan.n_sweeps, report)
    fixed = run_learning("fixed", cfg, pres, flags)
    assert got["spikes"] > fixed.spike_cn.size > 0 and C == 2
    F = 8 * stream_format(spec.info)["spike_field_bytes"]
    n_total = pres.n * pres.n_ticks
    ids = [[d & ((1 << F) - 1) for d, _ in beats] for beats in report["packets"]]
    weights = [weights_from_ids(cfg, ids[n_total + j * C] + ids[n_total + j * C + 1])
               for j in range(cfg.n_targets)]
    assert not np.array_equal(fixed.weights_raw, cfg.weights_raw)
    assert np.array_equal(np.stack(weights), fixed.weights_raw)
