"""The hardware flow: Verilog emission (:mod:`.verilog`), the one lookup of the yowasp tools
(:mod:`.tools`), synthesis and place-and-route figures (:mod:`.synth`) and SymbiYosys
(:mod:`.sby`). Blocks call these; none of them knows a block."""
