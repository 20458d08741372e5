"""Size the Izhikevich cores for a device and refuse, naming the limit, what it cannot hold.

A build holds ``n_cores`` cores of ``n_neurons`` each (one core, or an
:class:`~cuneate.hdl.izhikevich.array.IzhikevichArray` behind the link). For the requested
neuron count the sizing takes each of the target's PLL plans whose clock the pipeline depth's
fmax bound allows, the fewest cores whose sweeps fit the cycles per tick
(``n_neurons + LINK_IDLE_CYCLES <= clock_hz / update_hz``) and whose memories, multipliers and
logic fit the device, and the plan that needs the fewest cores. Limits checked (each refusal
is one line naming it): cycles per sweep, block RAM (state, current, parameter-set memories and
the spike FIFO of every core plus the link's buffers, counted in whole blocks of the device's
best shape for each memory), hardware multipliers (four products per update; an
``operand_width``-bit product takes ``ceil(w / dsp_width)**2`` multiplier blocks), logic
(measured cells per core, where the target gives them) and the link's 65 536 neuron ids.
"""

from __future__ import annotations

import math

from ..hdl.izhikevich.config import ConfigError, IzhikevichConfig
from ..hdl.lib.banked import bank_shape
from ..hdl.lib.payload import payload_spec
from ..hdl.link.config import LINK_IDLE_CYCLES, LinkConfig, sweep_cycles
from ..hdl.link.codec import HEADER_BYTES, MAX_FRAME
from .top import ClockPlan

__all__ = ["size_core", "estimate", "limits", "clock_plans", "chosen_plans", "MAX_LINK_NEURONS",
           "count_blocks",
           "device_overrun", "fmax_bound", "target_core", "target_link", "FMAX_MARGIN"]

MULTIPLIERS = 4
#: the share of a core's measured (out of context) fmax the sizing clocks a board build at
FMAX_MARGIN = 0.9
#: neuron ids the link's 16-bit addresses reach
MAX_LINK_NEURONS = 1 << 16


def clock_plans(target: dict) -> list:
    """``[(ClockPlan, pll builder)]`` of ``target``, its default plan first."""
    return list(target.get("clock_plans") or [(target["clock_plan"], target.get("pll"))])


def _blocks(depth: int, width: int, target: dict) -> int:
    """Whole RAM blocks for a depth x width memory: the cores' banks
    (:func:`~cuneate.hdl.lib.banked.bank_shape`, the best of the block's shapes)."""
    return bank_shape(depth, width, target["bram_shapes"])[1]


def _core_memories(cfg: IzhikevichConfig, n: int) -> list:
    """``(depth, width)`` of one core's memories at ``n`` neurons."""
    return [(n, cfg.V.width + cfg.U.width), (n, cfg.I.width), (n, max(cfg.sel_bits, 1)),
            (cfg.spike_fifo_depth, 16 + cfg.sweep_number_width)]


