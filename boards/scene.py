"""What a board built for a scene holds (``cuneate build BOARD SCENE``): the scene's blocks
behind the host link, sized to it, and the link's budget for streaming it in real time.

Every board top is :class:`~cuneate.hdl.link.LinkedTop`: the scene's blocks' payload behind
the UART face. By scene kind:

``afferent``
    the Izhikevich afferents behind the link (an array of cores when one does not hold them);
    with the channel fan-out (``hardware.fanout``) one core fed by the fan-out: the host
    streams the channels, the table on chip makes the afferents' currents. ``hardware.board_trials`` (for
    instance 1 for the whole hand: one hand's gratings) builds the board for that many of the
    scene's trials (the engines lay every trial side by side on one core; a physical hand
    presents one grasp at a time); ``cuneate stream`` plays the trials in turn on it
    (:mod:`cuneate.sim.scenes.in_turn`). A scene with a cuneate layer
    (:mod:`cuneate.sim.network.scene`) gets the afferent -> cuneate network instead of the
    bare core, its detector holding the
    layer of the trials on board (behind the fan-out when the scene streams channels);
``ridge``
    the afferent -> cuneate network;
``skin``
    the LIF core.

The budget is the worst case: every value the host writes changes every sample (a ridge
scene's currents every sweep), every neuron fires at 200 Hz. A scene the board's link cannot
carry, or whose spikes overflow a batch's frame, is refused in one line naming the figure.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..hdl.lib.config import ConfigError

__all__ = ["BoardRequest", "scene_request", "WORST_RATE_HZ"]

#: the firing rate of every neuron in the budget's worst case
WORST_RATE_HZ = 200.0
#: logic cells of a cuneate layer's detector beside the core: the whole hand's hand on the
#: ULX3S took 7789 LUTs with its detector (6 x 192), 4880 without (seed 1), rounded up
DETECTOR_LUTS = 3000


@dataclass
class BoardRequest:
    """A scene's board: ``kind`` (``core``, ``fanout``, ``network``, ``lif``), the neurons the
    board holds, the blocks (one description each), the link's budget, and for ``core`` the core
    keywords the sizing takes (:func:`~cuneate.boards.sizing.size_core`); for the other kinds
    ``linked(plan, target, pipeline_stages)`` returns the link configuration at a clock plan
    (:func:`~cuneate.boards.sizing.target_link`; the board top is its
    :class:`~cuneate.hdl.link.LinkedTop`). ``update_hz``: the blocks' sweep rate."""

    kind: str
    neurons: int
    sample_hz: float
    update_hz: float
    blocks: list
    core: dict | None = None
    linked: object = None
    trials: dict = field(default_factory=dict)
    #: resources of blocks beside the cores the sizing estimates (a cuneate layer's detector)
    extra: dict = field(default_factory=dict)
    link_budget: dict = field(default_factory=dict)
    link_budget_lines: list = field(default_factory=list)

    def describe(self) -> dict:
        """The report's ``scene`` section."""
        return {"kind": self.kind, "neurons": self.neurons, "sample_hz": self.sample_hz,
                "update_hz": self.update_hz,
                "blocks": self.blocks, "link_budget": self.link_budget,
                "link_budget_lines": self.link_budget_lines} | self.trials


def _check_budget(req: BoardRequest, target: dict, values: str, written: int,
                  width: int, update_hz: float, spike_neurons: int,
                  real_time: bool = True, baud: float | None = None) -> None:
    from ..hdl.link.codec import MAX_FRAME, MIN_FRAME, SPIKE_HEADER
    from ..sim.host.uart import BUDGET_BAUDS, format_budget, link_budget
    baud = baud or target["clock_plan"].baud
    budget = link_budget(written, width, req.sample_hz, update_hz,
                         WORST_RATE_HZ * spike_neurons, bauds=sorted({*BUDGET_BAUDS, baud}))
    req.link_budget = budget
    req.link_budget_lines = format_budget(budget)
    if not real_time:
        return
    line = f"{baud / 1e6:g} Mbaud" if baud >= 1e6 else f"{baud:g} baud"
    row = next(r for r in budget["rows"] if r["baud"] == baud)
    cap = baud / 10
    if budget["in_bytes_per_s"] > cap:
        raise ConfigError(f"{target['name']}: the scene's {values} take "
                          f"{budget['in_bytes_per_s']:,.0f} B/s to the board (worst case: "
                          f"{written} {values} every sample at {req.sample_hz:g} Hz), "
                          f"more than the {line} link's {cap:,.0f} B/s (link limit)")
    if not row["real_time"]:
        raise ConfigError(f"{target['name']}: the scene's spikes take "
                          f"{budget['out_bytes_per_s']:,.0f} B/s from the board (worst case: "
                          f"{spike_neurons} neurons at {WORST_RATE_HZ:g} Hz), more than the "
                          f"{line} link's {cap:,.0f} B/s (link limit)")
    frame_spikes = (MAX_FRAME - MIN_FRAME - SPIKE_HEADER) // 3
    if budget["spikes_per_batch"] > frame_spikes:
        raise ConfigError(f"{target['name']}: {budget['spikes_per_batch']:.0f} spikes a batch "
                          f"of {budget['batch_sweeps']} sweeps (worst case: {spike_neurons} "
                          f"neurons at {WORST_RATE_HZ:g} Hz) exceed the {frame_spikes} a spike "
                          f"frame holds (link limit)")


