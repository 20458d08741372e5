"""Scenes written inline by the tests: parsed after textual substitutions."""

from cuneate.sim.scenes.scene import parse_scene

__all__ = ["scene_with"]


def scene_with(text: str, **subs):
    """The scene of ``text`` with each ``key`` replaced by its value (as ``t.toml``)."""
    for a, b in subs.items():
        text = text.replace(a, b)
    return parse_scene(text, "t.toml")
