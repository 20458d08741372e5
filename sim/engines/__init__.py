"""What runs a block: the engine registry (:mod:`.registry`), the cocotb runner and bench helpers
(:mod:`.cocotb`), the Amaranth simulator helper (:mod:`.amaranth`), the run record
(:mod:`.run`), the compiled Verilator harness (:mod:`.verilator_fast`) and the simulator
toolchain (:mod:`.toolchain`)."""
