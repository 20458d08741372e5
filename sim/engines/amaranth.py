"""Running a block's RTL in Amaranth's simulator: one helper for every block's engine.

:func:`simulate` elaborates ``dut``, adds a clock and an async testbench, and runs it, optionally
writing a VCD of the run (``vcd``: a path; ``traces``: extra signals to include).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["simulate"]


def simulate(dut, testbench, clock_hz: float = 1e6, vcd: Path | str | None = None,
             traces=()) -> None:
    """Run ``testbench`` (an ``async def tb(ctx)``) on ``dut`` with a clock of ``clock_hz``."""
    from amaranth.sim import Simulator
    sim = Simulator(dut)
    sim.add_clock(1.0 / clock_hz)
    sim.add_testbench(testbench)
    if vcd is None:
        sim.run()
        return
    vcd = Path(vcd)
    vcd.parent.mkdir(parents=True, exist_ok=True)
    with sim.write_vcd(str(vcd), traces=list(traces)):
        sim.run()
