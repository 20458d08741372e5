"""The one list of simulation engines, and which blocks each runs.

An *engine* is a way of running a block: its float64 golden model, its bit-exact integer twin,
or its RTL in a simulator. :data:`ENGINES` names every engine once with its traits, in the
order they are listed to users. An engine's implementation for a block is a class of that
block's engine interface (:class:`~cuneate.sim.engines.engine.BlockEngine`) that registers
itself with :func:`implements` (as Lava's process models declare ``@implements(proc=...)``
and Brian2's devices enter its device registry): no block lists its engines. Implementations
live in each block's ``cuneate.sim.<block>.engines`` (found, not listed) or, for an engine
that runs several blocks through one face, in the module its :data:`ENGINES` row names
(``board``: :mod:`cuneate.sim.engines.board`).

Everything that takes an engine name (``cuneate simulate``, ``cuneate run``, scenes'
``run.engines``, sweeps, the run time estimates) asks this module, so a name accepted for a
block in one place is accepted in every place that block runs, and an unknown name is refused
with the list the block supports.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
from dataclasses import dataclass, field

__all__ = ["Engine", "BlockEngines", "ENGINES", "BLOCKS", "implements", "block_engines",
           "check_engine", "engine", "engine_for", "implementation", "estimate_seconds",
           "refuse_engines_outside", "UnknownEngine"]


class UnknownEngine(ValueError):
    """An engine name that does not exist, or that the block does not support."""


@dataclass(frozen=True)
class Engine:
    """One engine and its traits.

    ``level``: ``"golden"`` (float64 model of the scheme), ``"twin"`` (bit-exact integer model
    built from the RTL's stage functions) or ``"rtl"`` (the block's hardware description in a
    simulator). ``simulator``: the HDL simulator an RTL engine runs (``None`` otherwise).
    ``background``: runs in a simulator process of its own, so a scene overlaps it with the
    Python engines. ``module``: the module holding the engine's implementations when they live
    in one module of their own rather than in the blocks' ``engines`` modules.
    """

    name: str
    level: str
    simulator: str | None
    background: bool
    summary: str
    module: str | None = None

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
           "through a simulated serial line", module="cuneate.sim.engines.board"),
    Engine("axi", "rtl", "verilator", True,
           "the block behind the AXI face (AXI4-Stream, AXI4-Lite) compiled by Verilator, "
           "driven by the host's bus transactions (no Python per cycle)",
           module="cuneate.sim.engines.axi"),
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


#: ``(block, engine)`` -> ``(implementation class, speed)``, filled by :func:`implements`.
_IMPLEMENTATIONS: dict[tuple[str, str], tuple[type, float]] = {}
#: Block name -> its engines (derived from the implementations once they are all loaded).
BLOCKS: dict[str, BlockEngines] = {}
_loaded = False


def implements(block: str, name: str, speed: float):
    """Class decorator: the class runs ``block`` as engine ``name`` (a row of
    :data:`ENGINES`), ``speed`` updates (HDL: cycles) a second on a 2-core machine,
    conservatively, for estimates. One class may implement several engines (stacked)."""
    if name not in ENGINES:
        raise ValueError(f"block {block!r}: an implementation of an unknown engine {name!r}")

    def register(cls):
        if (block, name) in _IMPLEMENTATIONS and _IMPLEMENTATIONS[block, name][0] is not cls:
            raise ValueError(f"engine {name!r} implements the {block} block twice")
        _IMPLEMENTATIONS[block, name] = (cls, float(speed))
        return cls
    return register


def _load() -> None:
    """Import every module that implements engines: each block's ``cuneate.sim.<block>
    .engines`` and the modules :data:`ENGINES` rows name; then derive :data:`BLOCKS`."""
    global _loaded
    if _loaded:
        return
    sim = importlib.import_module(__package__.rsplit(".", 1)[0])
    for info in pkgutil.iter_modules(sim.__path__):
        if info.ispkg and importlib.util.find_spec(f"{sim.__name__}.{info.name}.engines"):
            importlib.import_module(f"{sim.__name__}.{info.name}.engines")
    for e in ENGINES.values():
        if e.module is not None:
            importlib.import_module(e.module)
    _loaded = True
    blocks = sorted({b for b, _ in _IMPLEMENTATIONS})
    for b in blocks:
        names = tuple(e for e in ENGINES if (b, e) in _IMPLEMENTATIONS)
        BLOCKS[b] = BlockEngines(b, names, {e: _IMPLEMENTATIONS[b, e][1] for e in names})


def _declaration(block: str) -> BlockEngines:
    _load()
    if block not in BLOCKS:
        raise KeyError(f"no block named {block!r} has engines")
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


def refuse_engines_outside(engines, ok, where: str, what: str) -> None:
    """Refuse (one line, naming ``where``) the first of ``engines`` not in ``ok``, the engines
    that run ``what``."""
    bad = [e for e in engines if e not in ok]
    if bad:
        raise ValueError(f"{where}: engine {bad[0]!r} does not run the {what} (engines that "
                         f"do: {', '.join(ok)})")


def engine(name: str) -> Engine:
    """The traits of engine ``name``."""
    if name not in ENGINES:
        raise UnknownEngine(f"unknown engine {name!r} (known: {', '.join(ENGINES)})")
    return ENGINES[name]


def implementation(block: str, name: str) -> type:
    """The class implementing ``block`` on engine ``name`` (refused as :func:`check_engine`)."""
    check_engine(block, name)
    return _IMPLEMENTATIONS[block, name][0]


def engine_for(block: str, name: str, **options):
    """Engine ``name`` ready to run ``block`` with the run's ``options`` (``build_dir``,
    ``progress``, ``waves`` and the engine's own): an instance of its implementation."""
    return implementation(block, name)(name, **options)


def estimate_seconds(block: str, name: str, work: float) -> float:
    """Conservative wall time of ``work`` (in the block's unit) on engine ``name``."""
    decl = _declaration(block)
    return float(work) / decl.speed[name]
