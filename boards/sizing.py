"""Size a core for a device and refuse, naming the limit, what the device cannot hold.

Limits checked (each refusal is one line naming it): cycles per sweep (one update per clock:
``n_neurons <= clock_hz / update_hz``), block RAM (state, current, parameter-set and link
buffers, counted in whole blocks of the device's geometry) and hardware multipliers (four
products per update; an ``operand_width``-bit product takes ``ceil(w / dsp_width)**2``
multiplier blocks of the device).
"""

from __future__ import annotations

import math

from ..hdl.izhikevich.config import ConfigError, IzhikevichConfig
from ..hdl.link import LinkConfig
from ..hdl.link.codec import HEADER_BYTES, MAX_FRAME
from .top import ClockPlan

__all__ = ["size_core", "estimate"]

MULTIPLIERS = 4
#: idle cycles per sweep kept for host writes (the link writes between sweeps)
LINK_IDLE_CYCLES = 16


def _blocks(depth: int, width: int, target: dict) -> int:
    """Whole RAM blocks for a depth x width memory (best aspect of the block's shapes)."""
    best = None
    for d, w in target["bram_shapes"]:
        n = math.ceil(depth / d) * math.ceil(width / w)
        best = n if best is None else min(best, n)
    return best


def estimate(lcfg: LinkConfig, target: dict) -> dict:
    cfg = lcfg.core
    N = cfg.n_neurons
    mems = [(N, cfg.V.width + cfg.U.width), (N, cfg.I.width), (N, max(cfg.sel_bits, 1)),
            (cfg.spike_fifo_depth, 16 + cfg.sweep_number_width),
            (lcfg.rx_fifo_depth, 8), (2 * lcfg.batch_capacity, 24), (MAX_FRAME, 8),
            ((MAX_FRAME - HEADER_BYTES - 2) // lcfg.current_bytes + 1, cfg.I.width)]
    bram = sum(_blocks(d, w, target) for d, w in mems if d * w > target.get("lutram_bits", 0))
    dsp = MULTIPLIERS * math.ceil(cfg.operand_width / target["dsp_width"]) ** 2
    return {"BRAM": bram, "DSP": dsp}


def size_core(target: dict, n_neurons: int | None = None, clock_hz: float | None = None,
              update_hz: float | None = None, **core_kwargs) -> dict:
    """The link configuration for ``target`` (defaults from the target), its clock plan and
    resource estimate; :class:`ConfigError` names the first limit exceeded."""
    plan: ClockPlan = target["clock_plan"]
    if update_hz is not None and update_hz != plan.update_hz or \
            clock_hz is not None and clock_hz != plan.clock_hz:
        plan = ClockPlan(plan.osc_hz, clock_hz or plan.clock_hz, update_hz or plan.update_hz,
                         plan.baud)
        if clock_hz is not None and clock_hz not in target.get("pll_clocks", [plan.clock_hz]):
            raise ConfigError(f"{target['name']}: the PLL plans give "
                              f"{', '.join(f'{c / 1e6:g}' for c in target.get('pll_clocks', []))}"
                              f" MHz, not {clock_hz / 1e6:g} MHz")
    N = n_neurons or target["default_neurons"]
    cpt = plan.cycles_per_tick
    if N + LINK_IDLE_CYCLES > cpt:
        raise ConfigError(f"{target['name']}: {N} neurons need {N + LINK_IDLE_CYCLES} cycles "
                          f"per sweep ({LINK_IDLE_CYCLES} idle for host writes), the "
                          f"{plan.clock_hz / 1e6:g} MHz clock gives {cpt} at "
                          f"{plan.update_hz / 1e3:g} kHz (cycles per tick limit)")
    kw = dict(target.get("core_defaults", {}))
    kw.update(core_kwargs)
    kw.update(n_neurons=N, clock_hz=plan.clock_hz, update_hz=plan.update_hz,
              tick_source="external")
    kw.setdefault("spike_fifo_depth", 256)
    core = IzhikevichConfig(**kw)
    lcfg = LinkConfig(core, clocks_per_bit=plan.clocks_per_bit,
                      batch_sweeps=max(1, int(round(plan.update_hz / 1000))),
                      **target.get("link_defaults", {}))
    est = estimate(lcfg, target)
    res = target["resources"]
    if est["BRAM"] > res["BRAM"]:
        raise ConfigError(f"{target['name']}: {N} neurons need about {est['BRAM']} block RAMs, "
                          f"the {target['device']} has {res['BRAM']} (RAM limit)")
    if est["DSP"] > res["DSP"]:
        raise ConfigError(f"{target['name']}: {core.operand_width}-bit operands need "
                          f"{est['DSP']} multiplier blocks, the {target['device']} has "
                          f"{res['DSP']} (DSP limit; try operand_width=16)")
    return {"link": lcfg, "estimate": est,
            "plan": {"osc_hz": plan.osc_hz, "clock_hz": plan.clock_hz,
                     "update_hz": plan.update_hz, "baud": plan.baud,
                     "cycles_per_tick": cpt, "clocks_per_bit": plan.clocks_per_bit}}
