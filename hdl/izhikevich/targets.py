"""The options and the Izhikevich arithmetic of a block's target neurons (the coincidence
detector's targets, the learning layer's CNs): one core configuration, its tick external, of at
least :func:`~cuneate.hdl.izhikevich.config.min_neurons` neurons (the targets first, the
padding on parameter set 0), proven for the targets' current range."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

from ..lib.config import ConfigError
from .config import IzhikevichConfig, min_neurons

__all__ = ["TargetOptions", "target_arithmetic"]


@dataclass(kw_only=True)
class TargetOptions:
    """The options every block of Izhikevich target neurons takes (keywords only; the block's
    docstring states them): ``param_sets``, ``target_sets``, ``clock_hz``, ``tick_source``,
    ``operand_width``, ``rounding``, ``max_decay_error``; ``iz`` is derived, the targets'
    arithmetic (:func:`target_arithmetic`)."""

    param_sets: Sequence = ("RS",)
    target_sets: Sequence[int] | None = None
    clock_hz: float = 40e6
    tick_source: str = "external"
    operand_width: int = 18
    rounding: str = "nearest"
    max_decay_error: float = 1e-2

    iz: IzhikevichConfig = field(init=False, repr=False)


def target_arithmetic(cfg, what: str, current_format, current_range
                      ) -> tuple[IzhikevichConfig, list[int]]:
    """``(iz, target_sets)``: the arithmetic of ``cfg``'s targets (its ``n_targets``,
    ``param_sets``, ``target_sets``, ``update_hz``, ``operand_width``, ``rounding``) taking
    currents in ``current_format`` within ``current_range``, and each target's parameter set.
    A refusal of the core's configuration is ``"<what>' Izhikevich arithmetic refused: ..."``."""
    M = cfg.n_targets
    ts = [0] * M if cfg.target_sets is None else list(cfg.target_sets)
    if len(ts) != M or any(not 0 <= x < len(cfg.param_sets) for x in ts):
        raise ConfigError(f"target_sets needs {M} indices into the {len(cfg.param_sets)} "
                          f"parameter set(s)")
    n_iz = max(M, min_neurons())
    try:
        iz = IzhikevichConfig(
            n_neurons=n_iz, clock_hz=cfg.update_hz * n_iz, update_hz=cfg.update_hz,
            param_sets=tuple(cfg.param_sets), neuron_sets=ts + [0] * (n_iz - M),
            operand_width=cfg.operand_width, rounding=cfg.rounding,
            current_format=current_format, current_range=current_range,
            tick_source="external")
    except ConfigError as exc:
        raise ConfigError(f"{what}' Izhikevich arithmetic refused: {exc}") from None
    return iz, ts
