"""The brief's ridge-angle experiment (section 5): afferent timing -> cuneate spatial code.

Two sensors, one above the other (``spacing_mm`` apart), touch a surface that slides
horizontally at ``speed_mm_per_s``. A ridge at angle ``theta`` from the vertical (the direction
orthogonal to sliding) crosses the lower sensor ``spacing tan(theta) / speed`` later than the
upper one (earlier for negative angles). Each crossing indents a sensor for about
``ridge_width_mm / speed``: a Gaussian bump of force ``force_N``. Per sensor an SA afferent
(current ``sa_gain x indentation``) and an FA afferent (``fa_gain x`` its positive rate of
change, as in :func:`cuneate.golden.encoders.fa_current`) are Izhikevich RS neurons; their
spikes feed three cuneate neurons (the coincidence detector) that differ only in their
conduction delays: neuron ``j`` delays the upper sensor's afferents by ``max(0, L_j)`` and the
lower's by ``max(0, -L_j)``, ``L_j`` the crossing lag of angle ``j``, so their PSPs superimpose
only for a ridge near that angle. The set of active cuneate neurons is decoded through a lookup
table built on training trials (every other trial of each angle; each pattern -> its most
frequent angle) and tested on the others.

Trials vary the speed (``spread_speed``, relative s.d.), the crossing times of each sensor
(``jitter_ms``) and the force (``spread_force``). Trials run one after another in one long run
(``trial_ms`` each, the last ``rest_ms`` of it without contact so every state settles), so one
engine run serves all trials. The afferents run on the golden model for the golden engine and on
the Izhikevich core's twin for the others (the fixed-point afferent layer); the detector runs on
the engine.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ..golden import izhikevich as giz
from ..hdl.cuneate import CoincidenceConfig
from ..hdl.izhikevich import IzhikevichConfig, IzhikevichTwin
from .cuneate_engines import run_coincidence

__all__ = ["RidgeSpec", "RidgeResult", "ridge_experiment", "format_ridge", "detector_config",
           "afferent_currents", "afferent_spikes", "decode"]


@dataclass
class RidgeSpec:
    angles_deg: tuple = (-45.0, 0.0, 45.0)
    speed_mm_per_s: float = 20.0
    force_N: float = 0.5
    spacing_mm: float = 0.25
    ridge_width_mm: float = 0.2
    sa_gain: float = 25.0            # mV/ms per N of indentation force
    fa_gain: float = 0.4             # mV/ms per N/s of force rate
    weight: float = 4.5              # J w per afferent (mV/ms): one sensor alone stays below
    #                                  threshold, both sensors' PSPs together cross it
    trial_ms: float = 120.0
    onset_ms: float = 30.0
    trials_per_angle: int = 10
    spread_speed: float = 0.05
    spread_force: float = 0.1
    jitter_ms: float = 0.3
    seed: int = 1
    update_hz: float = 16e3
    weight_fa: float | None = None   # J w of the FA afferents (default: ``weight``)
    delays_ticks: list | None = None  # (targets, 4) delays; default: tuned to the angles


@dataclass
class RidgeResult:
    engine: str
    angles: list
    trial_angle: list
    patterns: list                   # per trial: tuple of active cuneate neurons
    counts: np.ndarray               # (trials, 3) spikes per cuneate neuron
    table: dict = field(default_factory=dict)
    accuracy: float = 0.0
    wall_s: float = 0.0

    def to_dict(self) -> dict:
        return {"engine": self.engine, "angles": self.angles, "accuracy": self.accuracy,
                "table": {str(list(k)): v for k, v in self.table.items()},
                "patterns": [list(p) for p in self.patterns],
                "trial_angle": self.trial_angle, "counts": self.counts.tolist(),
                "wall_s": self.wall_s}


def _lags_ms(spec: RidgeSpec, speed, angle_deg):
    return spec.spacing_mm * math.tan(math.radians(angle_deg)) / speed * 1000.0


def detector_config(spec: RidgeSpec) -> CoincidenceConfig:
    """Three cuneate neurons, each tuned to one angle's crossing lag; sources (SA top, FA top,
    SA bottom, FA bottom)."""
    dt = 1000.0 / spec.update_hz
    delays = spec.delays_ticks
    if delays is None:
        delays = []
        for a in spec.angles_deg:
            lag = _lags_ms(spec, spec.speed_mm_per_s, a)
            top, bot = int(round(max(0.0, lag) / dt)), int(round(max(0.0, -lag) / dt))
            delays.append([top, top, bot, bot])
    wf = spec.weight if spec.weight_fa is None else spec.weight_fa
    return CoincidenceConfig(n_sources=4, n_targets=len(delays), delays_ticks=delays,
                             weights=np.tile([spec.weight, wf, spec.weight, wf],
                                             (len(delays), 1)),
                             update_hz=spec.update_hz)


def afferent_currents(spec: RidgeSpec):
    """Currents (n_ticks, 4) of all trials in sequence and the angle of each trial."""
    rng = np.random.default_rng(spec.seed)
    dt = 1000.0 / spec.update_hz
    per = int(round(spec.trial_ms / dt))
    angles = [a for a in spec.angles_deg for _ in range(spec.trials_per_angle)]
    order = rng.permutation(len(angles))
    angles = [angles[i] for i in order]
    cur = np.zeros((per * len(angles), 4))
    t = np.arange(per) * dt
    for k, a in enumerate(angles):
        speed = spec.speed_mm_per_s * (1 + spec.spread_speed * rng.standard_normal())
        force = spec.force_N * (1 + spec.spread_force * rng.standard_normal())
        sigma = spec.ridge_width_mm / speed * 1000.0 / 2
        lag = _lags_ms(spec, speed, a)
        t_top = spec.onset_ms + max(0.0, -lag) + spec.jitter_ms * rng.standard_normal()
        t_bot = spec.onset_ms + max(0.0, lag) + spec.jitter_ms * rng.standard_normal()
        for j, tc in enumerate((t_top, t_bot)):
            f = force * np.exp(-0.5 * ((t - tc) / sigma) ** 2)
            df = np.diff(f, prepend=f[0]) / (dt / 1000.0)        # N/s
            cur[k * per:(k + 1) * per, 2 * j] = spec.sa_gain * f
            cur[k * per:(k + 1) * per, 2 * j + 1] = spec.fa_gain * np.maximum(df, 0.0)
    return cur, angles, per


def afferent_spikes(spec: RidgeSpec, currents, fixed: bool) -> list[np.ndarray]:
    """Input ticks per afferent: golden RS (float64 Euler) or the core's twin."""
    dt = 1000.0 / spec.update_hz
    n = currents.shape[0]
    if not fixed:
        r = giz.simulate("RS", currents, n_steps=n, n_neurons=4, dt_ms=dt)
        return [np.round(np.asarray(s) / dt).astype(np.int64) for s in r.spikes_ms]
    cfg = IzhikevichConfig(n_neurons=8, clock_hz=spec.update_hz * 8, update_hz=spec.update_hz,
                           tick_source="external")
    twin = IzhikevichTwin(cfg)
    hits = [[] for _ in range(4)]
    for k in range(n):
        twin.set_currents(np.concatenate([currents[k], np.zeros(4)]))
        for i in np.flatnonzero(twin.sweep()[:4]):
            hits[i].append(k + 1)                    # spike of update k is stamped with k + 1
    return [np.asarray(h, dtype=np.int64) for h in hits]


