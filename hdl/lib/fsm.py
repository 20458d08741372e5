"""Finite-state-machine pieces the blocks share."""

from __future__ import annotations

from amaranth import Module

__all__ = ["wait_states"]


def wait_states(m: Module, *names: str) -> None:
    """Inside ``m``'s FSM, the states ``names[:-1]``, each of which only moves on to the next
    name (one cycle each: a pipeline's or a memory's latency); ``names[-1]`` is defined by the
    caller."""
    for state, following in zip(names, names[1:]):
        with m.State(state):
            m.next = following
