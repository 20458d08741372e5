"""Trials in turn: a board that holds ``k`` of an afferent scene's trials
(``hardware.board_trials``) plays them ``k`` at a time, one group after another, as a hand
presents one grasp after another.

The engines otherwise lay every trial side by side on one core, each from the reset state. In
turn, the core holds the first ``k`` trials' afferents (and their cuneate layer): the board's
core, as ``cuneate build`` puts it on the board. The host streams group ``g``'s samples
(trials ``g k`` .. ``g k + k - 1``; a last group short of trials gets idle ones, at 0) from
sweep ``g n`` on, ``n`` a trial's sweeps: the neurons' state carries from one group into the
next as it does on the board, so every engine run in turn (golden, fixed, board) plays the same
schedule and their trains compare exactly. Spikes of group ``g``'s window, sweeps ``g n`` ..
``g n + n - 1``, are its trials' spikes, shifted back by ``g n`` sweeps: the run's report,
decoding and spike files see the scene's trials as ever.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..engines.run import spike_ticks, spike_times
from ..fanout.scene import ChannelPlan
from ..host.driver import FbgDriver
from ..network.scene import scene_layer

__all__ = ["InTurn", "in_turn"]


@dataclass
class InTurn:
    """The in-turn schedule of a scene's ``n_trials`` trials, ``k`` at a time, ``n_ticks``
    sweeps of ``dt_ms`` a trial, ``per_trial`` afferents a trial."""

    k: int
    n_trials: int
    n_ticks: int
    dt_ms: float
    per_trial: int

    @property
    def n_groups(self) -> int:
        return -(-self.n_trials // self.k)

    def fold(self, per_sample: np.ndarray, width: int) -> np.ndarray:
        """Columns of every trial ``(n_samples, n_trials width)`` (trial-major, ``width`` a
        trial) as the board streams them: ``(n_groups n_samples, k width)``, group after
        group (an idle trial's columns 0)."""
        x = np.asarray(per_sample)
        n = x.shape[0]
        out = np.zeros((self.n_groups * n, self.k * width), dtype=x.dtype)
        for g in range(self.n_groups):
            cols = x[:, g * self.k * width:(g + 1) * self.k * width]
            out[g * n:(g + 1) * n, :cols.shape[1]] = cols
        return out

    def unfold(self, trains: list, width: int | None = None) -> list:
        """Spike trains of the board's neurons (ms, ``width`` a trial; default the
        afferents') as the scene's trials': every trial's ``width`` trains, each shifted back
        to its own window."""
        w = self.per_trial if width is None else width
        out = []
        for t in range(self.n_trials):
            g, j = divmod(t, self.k)
            for s in trains[j * w:(j + 1) * w]:
                s = np.asarray(s, dtype=np.float64)
                # the update of sweep T is at (T + 1) dt; window g holds sweeps g n .. g n + n - 1
                ticks = spike_ticks(s, self.dt_ms) - g * self.n_ticks
                keep = (ticks >= 0) & (ticks < self.n_ticks)
                out.append(spike_times(ticks[keep], self.dt_ms))
        return out

    def describe(self) -> dict:
        return {"trials_at_a_time": self.k, "groups": self.n_groups,
                "ticks_a_group": self.n_ticks, "ticks": self.n_groups * self.n_ticks}


def in_turn(scene, ctx: dict, n_trials: int, nk, cfg):
    """The in-turn schedule of ``scene``'s ``n_trials`` trials on the board's core ``cfg``
    holding the afferents ``nk`` of its first trials, and the engines' context for it:
    ``ctx`` (the run's context for every trial side by side: its driver, currents, raw
    currents, channel plan, cuneate layer, sweeps) with the board's core, neurons, driver,
    folded currents, channel plan and layer and the groups' sweeps."""
    per = len(ctx["neurons"]) // n_trials
    k = len(nk) // per
    if not 1 <= k <= n_trials:
        raise ValueError(f"{k} trials at a time: the scene has {n_trials}")
    drv = ctx["driver"]
    if drv.latency_ticks:
        raise ValueError(f"frontend.latency_ticks = {drv.latency_ticks}: in turn, a group's "
                         f"last samples would drive the next group's trials (play the trials "
                         f"in turn without latency)")
    turn = InTurn(k, n_trials, ctx["n_ticks"], ctx["config"].dt_ms, per)
    out = dict(ctx, neurons=nk, config=cfg, currents=turn.fold(ctx["currents"], per),
               raw=turn.fold(ctx["raw"], per), n_ticks=turn.n_groups * turn.n_ticks,
               driver=FbgDriver(cfg, nk.encoding, drv.fs_hz, drv.latency_ticks,
                                on_gap=drv.on_gap),
               layer=scene_layer(scene, nk, cfg))
    fan = ctx["fanout"]
    if fan is not None:
        fk = fan.config.first(len(nk))
        c = fk.n_channels // k                  # a trial's channels (trial-major)
        cd = fan.driver
        out["fanout"] = ChannelPlan(
            fan.channels[:fk.n_channels], turn.fold(fan.samples, c), turn.fold(fan.raw, c), fk,
            FbgDriver(fk.written(cfg), [None] * fk.n_channels, cd.fs_hz, cd.latency_ticks))
    return turn, out
