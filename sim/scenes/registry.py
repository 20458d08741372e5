"""The registry of scene kinds: which stimulus a kind handles, which block runs it, and the
module that validates, runs and reports it.

A scene's kind follows from its stimulus (``stimulus.kind``). Each kind is one module of this
package implementing:

``validate(V, raw, sections, populations, projections)``
    the kind's own checks and completions (``V.err(key, reason)`` refuses in one line);
``run(scene, engines, build_dir, progress, log)``
    runs the scene on its engines (every one of them supported by the kind's block, see
    :mod:`cuneate.sim.engines.registry`) and returns a run with ``kind`` set;
``summary(run)``, ``write_report(run, out)``, ``format_run(run)``
    ``run.json``, the report page and what ``cuneate run`` prints.

Adding a kind: write the module and add its row to :data:`KINDS`.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

__all__ = ["SceneKind", "KINDS", "kind_for", "kind_module"]


@dataclass(frozen=True)
class SceneKind:
    """``name``: the kind (and its module's name); ``stimuli``: the ``stimulus.kind`` values it
    handles; ``block``: the block whose engines run it; ``summary``: one line for users."""

    name: str
    stimuli: tuple
    block: str
    summary: str


#: Every scene kind.
KINDS: dict[str, SceneKind] = {k.name: k for k in (
    SceneKind("afferent", ("grasp", "slide", "pulses", "recorded"), "izhikevich",
              "FBG traces through the host front end into Izhikevich afferents; decoding"),
    SceneKind("skin", ("press",), "lif",
              "a taxel grid pressed with force pulses, one LIF neuron per taxel"),
    SceneKind("ridge", ("ridges",), "network",
              "ridges sliding over two sensors: SA/FA afferents into coincidence detectors"),
    SceneKind("texture", ("textures",), "izhikevich",
              "textures slid under the MEMS fingertip: SA afferents, the seeds' decoders"),
    SceneKind("learning", ("learning",), "plasticity",
              "a cuneate layer learning the fingertip's stimuli on chip (AIDP)"),
)}


def kind_for(stimulus_kind: str) -> SceneKind:
    """The kind that handles ``stimulus_kind``."""
    for k in KINDS.values():
        if stimulus_kind in k.stimuli:
            return k
    raise KeyError(f"no scene kind handles stimulus {stimulus_kind!r}")


def kind_module(kind: SceneKind | str):
    """The module implementing ``kind``."""
    name = kind if isinstance(kind, str) else kind.name
    return importlib.import_module(f"{__package__}.{name}")