def decode(patterns, angles, train_mask) -> tuple[dict, float]:
    """Lookup table pattern -> most frequent angle on the training trials; accuracy on the
    others (an unseen pattern counts as wrong)."""
    votes: dict = {}
    for p, a, tr in zip(patterns, angles, train_mask):
        if tr:
            votes.setdefault(p, Counter())[a] += 1
    table = {p: c.most_common(1)[0][0] for p, c in votes.items()}
    test = [(p, a) for p, a, tr in zip(patterns, angles, train_mask) if not tr]
    acc = float(np.mean([table.get(p) == a for p, a in test])) if test else 0.0
    return table, acc


def ridge_experiment(engine: str = "fixed", spec: RidgeSpec | None = None,
                     build_dir=None) -> RidgeResult:
    """Run the ridge experiment on ``engine`` (see the module docstring)."""
    spec = spec or RidgeSpec()
    cfg = detector_config(spec)
    cur, angles, per = afferent_currents(spec)
    ins = afferent_spikes(spec, cur, fixed=engine != "golden")
    n = cur.shape[0]
    run = run_coincidence(engine, cfg, ins, n, build_dir=build_dir)
    counts = np.zeros((len(angles), cfg.n_targets), dtype=np.int64)
    dt = cfg.dt_ms
    for t, sp in enumerate(run.spikes_ms):
        k = (np.asarray(sp) / dt - 1).round().astype(np.int64) // per
        np.add.at(counts[:, t], k[k < len(angles)], 1)
    patterns = [tuple(int(j) for j in np.flatnonzero(c)) for c in counts]
    # training: every other trial of each angle (stratified), tested on the rest
    seen = Counter()
    train = []
    for a in angles:
        train.append(seen[a] % 2 == 0)
        seen[a] += 1
    table, acc = decode(patterns, angles, train)
    return RidgeResult(engine, list(spec.angles_deg), angles, patterns, counts, table, acc,
                       run.wall_s)


def format_ridge(res: RidgeResult) -> str:
    lines = [f"ridge angle on {res.engine}: {len(res.trial_angle)} trials, decode accuracy "
             f"{100 * res.accuracy:.1f} % (lookup table from every other trial of each angle, "
             f"tested on the rest)"]
    for a in res.angles:
        pats = Counter(p for p, x in zip(res.patterns, res.trial_angle) if x == a)
        lines.append(f"  {a:+6.1f} deg: active cuneate neurons "
                     + ", ".join(f"{list(p) or '[]'} x{n}" for p, n in pats.most_common()))
    lines.append("  table: " + "; ".join(f"{list(p) or '[]'} -> {a:+g} deg"
                                         for p, a in sorted(res.table.items())))
    return "\n".join(lines)
