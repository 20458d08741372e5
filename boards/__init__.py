"""cuneate.boards."""
