"""SymbiYosys on the pipelined core against the one-step reference (hdl/formal_core.py): a
bounded proof on the smallest core, and injected faults the same check catches."""

import pytest

from cuneate.hdl.izhikevich import datapath as izh
from cuneate.hdl.izhikevich.formal import prove_core
from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.sim.hardcases import record


def _cfg():
    # the smallest core: 5 neurons for a 5-stage pipeline, so back-to-back sweeps read a
    # neuron one cycle after its write-back
    return IzhikevichConfig(n_neurons=5, clock_hz=5 * 16e3, update_hz=16e3,
                            tick_source="external")


@pytest.mark.long
def test_pipelined_core_equals_the_one_step_reference_for_9_cycles(tmp_path):
    """Every input sequence of 9 cycles from power-up with any RAM state: the first sweep's
    first three updates equal one step of the stage functions from the state they read, neuron
    0's next read after a back-to-back sweep boundary is its own result, host writes land as
    the contract says, and timing, order and bookkeeping hold (multipliers abstracted)."""
    r = prove_core(_cfg(), tmp_path, depth=9, timeout_s=1800)
    record("formal_core_equivalence_depth9", 1, 0, int(r["status"] != "pass"),
           "SymbiYosys, z3, multipliers abstracted")
    assert r["status"] == "pass", r


def test_a_host_write_timing_fault_is_caught(tmp_path):
    """A reference expecting writes one cycle earlier than the core honours them fails at the
    first update whose current was just written: the check is tight on write timing."""
    r = prove_core(_cfg(), tmp_path, depth=9, timeout_s=600, write_latency=4)
    assert r["status"] == "fail" and r["step"] is not None and 6 <= r["step"] <= 8, r


def test_a_datapath_fault_in_the_core_is_caught(tmp_path, v_one_high):
    """The core built with a faulty last stage (v one LSB high; the
    reference keeps the true stage functions) fails at its first update."""
    v_one_high(izh, "select_step", "v_next")
    r = prove_core(_cfg(), tmp_path, depth=8, timeout_s=600)
    assert r["status"] == "fail" and r["step"] == 6, r
