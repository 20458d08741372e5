"""Toolchain smoke test: Amaranth -> Verilog -> cocotb on Icarus and on Verilator."""


import pytest
from amaranth.back import verilog

from cuneate.hdl.lib.smoke import SmokeCounter
from cuneate.sim.engines.cocotb import run_cocotb
from cuneate.sim.engines.toolchain import SIMULATORS


@pytest.mark.cocotb
@pytest.mark.parametrize("simulator", SIMULATORS)
def test_smoke_counter(simulator, tmp_path_factory, build_root):
    width = 6
    build_dir = build_root / f"smoke_{simulator}_w{width}"
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / "smoke_counter.v"
    src.write_text(verilog.convert(SmokeCounter(width), name="smoke_counter", emit_src=False))
    run = run_cocotb(simulator, [src], "smoke_counter", "cuneate.sim.engines.smoke_bench",
                     build_dir, config={"width": width, "cycles": 300, "seed": 7})
    assert run.n_tests == 1 and run.n_failed == 0
    assert run.report == {"cycles": 300, "mismatches": 0}
