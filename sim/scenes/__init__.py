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

from ... import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    ".schema": "SceneError",
    ".scene": "Scene load_scene parse_scene default_scene example_path example_names "
              "DEFAULT_SCENE_TOML",
    ".runner": "run_scene",
    ".registry": "KINDS"})
