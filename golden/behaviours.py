"""Izhikevich's twenty neuro-computational behaviours (2004), with the published stimuli.

Each :class:`Behaviour` carries the parameter set, initial state, stimulus and duration of one
panel of the published figure (the figure's MATLAB code, "Which model to use for cortical
spiking neurons?", IEEE TNN 15(5), 2004), so that every engine can be driven exactly as the
figure was. Where the figure code differs from the paper's table or from the standard equations,
the figure code is followed and :attr:`Behaviour.note` says so:

* (G) class-1 excitability and (L) integrator use the v-equation ``0.04 v^2 + 4.1 v + 108``;
* (P) bistability uses ``a = 0.1, b = 0.26`` (the table lists ``a = 1, b = 1.5``);
* (R) accommodation uses ``du/dt = a b (v + 65)`` (no ``-u`` term) and starts at ``u = -16``;
* (S), (T) use ``a < 0`` and ``b = -1``.

What is *not* taken from the figure code is its integration: the figure integrates with a
semi-implicit Euler step (``u`` from the new ``v``) at ``tau`` = 0.1-0.5 ms and tests
``v > 30``; every cuneate engine integrates by its own stated scheme (forward Euler at the core's
``dt`` by default) and tests ``v >= 30``. :attr:`Behaviour.figure_tau_ms` keeps the figure's step
for reference. Stimuli are functions of ``t`` (ms), read at the start of each update
(``t = k dt``), as in the figure code.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np

from .izhikevich import IzhikevichParams

__all__ = ["Behaviour", "BEHAVIOURS", "behaviour", "pulses"]


@dataclass(frozen=True)
class Behaviour:
    """One panel of the published figure."""

    letter: str
    name: str
    params: IzhikevichParams
    v0: float
    u0: float
    duration_ms: float
    stimulus: Callable[[np.ndarray], np.ndarray]   # t (ms) -> I (mV/ms), vectorized
    figure_tau_ms: float
    current_range: tuple[float, float]             # min and max of the stimulus
    note: str = ""

    @property
    def key(self) -> str:
        return f"{self.letter} {self.name}"

    def current(self, t_ms):
        """The stimulus at time(s) ``t_ms`` (float64 array)."""
        return np.asarray(self.stimulus(np.asarray(t_ms, dtype=np.float64)), dtype=np.float64)

    def schedule(self, dt_ms: float) -> np.ndarray:
        """Per-update currents ``I[k] = stimulus(k dt)`` for ``round(duration / dt)`` updates."""
        n = int(round(self.duration_ms / dt_ms))
        return self.current(np.arange(n) * dt_ms)


def _p(letter, name, a, b, c, d, **kw) -> IzhikevichParams:
    return IzhikevichParams(a, b, c, d, name=f"{letter} {name}", **kw)


def _where(cond, x, y):
    return np.where(cond, x, y).astype(np.float64)


def pulses(t, starts, width, amp, base=0.0):
    """``base`` plus ``amp`` during each pulse of ``width`` ms starting at ``starts`` (ms)."""
    on = np.zeros(np.shape(t), dtype=bool)
    for s in starts:
        on |= (t > s) & (t < s + width)
    return _where(on, amp, base)


_CLASS1 = {"A": 0.04, "B": 4.1, "C": 108.0}


def _table() -> list[Behaviour]:
    B = []
    # (A) tonic spiking: step to 14 at T1 = 10 ms
    B.append(Behaviour("A", "tonic spiking", _p("A", "tonic spiking", 0.02, 0.2, -65, 6),
                       -70, 0.2 * -70, 100, lambda t: _where(t > 10, 14.0, 0.0), 0.25, (0, 14)))
    B.append(Behaviour("B", "phasic spiking", _p("B", "phasic spiking", 0.02, 0.25, -65, 6),
                       -64, 0.25 * -64, 200, lambda t: _where(t > 20, 0.5, 0.0), 0.25, (0, 0.5)))
    B.append(Behaviour("C", "tonic bursting", _p("C", "tonic bursting", 0.02, 0.2, -50, 2),
                       -70, 0.2 * -70, 220, lambda t: _where(t > 22, 15.0, 0.0), 0.25, (0, 15)))
    B.append(Behaviour("D", "phasic bursting",
                       _p("D", "phasic bursting", 0.02, 0.25, -55, 0.05),
                       -64, 0.25 * -64, 200, lambda t: _where(t > 20, 0.6, 0.0), 0.2, (0, 0.6)))
    B.append(Behaviour("E", "mixed mode", _p("E", "mixed mode", 0.02, 0.2, -55, 4),
                       -70, 0.2 * -70, 160, lambda t: _where(t > 16, 10.0, 0.0), 0.25, (0, 10)))
    B.append(Behaviour("F", "spike frequency adaptation",
                       _p("F", "spike frequency adaptation", 0.01, 0.2, -65, 8),
                       -70, 0.2 * -70, 85, lambda t: _where(t > 8.5, 30.0, 0.0), 0.25, (0, 30)))
    B.append(Behaviour("G", "class 1 excitability",
                       _p("G", "class 1 excitability", 0.02, -0.1, -55, 6, **_CLASS1),
                       -60, -0.1 * -60, 300,
                       lambda t: _where(t > 30, 0.075 * (t - 30), 0.0), 0.25, (0, 0.075 * 270),
                       "v-equation 0.04 v^2 + 4.1 v + 108 (figure code)"))
    B.append(Behaviour("H", "class 2 excitability",
                       _p("H", "class 2 excitability", 0.2, 0.26, -65, 0),
                       -64, 0.26 * -64, 300,
                       lambda t: _where(t > 30, -0.5 + 0.015 * (t - 30), -0.5), 0.25,
                       (-0.5, -0.5 + 0.015 * 270)))
    B.append(Behaviour("I", "spike latency", _p("I", "spike latency", 0.02, 0.2, -65, 6),
                       -70, 0.2 * -70, 100, lambda t: pulses(t, [10], 3, 7.04), 0.2, (0, 7.04)))
    B.append(Behaviour("J", "subthreshold oscillations",
                       _p("J", "subthreshold oscillations", 0.05, 0.26, -60, 0),
                       -62, 0.26 * -62, 200, lambda t: pulses(t, [20], 5, 2.0), 0.25, (0, 2)))
    B.append(Behaviour("K", "resonator", _p("K", "resonator", 0.1, 0.26, -60, -1),
                       -62, 0.26 * -62, 400,
                       lambda t: pulses(t, [40, 60, 280, 320], 4, 0.65), 0.25, (0, 0.65),
                       "pulse pairs 20 ms apart (at 40 ms) and 40 ms apart (at 280 ms)"))
    B.append(Behaviour("L", "integrator",
                       _p("L", "integrator", 0.02, -0.1, -55, 6, **_CLASS1),
                       -60, -0.1 * -60, 100,
                       lambda t: pulses(t, [100 / 11, 100 / 11 + 5, 70, 80], 2, 9.0), 0.25,
                       (0, 9), "v-equation 0.04 v^2 + 4.1 v + 108 (figure code); pulse pairs "
                       "5 ms apart (at 9.09 ms) and 10 ms apart (at 70 ms)"))
    B.append(Behaviour("M", "rebound spike", _p("M", "rebound spike", 0.03, 0.25, -60, 4),
                       -64, 0.25 * -64, 200, lambda t: pulses(t, [20], 5, -15.0), 0.2, (-15, 0)))
    B.append(Behaviour("N", "rebound burst", _p("N", "rebound burst", 0.03, 0.25, -52, 0),
                       -64, 0.25 * -64, 200, lambda t: pulses(t, [20], 5, -15.0), 0.2, (-15, 0)))

    def thresh_var(t):
        exc = ((t > 10) & (t < 15)) | ((t > 80) & (t < 85))
        inh = (t > 70) & (t < 75)
        return _where(exc, 1.0, _where(inh, -6.0, 0.0))
    B.append(Behaviour("O", "threshold variability",
                       _p("O", "threshold variability", 0.03, 0.25, -60, 4),
                       -64, 0.25 * -64, 100, thresh_var, 0.25, (-6, 1),
                       "excitatory pulses at 10 ms (alone) and 80 ms (after an inhibitory pulse "
                       "at 70 ms)"))
    B.append(Behaviour("P", "bistability", _p("P", "bistability", 0.1, 0.26, -60, 0),
                       -61, 0.26 * -61, 300,
                       lambda t: pulses(t, [300 / 8, 216], 5, 1.24, base=0.24), 0.25,
                       (0.24, 1.24), "a = 0.1, b = 0.26 (figure code; the table lists a = 1, "
                       "b = 1.5); pulses at 37.5 ms (on) and 216 ms (off)"))
    B.append(Behaviour("Q", "depolarizing after-potential",
                       _p("Q", "depolarizing after-potential", 1.0, 0.2, -60, -21),
                       -70, 0.2 * -70, 50, lambda t: _where(np.abs(t - 10) < 1, 20.0, 0.0), 0.1,
                       (0, 20)))

    def accommodation(t):
        return np.select([t < 200, t < 300, t < 312.5], [t / 25, 0.0 * t, (t - 300) / 12.5 * 4],
                         0.0).astype(np.float64)
    B.append(Behaviour("R", "accommodation",
                       _p("R", "accommodation", 0.02, 1.0, -55, 4, u_leak=0.0, v_u=-65.0),
                       -65, -16, 400, accommodation, 0.5, (0, 8),
                       "u-equation du/dt = a b (v + 65) and u0 = -16 (figure code); slow ramp "
                       "to 8 over 200 ms, then a fast ramp to 4 over 12.5 ms at 300 ms"))
    B.append(Behaviour("S", "inhibition-induced spiking",
                       _p("S", "inhibition-induced spiking", -0.02, -1.0, -60, 8),
                       -63.8, 63.8, 350, lambda t: _where((t < 50) | (t > 250), 80.0, 75.0),
                       0.5, (75, 80), "a < 0, b = -1; bias 80, inhibitory step to 75 from 50 "
                       "to 250 ms"))
    B.append(Behaviour("T", "inhibition-induced bursting",
                       _p("T", "inhibition-induced bursting", -0.026, -1.0, -45, -2),
                       -63.8, 63.8, 350, lambda t: _where((t < 50) | (t > 250), 80.0, 75.0),
                       0.5, (75, 80), "a < 0, b = -1; same stimulus as (S)"))
    return B


#: The twenty behaviours keyed by letter ("A" .. "T").
BEHAVIOURS: Mapping[str, Behaviour] = {b.letter: b for b in _table()}


def behaviour(key: str) -> Behaviour:
    """A behaviour by letter (``"Q"``) or name (``"depolarizing after-potential"``)."""
    k = key.strip()
    if k.upper() in BEHAVIOURS:
        return BEHAVIOURS[k.upper()]
    for b in BEHAVIOURS.values():
        if b.name == k.lower():
            return b
    raise ValueError(f"unknown behaviour {key!r}; known: "
                     + ", ".join(f"{b.letter} ({b.name})" for b in BEHAVIOURS.values()))
