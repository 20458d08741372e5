"""Running a block's RTL in Amaranth's simulator: one helper for every block's engine.

:func:`simulate` elaborates ``dut``, adds a clock and an async testbench, and runs it, optionally
writing a VCD of the run (``vcd``: a path, or a file object such as the window of
:class:`cuneate.sim.engines.waves.WindowedVcd`; ``traces``: extra signals to include).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["simulate", "write_currents", "spikes_then_tick"]


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
    if isinstance(vcd, (str, Path)):
        vcd = Path(vcd)
        vcd.parent.mkdir(parents=True, exist_ok=True)
        vcd = str(vcd)
    with sim.write_vcd(vcd, traces=list(traces)):
        sim.run()


async def write_currents(ctx, dut, raw, first: int = 0) -> None:
    """Drive raw currents through a core's host-write port (``i_wr_*``), one neuron per cycle
    from ``first`` on, and leave the port idle."""
    for i, x in enumerate(raw):
        ctx.set(dut.i_wr_en, 1)
        ctx.set(dut.i_wr_addr, first + i)
        ctx.set(dut.i_wr_data, int(x))
        await ctx.tick()
    ctx.set(dut.i_wr_en, 0)


async def spikes_then_tick(ctx, dut, sources, step, has_inputs: bool) -> None:
    """Present each input spike source on ``in_valid``/``in_source`` for one ``step``, then one
    ``tick`` pulse (the order every core with an input port expects within a sweep)."""
    for s in sources:
        ctx.set(dut.in_valid, 1)
        ctx.set(dut.in_source, int(s))
        await step()
    if has_inputs:
        ctx.set(dut.in_valid, 0)
    ctx.set(dut.tick, 1)
    await step()
    ctx.set(dut.tick, 0)
