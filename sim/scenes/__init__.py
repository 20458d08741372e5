"""Scenes: the questions a user puts to the hardware, as TOML files.

``schema``    every section and key, their types, defaults, bounds and units; the validator
``scene``     :func:`load_scene`, :func:`parse_scene`, :class:`Scene`, the embedded default scene,
              the shipped examples (``examples/``)
``registry``  the scene kinds: which stimulus each handles and which block runs it
``runner``    :func:`run_scene` for every kind, and the engine agreement
``afferent``, ``skin``, ``ridge``  one module per kind: validate, run, summary, report

The names below load on first use.
"""

from __future__ import annotations

import importlib

_EXPORTS = {"SceneError": ".schema", "Scene": ".scene", "load_scene": ".scene",
            "parse_scene": ".scene", "default_scene": ".scene", "example_path": ".scene",
            "example_names": ".scene", "DEFAULT_SCENE_TOML": ".scene", "run_scene": ".runner",
            "KINDS": ".registry"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
