"""The bus faces in simulation: the ``axi`` engine's host transport (:mod:`.transport`:
:class:`AxiTransport`, a block behind the AXI face compiled by Verilator with
``axi_harness.cpp``) and the cocotb bench of the AXI and Wishbone faces (:mod:`.bench`, with
cocotbext-axi and cocotbext-wishbone)."""
