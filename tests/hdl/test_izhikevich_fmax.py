"""fmax of the Izhikevich core per pipeline depth: yosys synth_ecp5 and nextpnr-ecp5 out of
context on the LFE5U-85F (CABGA381, speed grade 6), the default 2 500-neuron configuration
(long lane: place and route, ~5 min a depth on 2 busy cores). The floors are the measured
figures less a placement margin (docs/architecture.md lists them per seed)."""

import pytest

from cuneate.hdl.flow.synth import available, nextpnr_ecp5, synthesize
from cuneate.hdl.izhikevich import IzhikevichConfig, izhikevich_verilog

#: the lowest fmax (MHz) accepted per depth, seed 1 (docs/architecture.md has both depths
#: measured; the long lane's filled ULX3S build is depth 5, the sizing's largest, and the
#: 40 000-neuron depth-8 build is measured in docs/boards.md)
FLOORS = {5: 85.0}


@pytest.mark.long
@pytest.mark.parametrize("depth", sorted(FLOORS))
def test_fmax_per_pipeline_depth(depth, tmp_path):
    if not available():
        pytest.skip("yowasp yosys / nextpnr-ecp5 not installed (synth extra)")
    cfg = IzhikevichConfig(n_neurons=2500, clock_hz=40e6, update_hz=16e3,
                           pipeline_stages=depth)
    r = synthesize(izhikevich_verilog(cfg, "izhikevich_core"), "izhikevich_core", "ecp5",
                   tmp_path, netlist=True)
    assert r["cells"].get("MULT18X18D", 0) == 4 and r["cells"].get("DP16KD", 0) <= 14
    pnr = nextpnr_ecp5(tmp_path, r["netlist"], device="85k", package="CABGA381", speed=6,
                       seed=1, freq_mhz=150, out_of_context=True, timeout=3600)
    print(f"\ndepth {depth}: fmax {pnr['min_fmax_mhz']:.1f} MHz, critical path "
          f"{pnr['critical_path']}")
    assert pnr["min_fmax_mhz"] >= FLOORS[depth], pnr["critical_path"]
