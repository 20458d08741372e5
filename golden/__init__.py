"""cuneate.golden."""
