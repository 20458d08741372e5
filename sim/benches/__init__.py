"""cuneate.sim.benches."""
