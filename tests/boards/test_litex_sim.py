"""The LiteX SoC (boards/litex_sim.py) simulated on Icarus and Verilator with the host on
LiteX's own ``CommUART`` over UARTBone (a pseudo-terminal bridged to cocotbext-uart on the
SoC's serial pins), and through ``litex_server`` (its own process) and a RemoteClient as a
LiteX user reaches a board: a small Izhikevich core's currents written through the write CSRs, sweeps
stepped through the Wishbone face, the spike beats popped from the FIFO, the clamp flags and
the face's counters read; compared with the block's payload twin.

Default lane: CommUART on Icarus (about 5 to 8 s); long lane: Verilator (3 s with its model
cached, 20 s without) and the RemoteClient on both. Without LiteX (the ``synth`` extra) every case skips, and CI fails on them:
``scripts/check_simulators_ran.py`` counts a skipped simulator case as not passed."""

import numpy as np
import pytest

from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.sim.axi.scoreboard import check_packets, reference
from cuneate.sim.axi.transport import axi_spec
from cuneate.sim.engines.toolchain import SIMULATORS

SWEEPS = 5


def _spec():
    return axi_spec(IzhikevichConfig(n_neurons=8, clock_hz=16e3, update_hz=1e3,
                                     spike_fifo_depth=16, current_range=(-5.0, 100.0)))


def _schedule(spec) -> dict:
    """Six currents and the largest raw value for the last two neurons (a clamp) at sweep 0,
    the smallest for neurons 0 and 1 at sweep 3 (it silences them at sweep 4)."""
    fmt = spec.info.value_format
    rng = np.random.default_rng(2)
    raw = [int(v) for v in np.atleast_1d(fmt.to_raw(rng.uniform(20.0, 90.0, 6)))]
    return {0: [(0, raw), (6, [fmt.max_raw] * 2)], 3: [(0, [fmt.min_raw] * 2)]}


@pytest.mark.cocotb
# CommUART on Icarus in the default lane; Verilator (its first build of the SoC about 20 s) and
# litex_server + RemoteClient in the long lane
@pytest.mark.parametrize("simulator, bridge", [
    pytest.param(s, b, marks=pytest.mark.long) if (s, b) != ("icarus", "comm_uart") else (s, b)
    for b in ("comm_uart", "litex_server") for s in SIMULATORS])
def test_litex_soc_through_uartbone_equals_the_twin(simulator, bridge, build_root):
    pytest.importorskip("litex", reason="LiteX 2024.12 (the synth extra) is not installed")
    from cuneate.boards.litex_sim import run_sim
    spec = _spec()
    sched = _schedule(spec)
    got = run_sim(simulator, spec, sched, SWEEPS, build_root / f"litex_sim_{simulator}_{bridge}",
                  bridge=bridge)
    want = reference(spec, sched, SWEEPS)
    n = check_packets(spec.info, got["packets"], want.sweeps)
    print(f"\n{simulator}, {got['bridge']}: {n} spikes, {got['transactions']} transactions, "
          f"{got['bench']}")
    assert n > 0 and want.clamp_flags != 0
    assert reference(spec, {0: sched[0]}, SWEEPS).sweeps != want.sweeps   # sweep 3's burst shows
    assert got["clamp_flags"] == want.clamp_flags
    values = sum(len(raw) for rows in sched.values() for _, raw in rows)
    assert got["counters"] == {
        "writes": values, "bursts": sum(len(rows) for rows in sched.values()),
        "writes_refused": 0, "spikes": n, "sweeps": SWEEPS,
        "empty_sweeps": sum(not s for s in want.sweeps), "ticks": SWEEPS, "tick_overruns": 0}
    assert got["id"] == int.from_bytes(b"cune", "little")
    assert got["write_lost"] == 0 and got["spike_lost"] == 0