def _link_memories(lcfg: LinkConfig) -> list:
    return [(lcfg.rx_fifo_depth, 8), (2 * lcfg.batch_capacity, 24), (MAX_FRAME, 8),
            ((MAX_FRAME - HEADER_BYTES - 2) // lcfg.current_bytes + 1, lcfg.current_width)]


def count_blocks(mems, target: dict) -> int:
    """Block RAMs for the ``(depth, width)`` memories ``mems`` (those above the target's LUT
    RAM size; each at its best block shape)."""
    return sum(_blocks(d, w, target) for d, w in mems if d * w > target.get("lutram_bits", 0))


def _dsp_per_core(cfg: IzhikevichConfig, target: dict) -> int:
    """Multiplier blocks of one core: four products, each ``ceil(w / dsp_width)**2`` blocks."""
    return MULTIPLIERS * math.ceil(cfg.operand_width / target["dsp_width"]) ** 2


def _estimate(cfg: IzhikevichConfig, lcfg: LinkConfig, n: int, cores: int,
              target: dict) -> dict:
    bram = cores * count_blocks(_core_memories(cfg, n), target) + \
        count_blocks(_link_memories(lcfg), target)
    dsp = cores * _dsp_per_core(cfg, target)
    out = {"BRAM": bram, "DSP": dsp, "cores": cores}
    logic = target.get("logic_per_core")
    if logic:
        out["LUT"] = cores * logic + target.get("logic_link", 0)
    return out


def estimate(lcfg: LinkConfig, target: dict) -> dict:
    """Block RAMs, multiplier blocks (and logic cells where the target gives a per-core
    figure) the linked cores of ``lcfg`` need on ``target``."""
    return _estimate(lcfg.core, lcfg, lcfg.core.n_neurons, lcfg.n_cores, target)


def device_overrun(est: dict, target: dict) -> str | None:
    """The first device limit ``est`` exceeds, as a phrase, or None."""
    res = target["resources"]
    for kind, what, limit in (("BRAM", "block RAMs", "RAM limit"),
                              ("DSP", "multiplier blocks", "DSP limit"),
                              ("LUT", "logic cells", "logic limit")):
        if kind in est and est[kind] > res[kind]:
            return (f"about {est[kind]} {what}, the {target['device']} has {res[kind]} "
                    f"({limit})")
    return None


def fmax_bound(target: dict, depth: int) -> float | None:
    """The fmax (Hz) the target's measurements give a build with cores of pipeline ``depth``:
    the core's (out of context) or the link's (in a board build), whichever is lower."""
    table = target.get("fmax_mhz") or {}
    known = [d for d in table if d <= depth]
    bounds = ([table[max(known)]] if known else []) + \
        ([target["link_fmax_mhz"]] if target.get("link_fmax_mhz") else [])
    return min(bounds) * 1e6 if bounds else None


def _choose(target: dict, N: int, plans: list, cfg: IzhikevichConfig, depth: int):
    """``(plan, pll, cores, per-core neurons, estimate)`` for ``N`` neurons: per plan the
    fewest cores that fit, then the plan with the fewest cores (the lower clock on a tie);
    raises :class:`ConfigError` naming the limit when none fits."""
    best, why = None, []
    fmax = fmax_bound(target, depth)
    for plan, pll in plans:
        if fmax is not None and plan.clock_hz > FMAX_MARGIN * fmax and len(plans) > 1:
            why.append(f"the {plan.clock_hz / 1e6:g} MHz plan is above {FMAX_MARGIN:g} x "
                       f"the {fmax / 1e6:.4g} MHz fmax of the link and depth-{depth} cores "
                       f"(fmax limit)")
            continue
        per_core = plan.cycles_per_tick - LINK_IDLE_CYCLES
        if per_core < 1:
            continue
        k_min = math.ceil(N / per_core)
        k_max = max(k_min, target["resources"]["DSP"] // _dsp_per_core(cfg, target))
        link = target_link(target, cfg, plan)      # its buffers do not depend on N
        for k in range(k_min, k_max + 1):
            n = math.ceil(N / k)
            est = _estimate(cfg, link, n, k, target)
            over = device_overrun(est, target)
            if over is None:
                if best is None or k < best[2]:
                    best = (plan, pll, k, n, est)
                break
            if k == k_min:
                why.insert(0, f"{N} neurons as {k} core{'s' if k > 1 else ''} of {n} at "
                              f"{plan.clock_hz / 1e6:g} MHz need {over}; more cores do not "
                              f"fit either")
    if best is None:
        raise ConfigError(f"{target['name']}: {'; '.join(why)}")
    return best


def limits(target: dict, pipeline_stages: int = 5) -> dict:
    """The bounds on neurons at the target's update rate: ``bram`` (every block RAM bit used
    by state, current and set at the best shapes' packing), ``multiplier`` (every multiplier
    block in a core at the fastest plan's cycles per tick), ``fmax`` (cores as many as the
    logic holds, each at the measured fmax), ``largest`` (what the sizing accepts) and the
    clock, cores and per-core neurons of the largest."""
    plans = clock_plans(target)
    cfg = _width_config(target)
    res = target["resources"]
    per_bits = cfg.V.width + cfg.U.width + cfg.I.width + max(cfg.sel_bits, 1)
    block_bits = max(d * w for d, w in target["bram_shapes"])
    dsp_core = _dsp_per_core(cfg, target)
    fastest = max(p.clock_hz for p, _ in plans)
    upd = plans[0][0].update_hz
    fmax = fmax_bound(target, pipeline_stages)
    logic = target.get("logic_per_core")
    cores_by_logic = (res["LUT"] - target.get("logic_link", 0)) // logic if logic else None
    lo, hi = 1, MAX_LINK_NEURONS
    largest = None
    while lo <= hi:                        # the sizing's acceptance is monotone in N
        mid = (lo + hi) // 2
        try:
            largest = (mid, size_plan(target, mid, pipeline_stages))
            lo = mid + 1
        except ConfigError:
            hi = mid - 1
    out = {"bram": res["BRAM"] * block_bits // per_bits,
           "multiplier": (res["DSP"] // dsp_core) * (int(fastest // upd) - LINK_IDLE_CYCLES),
           "fmax": (cores_by_logic * int(fmax // upd) if fmax and cores_by_logic else None),
           "fmax_mhz": fmax / 1e6 if fmax else None, "update_hz": upd,
           "bits_per_neuron": per_bits}
    if largest:
        n, (plan, _, k, per, est) = largest
        out.update(largest=n, clock_hz=plan.clock_hz, cores=k, per_core=per, estimate=est)
    return out


def target_core(target: dict, core_kwargs: dict, n: int, clock_hz: float,
                 update_hz: float) -> IzhikevichConfig:
    """A core of ``n`` neurons for ``target`` (its ``core_defaults``, then ``core_kwargs``;
    external tick: the link drives it)."""
    kw = dict(target.get("core_defaults", {}))
    kw.update(core_kwargs)
    kw.update(n_neurons=n, clock_hz=clock_hz, update_hz=update_hz, tick_source="external")
    kw.setdefault("spike_fifo_depth", 256)
    kw.setdefault("bram_shapes", tuple(tuple(s) for s in target["bram_shapes"]))
    return IzhikevichConfig(**kw)


def _width_config(target: dict, **core_kwargs) -> IzhikevichConfig:
    """A small configuration with the target's formats (widths do not depend on N)."""
    core_kwargs.pop("neuron_sets", None)
    return target_core(target, core_kwargs, 16, 16 * 16e3, 16e3)


def target_link(target: dict, block, plan: ClockPlan, **spec) -> LinkConfig:
    """The link for ``block`` (a configuration or payload spec, with the spec's options: an
    array's ``n_cores`` and ``neuron_sets``, a ``fanout`` in front) at ``plan``: the block at
    the plan's clock, its ticks from the link, one spike batch a millisecond; refused (one
    line) when a sweep cannot hold the block's work and the link's idle cycles
    (:func:`~cuneate.hdl.link.config.sweep_cycles`)."""
    p = payload_spec(block, **spec)          # its work a tick does not depend on the clock
    need = sweep_cycles(p.info)
    if plan.cycles_per_tick < need:
        raise ConfigError(f"a sweep of {plan.cycles_per_tick} cycles cannot hold the "
                          f"{p.info.block}'s {p.info.busy_cycles} cycles of work and the "
                          f"link's {LINK_IDLE_CYCLES} idle ones")
    return LinkConfig(p.retimed(plan.clock_hz), clocks_per_bit=plan.clocks_per_bit,
                      batch_sweeps=max(1, int(round(plan.update_hz / 1000))),
                      **target.get("link_defaults", {}))


def size_plan(target: dict, N: int, pipeline_stages: int = 5, plans=None, **core_kwargs):
    """``(plan, pll, cores, per-core neurons, estimate)`` for ``N`` neurons on ``target``
    (arithmetic only: no core is elaborated)."""
    if N > MAX_LINK_NEURONS:
        raise ConfigError(f"{target['name']}: {N} neurons exceed the link's "
                          f"{MAX_LINK_NEURONS} neuron ids (link limit)")
    cfg = _width_config(target, pipeline_stages=pipeline_stages, **core_kwargs)
    return _choose(target, N, plans or clock_plans(target), cfg, pipeline_stages)


def chosen_plans(target: dict, clock_hz: float | None = None, update_hz: float | None = None,
                 baud: float | None = None) -> list:
    """The target's clock plans (:func:`clock_plans`) at the requested clock (one of them),
    update rate and line rate (default: the target's); :class:`ConfigError` names a clock the
    PLL plans do not give, or a line rate no plan's clock divides within
    :data:`~cuneate.boards.top.MAX_BAUD_ERROR`."""
    plans = clock_plans(target)
    if clock_hz is not None:
        chosen = [(p, pll) for p, pll in plans if p.clock_hz == clock_hz]
        if not chosen:
            raise ConfigError(f"{target['name']}: the PLL plans give "
                              f"{', '.join(f'{p.clock_hz / 1e6:g}' for p, _ in plans)}"
                              f" MHz, not {clock_hz / 1e6:g} MHz")
        plans = chosen
    if update_hz is None and baud is None:
        return plans
    out, why = [], []
    for p, pll in plans:
        try:
            out.append((ClockPlan(p.osc_hz, p.clock_hz, update_hz or p.update_hz,
                                  baud or p.baud), pll))
        except ConfigError as exc:
            why.append(str(exc))
    if not out:
        raise ConfigError(f"{target['name']}: {'; '.join(why)}")
    return out


def size_core(target: dict, n_neurons: int | None = None, clock_hz: float | None = None,
              update_hz: float | None = None, baud: float | None = None,
              **core_kwargs) -> dict:
    """The link configuration for ``target`` (defaults from the target): its clock plan (the
    requested ``clock_hz`` or the one :func:`size_plan` chooses; the line at ``baud``), cores
    and resource estimate; :class:`ConfigError` names the first limit exceeded.
    ``neuron_sets`` (in ``core_kwargs``: one parameter set per requested neuron) go to the
    core, or, in an array, to each core's own neurons (the padding neurons take set 0)."""
    plans = chosen_plans(target, clock_hz, update_hz, baud)
    N = n_neurons or target["default_neurons"]
    depth = core_kwargs.get("pipeline_stages", 5)
    sets = core_kwargs.pop("neuron_sets", None)
    plan, pll, k, n, est = size_plan(target, N, plans=plans, **core_kwargs)
    if sets is not None:
        sets = [int(s) for s in sets]
        if len(sets) > n * k:
            raise ConfigError(f"{target['name']}: neuron_sets gives {len(sets)} sets for "
                              f"{N} neurons")
        sets += [0] * (n * k - len(sets))
        if k == 1:
            core_kwargs["neuron_sets"] = sets
    core = target_core(target, core_kwargs, n, plan.clock_hz, plan.update_hz)
    lcfg = target_link(target, core, plan, n_cores=k,
                       **({"neuron_sets": sets} if sets is not None and k > 1 else {}))
    return {"link": lcfg, "estimate": estimate(lcfg, target), "pll": pll,
            "requested_neurons": N, "pipeline_stages": depth,
            "plan": {"osc_hz": plan.osc_hz, "clock_hz": plan.clock_hz,
                     "update_hz": plan.update_hz, "baud": plan.line_baud,
                     "cycles_per_tick": plan.cycles_per_tick,
                     "clocks_per_bit": plan.clocks_per_bit}}
