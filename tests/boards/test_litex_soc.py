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
@pytest.mark.parametrize("board, sys_clk_hz", [("ulx3s", 50e6), ("butterstick", 60e6)])
def test_litex_soc_bitstream_through_the_yowasp_shims(board, sys_clk_hz, tmp_path):
    spec = axi_spec(IzhikevichConfig(n_neurons=64, clock_hz=sys_clk_hz, update_hz=16e3))
    r = build_soc(spec, tmp_path, sys_clk_hz, run=True, board=board)
    assert r["bitstream"] and Path(r["bitstream"]).stat().st_size > 0
    log = (Path(r["gateware"]) / "build.log").read_text()
    fmax = [line for line in log.splitlines() if "Max frequency" in line]
    print(fmax[-1])
    # after routing, at the SoC's clock
    assert f"PASS at {sys_clk_hz / 1e6:.2f} MHz" in fmax[-1]


def test_litex_soc_for_the_butterstick_writes_its_pins_pll_and_bank_control(tmp_path):
    """Verilog (the bitstream in the release lane): the ButterStick's pins (amaranth-boards' file and
    the adapter on SYZYGY 0), the PLL from 30 MHz, the SYZYGY banks' control as a source."""
    spec = axi_spec(IzhikevichConfig(n_neurons=64, clock_hz=60e6, update_hz=16e3))
    r = build_soc(spec, tmp_path, 60e6, board="butterstick")
    gw = Path(r["gateware"])
    csr = json.loads(Path(r["csr_json"]).read_text())
    assert csr["memories"]["cuneate"]["base"] == CUNEATE_BASE
    top = (gw / "cuneate_litex.v").read_text()
    assert "cuneate_wb cuneate_wb(" in top and "cuneate_vccio cuneate_vccio(" in top
    assert "EHXPLLL" in top and "uartbone" in top
    lpf = (gw / "cuneate_litex.lpf").read_text()
    sites = {"clk30": "B12", "serial_tx": "G2", "serial_rx": "J3", "vccio_ctrl_en": "E12",
             "vccio_ctrl_pdm[0]": "V1", "vccio_ctrl_pdm[1]": "E11", "vccio_ctrl_pdm[2]": "T2"}
    for port, site in sites.items():
        assert f'LOCATE COMP "{port}" SITE "{site}";' in lpf
    assert 'FREQUENCY PORT "clk30" 30.0 MHz;' in lpf
    reads = [line.split()[-1] for line in (gw / "cuneate_litex.ys").read_text().splitlines()
             if line.startswith("read_verilog")]
    assert sorted(reads) == ["cuneate_litex.v", "cuneate_vccio.v", "cuneate_wb.v"]
    sh = (gw / "build_cuneate_litex.sh").read_text()
    assert "--um5g-85k" in sh and "--speed 8" in sh and "CABGA381" in sh
