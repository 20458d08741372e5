"""``cuneate generate plasticity``: the learning cuneate layer of a learning scene as Verilog,
alone or behind a face (UART, AXI, Wishbone).

The layer's configuration is the scene's (:func:`~cuneate.sim.plasticity.protocol
.layer_config`: its afferents, CNs, synapses, initial weights and rule), the one its runs use;
its afferent count follows from the scene's tethers and gains (``n_afferents``), so nothing is
synthesized.
"""

from __future__ import annotations

from ...hdl.lib.config import ConfigError
from ..cli.options import (CliError, add_face_option, add_generate_options, generate_faced,
                           output_dir, positive_int, verilog_name)

__all__ = ["register", "scene_layer"]


def scene_layer(scene, tick_source: str = "internal"):
    """The learning layer's configuration of a learning ``scene`` (``tick_source`` as given)."""
    from .protocol import layer_config
    if scene.kind != "learning":
        raise CliError(f"cuneate generate plasticity: {scene.name!r} is a {scene.kind} scene; "
                       f"the layer is made from a learning scene (stimulus.kind = learning)")
    try:
        cfg = layer_config(scene)
        if tick_source != cfg.tick_source:
            cfg = type(cfg).from_kwargs(cfg.to_kwargs() | {"tick_source": tick_source})
    except ConfigError as exc:
        raise CliError(f"cuneate generate plasticity: {exc}") from None
    return cfg


def cmd_generate(args) -> int:
    from ...hdl.plasticity.core import generate_learning
    from ..cli.run import resolve_scene
    scene = resolve_scene(args.scene, "cuneate generate plasticity")
    cfg = scene_layer(scene, args.tick_source)
    if args.face == "none" and args.readout_synapses is not None:
        raise CliError("cuneate generate plasticity: --readout-synapses sets a face's readout "
                       "sweeps; the layer alone (--face none) reads its weights on its host "
                       "port")
    if args.face != "none":
        return generate_faced(args, cfg, "plasticity",
                              readout_synapses=args.readout_synapses)
    for f in generate_learning(output_dir(args.out), cfg, args.name):
        print(f)
    print(f"learning layer of {scene.name!r}: {cfg.n_targets} CNs x {cfg.n_synapses} synapses "
          f"of {cfg.n_sources} afferents, {cfg.clock_hz / 1e6:g} MHz, {cfg.update_hz:g} Hz "
          f"updates; weights {cfg.W}")
    return 0


def register(groups) -> None:
    g = groups.generate.add_parser(
        "plasticity", help="the learning cuneate layer (AIDP) of a learning scene")
    g.add_argument("scene", metavar="SCENE",
                   help="a learning scene: file or shipped example name (cuneate_learning)")
    add_generate_options(g)
    add_face_option(g)
    g.add_argument("--name", type=verilog_name, default="learning_layer",
                   help="Verilog module name (default learning_layer; behind a face "
                        "NAME_FACE)")
    g.add_argument("--readout-synapses", type=positive_int, default=None, metavar="K",
                   help="behind a face: synapses a readout sweep sends (default every "
                        "synapse of a CN)")
    g.set_defaults(func=cmd_generate)
