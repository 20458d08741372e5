"""Machinery every block shares: fixed point (:mod:`.fixed`), the one configuration error and
format sizing (:mod:`.config`), helpers for stage functions that run in twins and RTL
(:mod:`.datapath`), the tick (:mod:`.tick`), the sweep bookkeeping RTL (:mod:`.bookkeeping`),
synaptic traces (:mod:`.synapses`), the twins' compiled-loop helpers (:mod:`.kernel`), the UART
(:mod:`.uart`) and the toolchain smoke block (:mod:`.smoke`)."""
