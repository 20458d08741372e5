"""The batteries a sweep simulates (see :mod:`cuneate.sim.sweep`).

A :class:`Battery` is a population of independent Izhikevich neurons, each with a parameter set,
an initial state and a current of time:

* ``yardstick`` (RS, IB, CH, FS x I in {4, 10, 30, 100}: the README's 16 trains), ``wide`` (the
  same presets x 15 currents 3.5..100: 60 trains), ``long`` (6 presets x 8 currents 0..40);
* ``behaviours``: Izhikevich's published panels but (T), each with its own parameters
  (class-1 v-equation, accommodation's u-equation, negative ``a``), initial state and stimulus
  (steps, pulses, ramps), held at its last value after the panel;
* ``scene``, ``scene:NAME`` (an example scene) or ``scene:PATH`` (a scene file): the scene's
  driven Izhikevich neurons (every trial, population and grating) with the currents its front
  end computes from its synthesized traces - per sample, held for the sample period (the
  driver's latency, a pure shift, is left out so every engine sees the same signal).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["BATTERIES", "Battery", "battery", "scene_battery", "simulate_float"]

PRESETS = ("RS", "IB", "CH", "FS")
BATTERIES = {
    "yardstick": [(p, i) for p in PRESETS for i in (4.0, 10.0, 30.0, 100.0)],
    "wide": [(p, float(i)) for p in PRESETS
             for i in np.round(np.geomspace(3.5, 100.0, 15), 2)],
    "long": [(p, float(i)) for p in ("RS", "IB", "CH", "FS", "LTS", "RZ")
             for i in (0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0)],
    # Izhikevich's published panels (each with its own parameters, initial state and stimulus)
    "behaviours": "the 20 published behaviours but (T), which diverges at every converged step",
}


@dataclass(frozen=True)
class Battery:
    """The trains a sweep simulates: per train a parameter set (preset name or
    :class:`~cuneate.golden.izhikevich.IzhikevichParams`), an initial state and a current -
    constant (``constant``), a stimulus of time (``stimuli``, the published behaviours, each
    held at its last value after the panel's duration) or per-sample currents (``samples``,
    ``(n_samples, n)`` mV/ms, each held for ``sample_ms``; a scene's front end).
    ``duration_ms``: the battery's natural length (a scene's), if it has one;
    ``current_range`` / ``current_format``: the core's accepted currents, if not its defaults
    (a scene's hardware current format)."""

    name: str
    params: tuple
    labels: tuple
    constant: tuple | None = None
    stimuli: tuple | None = None
    v0: tuple | None = None
    u0: tuple | None = None
    current_range: tuple | None = None
    samples: np.ndarray | None = None
    sample_ms: float | None = None
    duration_ms: float | None = None
    current_format: object = None

    @property
    def n(self) -> int:
        return len(self.params)

    def currents(self, dt_ms: float, n_steps: int) -> np.ndarray:
        """Per-update currents ``(n_steps, n)`` read at ``t = k dt`` (constants as a zero-copy
        broadcast)."""
        if self.constant is not None:
            return np.broadcast_to(np.asarray(self.constant, dtype=np.float64),
                                   (n_steps, self.n))
        t = np.arange(n_steps) * dt_ms
        if self.samples is not None:
            # sample j holds over [j T, (j + 1) T); the last one is held after the scene
            j = np.floor(t / self.sample_ms + 1e-9).astype(np.int64)
            return self.samples[np.minimum(j, self.samples.shape[0] - 1)]
        return np.stack([np.broadcast_to(b.current(np.minimum(t, b.duration_ms)), (n_steps,))
                         for b in self.stimuli], axis=1)


def battery(name: str) -> Battery:
    """The battery called ``name``: one of :data:`BATTERIES`, or ``scene`` (the default
    scene), ``scene:NAME`` (an example scene) or ``scene:PATH`` (a scene file)."""
    if name == "scene" or name.startswith("scene:"):
        return scene_battery(name.partition(":")[2] or None)
    if name not in BATTERIES:
        raise ValueError(f"unknown battery {name!r}; known: {', '.join(BATTERIES)}, scene, "
                         f"scene:NAME (an example) or scene:PATH (a scene file)")
    if name == "behaviours":
        from ..golden.behaviours import BEHAVIOURS
        bs = [b for k, b in BEHAVIOURS.items() if k != "T"]
        return Battery(name, tuple(b.params for b in bs), tuple(b.key for b in bs),
                       stimuli=tuple(bs), v0=tuple(b.v0 for b in bs),
                       u0=tuple(b.u0 for b in bs),
                       current_range=(min(b.current_range[0] for b in bs),
                                      max(b.current_range[1] for b in bs)))
    b = BATTERIES[name]
    return Battery(name, tuple(p for p, _ in b), tuple(f"{p} I={i:g}" for p, i in b),
                   constant=tuple(float(i) for _, i in b))


@functools.lru_cache(maxsize=4)
def scene_battery(which: str | None = None) -> Battery:
    """A scene's driven Izhikevich neurons (every trial, population and grating; labels
    ``trial/population/grating``) with the float currents its front end computes from its
    synthesized traces, per sensor sample. ``which``: ``None`` (the default scene), an example
    name or a scene file. Refused (``ValueError``, one line): a scene whose neurons are not
    Izhikevich neurons driven by currents (the taxel skin, the ridge network)."""
    from .scene_run import build_izhikevich, build_neurons, front_end, synthesize
    from .scenes import default_scene, example_names, example_path, load_scene
    if which is None:
        scene = default_scene()
    elif example_path(which) is not None:
        scene = load_scene(example_path(which))
    elif Path(which).is_file():
        scene = load_scene(which)
    else:
        raise ValueError(f"scene {which!r} is neither an example "
                         f"({', '.join(Path(n).stem for n in example_names())})"
                         f" nor a scene file")
    kind = scene["stimulus"]["kind"]
    if kind in ("press", "ridges") or any(p["model"] != "izhikevich" for p in scene.populations):
        raise ValueError(f"scene {which or 'default'!r} ({kind}) does not drive independent "
                         f"Izhikevich neurons with currents; a sweep battery needs one that does")
    _, _, traces, infos, _ = synthesize(scene)
    nn = build_neurons(scene, len(traces))
    cfg, _ = build_izhikevich(scene, nn)
    _, cur, _ = front_end(scene, nn, traces, infos, cfg)
    fs = scene["sensor"]["sample_rate_hz"]
    return Battery(f"scene:{which}" if which else "scene", tuple(nn.preset),
                   tuple(f"{t}/{p}/{g}" for t, p, g in zip(nn.trial, nn.population, nn.grating)),
                   samples=cur, sample_ms=1000.0 / fs, current_format=cfg.I,
                   current_range=cfg.current_range, duration_ms=cur.shape[0] * 1000.0 / fs)


def simulate_float(bat: Battery, dt_ms: float, n_steps: int, scheme: str,
                    dtype=np.float64) -> list[np.ndarray]:
    from ..golden import izhikevich as giz
    r = giz.simulate(list(bat.params), bat.currents(dt_ms, n_steps), n_neurons=bat.n,
                     n_steps=n_steps, dt_ms=dt_ms, scheme=scheme, dtype=dtype,
                     v0=None if bat.v0 is None else np.asarray(bat.v0),
                     u0=None if bat.u0 is None else np.asarray(bat.u0))
    return [np.asarray(s) for s in r.spikes_ms]


