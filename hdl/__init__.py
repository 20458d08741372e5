"""cuneate.hdl."""
