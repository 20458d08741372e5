"""An afferent scene with a cuneate layer, for the tests that run one: the slide-texture
example cut short, with two cuneate neurons a trial over its SA and FA afferents."""

from cuneate.sim.scenes import example_path

__all__ = ["LAYER", "layered_text"]

SLIDE = example_path("slide_texture.toml").read_text()
LAYER = """
[[population]]
name = "cn"
model = "cuneate"
size = 2
inputs = ["sa", "fa"]

[[projection]]
source = "sa"
target = "cn"
weight = 10.0

[[projection]]
source = "fa"
target = "cn"
weight = 10.0
delays_ms = [1, 2]

"""


def layered_text(layer=LAYER, duration_ms=200, trials=2, engines='["golden", "fixed"]'):
    return (SLIDE.replace("[hardware]", layer + "[hardware]")
            .replace("duration_ms = 500", f"duration_ms = {duration_ms}")
            .replace("trials = 8", f"trials = {trials}")
            .replace('engines = ["golden", "fixed"]', f"engines = {engines}"))
