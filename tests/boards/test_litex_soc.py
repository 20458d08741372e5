"""The block behind the Wishbone face as a LiteX peripheral in a LiteX SoC for the ULX3S
(boards/litex_soc.py, LiteX 2024.12, migen 0.10): the SoC's gateware, its CSR map and the
build script the yowasp shims run (default lane); the bitstream through the shims (release
lane, benchmarks/boards.md)."""

import json
from pathlib import Path

import pytest

from cuneate.boards.litex_soc import CUNEATE_BASE, build_soc
from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.sim.axi.transport import axi_spec


def _spec():
    return axi_spec(IzhikevichConfig(n_neurons=64, clock_hz=50e6, update_hz=16e3))


def test_litex_soc_maps_the_registers_and_the_streams_and_reads_relative_sources(tmp_path):
    r = build_soc(_spec(), tmp_path, 50e6)
    csr = json.loads(Path(r["csr_json"]).read_text())
    assert csr["memories"]["cuneate"] == {"base": CUNEATE_BASE, "size": 0x1000, "type": "io"}
    assert {f"cuneate_{n}" for n in ("write_data", "write_push", "write_lost", "spike_level", "spike_data",
                                     "spike_flags", "spike_pop", "spike_lost")} \
        <= set(csr["csr_registers"])
    assert csr["constants"]["config_clock_frequency"] == 50_000_000
    gw = Path(r["gateware"])
    top = (gw / "cuneate_litex.v").read_text()
    assert "cuneate_wb cuneate_wb(" in top and "EHXPLLL" in top and "uartbone" in top
    ys = (gw / "cuneate_litex.ys").read_text()
    reads = [line.split()[-1] for line in ys.splitlines() if line.startswith("read_verilog")]
    assert reads == ["cuneate_wb.v", "cuneate_litex.v"]     # the yowasp tools see only gw
    assert all((gw / f).exists() for f in reads)
    sh = (gw / "build_cuneate_litex.sh").read_text()
    assert "nextpnr-ecp5" in sh and "--85k" in sh and "ecppack" in sh


@pytest.mark.release
def test_litex_soc_bitstream_through_the_yowasp_shims(tmp_path):
    r = build_soc(_spec(), tmp_path, 50e6, run=True)
    assert r["bitstream"] and Path(r["bitstream"]).stat().st_size > 0
    log = (Path(r["gateware"]) / "build.log").read_text()
    fmax = [line for line in log.splitlines() if "Max frequency" in line]
    print(fmax[-1])
    assert "PASS at 50.00 MHz" in fmax[-1]          # after routing, at the SoC's clock
