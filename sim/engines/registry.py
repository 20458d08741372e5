"""The one list of simulation engines and which blocks each runs.

An *engine* is a way of running a block: its float64 golden model, its bit-exact integer twin,
or its RTL in a simulator. :data:`ENGINES` names every engine once with its traits; a block
declares which engines it supports (and how fast each runs its work) by calling
:func:`register_block` from its package ``cuneate.sim.<block>`` (lava's ``proc`` folders and
Brian2's backends work the same way: the implementation registers itself). Everything that takes
an engine name (``cuneate simulate``, ``cuneate run``, scenes' ``run.engines``, sweeps, the run
time estimates) asks this module, so a name accepted for a block in one place is accepted in
every place that block runs, and an unknown name is refused with the list the block supports.

Declaring a block imports only this module; the block's engine code is imported when it runs.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field

__all__ = ["Engine", "BlockEngines", "ENGINES", "BLOCKS", "register_block", "block_engines",
           "check_engine", "engine", "estimate_seconds", "UnknownEngine"]


class UnknownEngine(ValueError):
    """An engine name that does not exist, or that the block does not support."""


@dataclass(frozen=True)
class Engine:
    """One engine and its traits.

    ``level``: ``"golden"`` (float64 model of the scheme), ``"twin"`` (bit-exact integer model
    built from the RTL's stage functions) or ``"rtl"`` (the block's hardware description in a
    simulator). ``simulator``: the HDL simulator an RTL engine runs (``None`` otherwise).
    ``background``: runs in a simulator process of its own, so a scene overlaps it with the
    Python engines.
    """

    name: str
    level: str
    simulator: str | None
    background: bool
    summary: str

    @property
    def hdl(self) -> bool:
        return self.level == "rtl"


#: Every engine, in the order they are listed to users.
ENGINES: dict[str, Engine] = {e.name: e for e in (
    Engine("golden", "golden", None, False, "float64 golden model (states its scheme)"),
    Engine("fixed", "twin", None, False, "bit-exact integer twin (NumPy, compiled with numba)"),
    Engine("amaranth", "rtl", "amaranth", False, "Amaranth's simulator on the block's RTL"),
    Engine("icarus", "rtl", "icarus", True, "cocotb on the generated Verilog, Icarus Verilog"),
    Engine("verilator", "rtl", "verilator", True, "cocotb on the generated Verilog, Verilator"),
    Engine("verilator-fast", "rtl", "verilator", True,
           "the generated Verilog compiled by Verilator with a C++ harness (no Python per cycle)"),
    Engine("board", "rtl", "verilator", True,
           "the board top (UART link + blocks) compiled by Verilator, driven by the host stack "
           "through a simulated serial line"),
    Engine("axi", "rtl", "verilator", True,
           "the block behind the AXI face (AXI4-Stream, AXI4-Lite) compiled by Verilator, "
           "driven by the host's bus transactions (no Python per cycle)"),
)}


@dataclass(frozen=True)
class BlockEngines:
    """The engines one block supports and how fast each runs its work.

    ``speed[engine]`` is a conservative rate in ``unit`` per second on a small (2-core) machine,
    for estimating a run before it starts; ``unit`` names the work: ``"updates"`` (neuron
    updates) or ``"cycles"``.
    """

    block: str
    engines: tuple[str, ...]
    speed: dict = field(default_factory=dict)
    unit: str = "updates"


#: Block name -> its declaration (filled by :func:`register_block`).
BLOCKS: dict[str, BlockEngines] = {}


def register_block(block: str, engines, speed: dict, unit: str = "updates") -> BlockEngines:
    """Declare the engines ``block`` supports (called by ``cuneate.sim.<block>``)."""
    engines = tuple(engines)
    for e in engines:
        if e not in ENGINES:
            raise ValueError(f"block {block!r} declares an unknown engine {e!r}")
    missing = [e for e in engines if e not in speed]
    if missing:
        raise ValueError(f"block {block!r}: no speed for engine(s) {', '.join(missing)}")
    decl = BlockEngines(block, engines, dict(speed), unit)
    BLOCKS[block] = decl
    return decl


def _declaration(block: str) -> BlockEngines:
    if block not in BLOCKS:
        try:
            importlib.import_module(f"{__package__.rsplit('.', 1)[0]}.{block}")
        except ModuleNotFoundError:
            pass
    if block not in BLOCKS:
        raise KeyError(f"no block named {block!r} declares engines")
    return BLOCKS[block]


def block_engines(block: str) -> tuple[str, ...]:
    """The engines ``block`` supports, in :data:`ENGINES` order."""
    return _declaration(block).engines


def check_engine(block: str, name: str) -> Engine:
    """The engine ``name`` if ``block`` supports it, else :class:`UnknownEngine` naming the
    engines it does support."""
    supported = block_engines(block)
    if name not in supported:
        if name in ENGINES:
            raise UnknownEngine(f"engine {name!r} does not run the {block} block (it runs on: "
                                f"{', '.join(supported)})")
        raise UnknownEngine(f"unknown engine {name!r} (the {block} block runs on: "
                            f"{', '.join(supported)})")
    return ENGINES[name]


def engine(name: str) -> Engine:
    """The traits of engine ``name``."""
    if name not in ENGINES:
        raise UnknownEngine(f"unknown engine {name!r} (known: {', '.join(ENGINES)})")
    return ENGINES[name]


def estimate_seconds(block: str, name: str, work: float) -> float:
    """Conservative wall time of ``work`` (in the block's unit) on engine ``name``."""
    decl = _declaration(block)
    return float(work) / decl.speed[name]