def scene_request(scene, target: dict, real_time: bool = True,
                  baud: float | None = None) -> BoardRequest:
    """The :class:`BoardRequest` of ``scene`` on ``target``; :class:`ConfigError` names the
    first limit it exceeds (the link's budget at ``baud``, default the target's, unless
    ``real_time`` is false: a lockstep host such as ``cuneate stream`` waits for the line; the
    device's when the build sizes it)."""
    from ..sim.scenes.registry import kind_for
    kind = kind_for(scene["stimulus"]["kind"]).name
    return {"afferent": _afferent, "ridge": _ridge, "skin": _skin}[kind](scene, target,
                                                                         real_time, baud)


def _afferent(scene, target: dict, real_time: bool = True,
              baud: float | None = None) -> BoardRequest:
    from ..sim.scenes.afferent import build_neurons, n_driven, scene_core
    n_all = n_driven(scene)[0]
    hw = scene["hardware"]
    k = hw["board_trials"] or n_all
    neurons = build_neurons(scene, k)
    core = scene_core(scene, neurons)
    fs = scene["sensor"]["sample_rate_hz"]
    trials = {"trials_on_board": k, "trials": n_all}
    block = {"block": "izhikevich_core", "neurons": len(neurons),
             "param_sets": list(core["param_sets"])}
    if any(p["model"] == "cuneate" for p in scene.populations):
        return _layered(scene, target, neurons, core, trials, block, real_time, baud)
    if not hw["fanout"]:
        req = BoardRequest("core", len(neurons), fs, core["update_hz"], [block], core=core,
                           trials=trials)
        from ..hdl.izhikevich.config import IzhikevichConfig
        width = IzhikevichConfig(n_neurons=8, clock_hz=16 * core["update_hz"],
                                 update_hz=core["update_hz"],
                                 current_format=core["current_format"]).I.width
        _check_budget(req, target, "currents", len(neurons), width, core["update_hz"],
                      len(neurons), real_time, baud)
        return req
    fan = _scene_fanout(scene, k)
    req = BoardRequest("fanout", len(neurons), fs, core["update_hz"], [fan.to_dict(), block],
                       core=core, trials=trials)
    _check_budget(req, target, "channels", fan.n_channels, fan.S.width, core["update_hz"],
                  len(neurons), real_time, baud)

    def linked(plan, target, pipeline_stages=5):
        from .sizing import target_core, target_link
        from ..hdl.fanout import FanoutConfig
        from ..hdl.lib.config import MIN_NEURONS
        n = max(len(neurons), MIN_NEURONS)      # a core's fewest neurons, as the engines pad
        kw = {k: v for k, v in core.items() if k != "update_hz"}
        kw["neuron_sets"] = list(core["neuron_sets"]) + [0] * (n - len(neurons))
        kw["pipeline_stages"] = pipeline_stages
        cfg = target_core(target, kw, n, plan.clock_hz, plan.update_hz)
        f = FanoutConfig.from_kwargs(fan.to_kwargs() | {"clock_hz": plan.clock_hz})
        return target_link(target, cfg, plan, fanout=f)
    req.linked = linked
    return req


