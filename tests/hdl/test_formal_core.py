"""SymbiYosys on the pipelined core against the one-step reference (hdl/izhikevich/formal.py):
injected faults the bounded check catches. The bounded proof itself (9 cycles) is superseded by
the unbounded k-induction of tests/hdl/test_core_proof.py (every input sequence, any length)."""

from cuneate.hdl.izhikevich import datapath as izh
from cuneate.hdl.izhikevich.formal import prove_core
from cuneate.hdl.izhikevich import IzhikevichConfig


def _cfg():
    # the smallest core: 6 neurons for a 5-stage pipeline, so back-to-back sweeps read a
    # neuron's memories (a cycle ahead of its fetch) as its registered write-back lands
    return IzhikevichConfig(n_neurons=6, clock_hz=6 * 16e3, update_hz=16e3,
                            tick_source="external")


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
