"""fmax of the Izhikevich core per pipeline depth: yosys synth_ecp5, the block RAMs' and
multipliers' registers packed (hdl/flow/ecp5_pack.py), and nextpnr-ecp5 out of context on the
LFE5U-85F (CABGA381, speed grade 6), the default 2 500-neuron configuration (release lane:
place and route, ~1 min a depth). The floors are the goals: 100 MHz at the default depth, 150 MHz at
the deepest (docs/architecture.md lists every depth's fmax per seed)."""

import pytest

from cuneate.hdl.flow.synth import available, nextpnr_ecp5, synthesize
from cuneate.hdl.izhikevich import IzhikevichConfig, izhikevich_verilog

#: the lowest fmax (MHz) accepted per depth, seed 1 (docs/architecture.md: 109.4 and 166.0;
#: the long lane's filled ULX3S build is depth 5, the sizing's largest)
FLOORS = {5: 100.0, 9: 150.0}


@pytest.mark.release
@pytest.mark.parametrize("depth", sorted(FLOORS))
def test_fmax_per_pipeline_depth(depth, tmp_path):
    if not available():
        pytest.skip("yowasp yosys / nextpnr-ecp5 not installed (synth extra)")
    cfg = IzhikevichConfig(n_neurons=2500, clock_hz=40e6, update_hz=16e3,
                           pipeline_stages=depth)
    r = synthesize(izhikevich_verilog(cfg, "izhikevich_core"), "izhikevich_core", "ecp5",
                   tmp_path, netlist=True, pack_registers=True)
    assert r["cells"].get("MULT18X18D", 0) == 4 and r["cells"].get("DP16KD", 0) <= 14
    packing = r["register_packing"]
    # every bank's word register is in its block RAM; both ports of every multiplier
    # registered
    assert packing["ram_outputs_packed"] >= 20 and packing["inputs_packed"] == 8, packing
    pnr = nextpnr_ecp5(tmp_path, r["netlist"], device="85k", package="CABGA381", speed=6,
                       seed=1, freq_mhz=150, out_of_context=True, timeout=3600)
    print(f"\ndepth {depth}: fmax {pnr['min_fmax_mhz']:.1f} MHz, critical path "
          f"{pnr['critical_path']}")
    assert pnr["min_fmax_mhz"] >= FLOORS[depth], pnr["critical_path"]
