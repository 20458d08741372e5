"""The synapse models live in cuneate.golden.synapses and stay importable from golden.lif."""

import numpy as np

from cuneate.golden import lif, synapses


def test_lif_reexports_the_synapse_models():
    for name in ("DiffExpSynapse", "AMPA", "GABA", "diff_exp_kernel", "diff_exp_peak_time",
                 "synaptic_current", "LATENCY_MS"):
        assert getattr(lif, name) is getattr(synapses, name)


def test_peak_normalized_kernel_peaks_at_one_at_the_analytic_time():
    tp = synapses.diff_exp_peak_time(0.4, 2.0)
    assert abs(tp - 0.4 * 2.0 / 1.6 * np.log(5.0)) < 1e-12
    t = np.linspace(0, 10, 100001)
    k = synapses.diff_exp_kernel(t, 0.4, 2.0)
    assert abs(k.max() - 1.0) < 1e-9 and abs(t[np.argmax(k)] - tp) < 1e-3
