"""cuneate.sim."""