def _layered(scene, target: dict, neurons, core: dict, trials: dict, block: dict,
             real_time: bool, baud) -> BoardRequest:
    """The board of an afferent scene with a cuneate layer: the network of the trials on board
    (their afferents on one core, their cuneate neurons on the detector), behind the channel
    fan-out when the scene streams channels."""
    from ..sim.izhikevich.engines import engine_core
    from ..sim.network.scene import layer_network, scene_layer
    k, fs = trials["trials_on_board"], scene["sensor"]["sample_rate_hz"]
    base = engine_core(core, len(neurons))          # the engines' core: the layer's sources
    layer = scene_layer(scene, neurons, base)
    n_spikes = base.n_neurons + layer.n_targets
    fan = _scene_fanout(scene, k) if scene["hardware"]["fanout"] else None
    blocks = ([fan.to_dict()] if fan else []) + [block, layer.describe()]
    det = layer.network.det
    from .sizing import count_blocks
    widths = sum(x.width for x in (det.iz.V, det.iz.U, det.traces[0].T, det.traces[1].T))
    w = target["dsp_width"]
    # the detector's multipliers (its neurons' four, the two trace decays: the unsigned
    # constant a bit wider as a signed operand), each ceil(a / w) x ceil(b / w) blocks at
    # most, and its memories
    ops = [*det.to_dict()["izhikevich"]["multiplier_operands"].values(),
           *([t.K.width + 1, t.Y.width] for t in det.traces)]
    extra = {"DSP": sum(-(-a // w) * -(-b // w) for a, b in ops), "BRAM": count_blocks(
        [(det.n_targets * det.n_sources, det.history_addr_bits + det.W.width),
         (det.max_delay_ticks, det.n_sources), (det.n_targets, widths)], target)}
    if target.get("logic_per_core"):      # the target estimates logic: the detector's too
        extra["LUT"] = DETECTOR_LUTS
    req = BoardRequest("fanout" if fan else "network", len(neurons) + layer.n_targets, fs,
                       core["update_hz"], blocks, trials=trials, extra=extra)
    if fan is not None:
        _check_budget(req, target, "channels", fan.n_channels, fan.S.width, core["update_hz"],
                      n_spikes, real_time, baud)
    else:
        _check_budget(req, target, "currents", base.n_neurons, base.I.width, core["update_hz"],
                      n_spikes, real_time, baud)

    def linked(plan, target, pipeline_stages=None):
        from .sizing import target_link
        from ..hdl.fanout import FanoutConfig
        from ..hdl.izhikevich.config import PIPELINE_DEPTH
        if pipeline_stages not in (None, PIPELINE_DEPTH):
            raise ConfigError(f"the network's afferent core has {PIPELINE_DEPTH} stages "
                              f"(--pipeline-stages sets a bare core's)")
        net = layer_network(base, layer.delays, layer.weights, layer.preset,
                            clock_hz=plan.clock_hz,
                            cuneate_fifo_depth=max(16, layer.n_targets))
        f = None if fan is None else \
            FanoutConfig.from_kwargs(fan.to_kwargs() | {"clock_hz": plan.clock_hz})
        return target_link(target, net, plan, fanout=f)
    req.linked = linked
    return req


def _scene_fanout(scene, k: int):
    """The fan-out of the first ``k`` trials of ``scene``: its table as the engines build it
    for every trial (the sample format holds every trial's largest sample), cut to the
    channels and afferents of those trials (the first in the engines' order)."""
    from ..sim.scenes.afferent import scene_channel_plan
    from ..sim.scenes.afferent import build_neurons, n_driven
    full = scene_channel_plan(scene).config
    neurons = build_neurons(scene, n_driven(scene)[0])
    return full.first(sum(1 for t in neurons.trial if t < k))


def _ridge(scene, target: dict, real_time: bool = True,
           baud: float | None = None) -> BoardRequest:
    from ..sim.coincidence.experiments import network_config
    from ..sim.scenes.ridge import spec_of
    net = network_config(spec_of(scene))
    n_spikes = net.n_afferents + net.n_targets
    req = BoardRequest("network", n_spikes, net.update_hz, net.update_hz, [
        {"block": "izhikevich_core", "neurons": net.n_afferents, "role": "SA and FA afferents"},
        {"block": "coincidence_detector", "neurons": net.n_targets,
         "sources": net.det.n_sources}])
    # the ridge's currents may change every sweep: one write a sweep
    _check_budget(req, target, "currents", net.n_afferents, net.core.I.width, net.update_hz,
                  n_spikes, real_time, baud)

    def linked(plan, target, pipeline_stages=None):
        from .sizing import target_link
        return target_link(target, net, plan)
    req.linked = linked
    return req


def _skin(scene, target: dict, real_time: bool = True,
          baud: float | None = None) -> BoardRequest:
    from ..sim.lif.engines import engine_config
    from ..sim.scenes.skin import core_keywords
    rows, cols = scene["sensor"]["grid"]
    hw = scene["hardware"]
    base = engine_config({"update_hz": hw["update_hz"]} | core_keywords(scene), rows * cols)
    n = rows * cols
    req = BoardRequest("lif", n, scene["sensor"]["sample_rate_hz"], hw["update_hz"], [
        {"block": "lif_core", "neurons": n, "core_neurons": base.n_neurons,
         "param_sets": [scene.populations[0]["preset"]]}])
    _check_budget(req, target, "currents", n, base.I.width, hw["update_hz"], n, real_time, baud)

    def linked(plan, target, pipeline_stages=None):
        from .sizing import target_link
        return target_link(target, base, plan)
    req.linked = linked
    return req
