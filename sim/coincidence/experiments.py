"""The brief's ridge-angle experiment (section 5): afferent timing -> cuneate spatial code.

Two sensors, one above the other (``spacing_mm`` apart), touch a surface that slides
horizontally at ``speed_mm_per_s``. A ridge at angle ``theta`` from the vertical (the direction
orthogonal to sliding) crosses the lower sensor ``spacing tan(theta) / speed`` later than the
upper one (earlier for negative angles). Each crossing indents a sensor for about
``ridge_width_mm / speed``: a Gaussian bump of force ``force_N``. Per sensor an SA afferent
(:func:`cuneate.golden.encoders.sa_current`: ``sa_gain x force``) and an FA afferent
(:func:`cuneate.golden.encoders.fa_current`: ``fa_gain x`` the force's rate of change in N/ms,
rectified to increases) are Izhikevich RS neurons; their
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

RTL engines are slow per trial: :func:`ridge_comparison` runs golden and fixed on every trial
and the HDL engines on the first few trials of the same sequence, decoded with the table the
fixed engine learnt; golden and fixed must decode every trial the same.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ...golden import encoders
from ...golden import izhikevich as giz
from ...golden.budget import BASE_BYTES, array_bytes
from ...hdl.coincidence import CoincidenceConfig
from ...hdl.izhikevich import IzhikevichConfig, IzhikevichTwin
from ...hdl.izhikevich.config import min_neurons
from ...hdl.network import NetworkConfig
from ..engines.registry import ENGINES, block_engines, estimate_seconds
from ..network.engines import run_network
from .engines import run_coincidence

__all__ = ["RidgeSpec", "RidgeResult", "ridge_experiment", "ridge_comparison", "format_ridge",
           "format_comparison", "detector_config", "network_config", "afferent_currents",
           "afferent_spikes", "decode", "ridge_problem", "ridge_estimate"]


@dataclass
class RidgeSpec:
    angles_deg: tuple = (-45.0, 0.0, 45.0)
    speed_mm_per_s: float = 20.0
    force_N: float = 0.5
    spacing_mm: float = 0.25
    ridge_width_mm: float = 0.2
    sa_gain: float = 25.0            # mV/ms per N of indentation force
    fa_gain: float = 400.0           # mV/ms per N/ms of force rate
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
    delay_scale: float = 1.0         # 0: the three neurons get identical (zero) delays
    weight_fa: float | None = None   # J w of the FA afferents (default: ``weight``)
    delays_ticks: list | None = None  # (neurons, 4) delays given by hand (a scene's)


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
    decoded: list = field(default_factory=list)   # per trial: the table's angle (None: unseen)
    tested: list = field(default_factory=list)    # per trial: counted in the accuracy
    #: (trials, 4) spikes per afferent (SA top, FA top, SA bottom, FA bottom)
    afferent_counts: np.ndarray | None = None
    #: the engine's counters (on ``board``: the link's frames, bytes, losses and cycles)
    counters: dict = field(default_factory=dict)
    #: the whole run's spike ticks (update ``k`` at tick ``k + 1``; trials in sequence of
    #: ``ticks_per_trial``): the 4 afferents' and the cuneate neurons'
    afferent_ticks: list = field(default_factory=list)
    cuneate_ticks: list = field(default_factory=list)
    ticks_per_trial: int = 0

    def to_dict(self) -> dict:
        return {"engine": self.engine, "angles": self.angles, "accuracy": self.accuracy,
                "decoded": self.decoded, "tested": self.tested,
                "table": {str(list(k)): v for k, v in self.table.items()},
                "patterns": [list(p) for p in self.patterns],
                "trial_angle": self.trial_angle, "counts": self.counts.tolist(),
                "afferent_counts": None if self.afferent_counts is None
                else self.afferent_counts.tolist(), "wall_s": self.wall_s,
                "counters": self.counters}


def _lags_ms(spec: RidgeSpec, speed, angle_deg):
    return spec.spacing_mm * math.tan(math.radians(angle_deg)) / speed * 1000.0


def ridge_problem(spec: RidgeSpec) -> tuple[str, str] | None:
    """``(field, reason)`` when the experiment cannot work with ``spec`` (checked before
    anything runs): the slowest crossing (speed less three spreads) must put its longest lag
    within the detector's delay line and its crossing and indentation within the trial; else
    ``None``."""
    dt = 1000.0 / spec.update_hz
    slowest = spec.speed_mm_per_s * (1.0 - 3.0 * spec.spread_speed)
    if not slowest > 0:
        return "spread_speed", (f"a speed spread of {spec.spread_speed:g} (relative s.d.) "
                                f"reaches standstill within three spreads; keep it below 1/3")
    max_delay_ms = (CoincidenceConfig.max_delay_ticks - 1) * dt
    angle = max(abs(a) for a in spec.angles_deg)
    lag = abs(_lags_ms(spec, spec.speed_mm_per_s, angle))
    if spec.delays_ticks is None and lag > max_delay_ms:
        need = spec.spacing_mm * math.tan(math.radians(angle)) / max_delay_ms * 1000.0
        return "speed_mm_per_s", (f"at {spec.speed_mm_per_s:g} mm/s the {angle:g} degree "
                                  f"ridges cross the second sensor {lag:.3g} ms after the first, "
                                  f"beyond the detector's {max_delay_ms:g} ms delay line; the "
                                  f"speed must be at least {need:.3g} mm/s")
    lag = abs(_lags_ms(spec, slowest, angle))
    press = spec.ridge_width_mm / slowest * 1000.0
    if spec.onset_ms + lag + 3 * spec.jitter_ms + press >= spec.trial_ms:
        return "speed_mm_per_s", (f"at {spec.speed_mm_per_s:g} mm/s a crossing ({lag:.3g} ms "
                                  f"lag, {press:.3g} ms indentation after {spec.onset_ms:g} ms) "
                                  f"does not end within the {spec.trial_ms:g} ms trial")
    return None


def ridge_estimate(spec: RidgeSpec, engines) -> dict:
    """Memory (bytes) and time (s) of the experiment on ``engines`` before it runs: every trial
    of every angle in one run, the afferents' currents and spikes per tick, and the afferent
    core's and the detector's updates (or cycles) at the engine registry's speeds."""

    def block_of(e):
        """The detector alone, or the on-chip network for the engines that run only that."""
        return "coincidence" if e in block_engines("coincidence") else "network"
    trials = spec.trials_per_angle * len(spec.angles_deg)
    ticks = trials * spec.trial_ms * spec.update_hz / 1000.0
    m = len(spec.delays_ticks) if spec.delays_ticks is not None else len(spec.angles_deg)
    engines = list(engines)
    nbytes = BASE_BYTES + (3 + len(engines)) * array_bytes(ticks, 4 + m)
    seconds = estimate_seconds("izhikevich", "fixed", ticks * 8) * len(engines)
    seconds += sum(estimate_seconds(block_of(e), e, ticks * (m * 8 if ENGINES[e].hdl else m))
                   for e in engines)
    return {"bytes": nbytes, "seconds": seconds,
            "what": f"{trials} trials of {spec.trial_ms:g} ms ({ticks:.3g} ticks) on "
                    f"{', '.join(engines)}"}


def detector_config(spec: RidgeSpec) -> CoincidenceConfig:
    """Three cuneate neurons, each tuned to one angle's crossing lag; sources (SA top, FA top,
    SA bottom, FA bottom)."""
    dt = 1000.0 / spec.update_hz
    delays = spec.delays_ticks
    if delays is None:
        delays = []
        for a in spec.angles_deg:
            lag = spec.delay_scale * _lags_ms(spec, spec.speed_mm_per_s, a)
            top, bot = int(round(max(0.0, lag) / dt)), int(round(max(0.0, -lag) / dt))
            delays.append([top, top, bot, bot])
    wf = spec.weight if spec.weight_fa is None else spec.weight_fa
    return CoincidenceConfig(n_sources=4, n_targets=len(delays), delays_ticks=delays,
                             weights=np.tile([spec.weight, wf, spec.weight, wf],
                                             (len(delays), 1)),
                             update_hz=spec.update_hz)


def network_config(spec: RidgeSpec):
    """The on-chip network of the experiment: 6 afferents (the core's minimum; the fifth and
    sixth idle),
    sources 0 .. 3 = (SA top, FA top, SA bottom, FA bottom), the detector of
    :func:`detector_config`."""
    det = detector_config(spec).to_kwargs()
    for k in ("clock_hz", "update_hz", "tick_source"):
        det.pop(k)
    return NetworkConfig(n_afferents=min_neurons(), detector=det, clock_hz=spec.update_hz * 64,
                         update_hz=spec.update_hz, tick_source="external")


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
            cur[k * per:(k + 1) * per, 2 * j] = encoders.sa_current(f, gain_K=spec.sa_gain)
            cur[k * per:(k + 1) * per, 2 * j + 1] = encoders.fa_current(
                f, dt, gain=spec.fa_gain, tau_ms=1.0, rectify="positive")
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
                     build_dir=None, table: dict | None = None,
                     trials=None, on_chip: bool = False) -> RidgeResult:
    """Run the ridge experiment on ``engine`` (see the module docstring).

    Without ``table`` the lookup table is learnt from every other trial of each angle and
    tested on the rest; with ``table`` (learnt on another engine) every trial is tested.
    ``trials`` (indices into the trial sequence) runs only those trials, one after another.
    ``on_chip`` runs afferents and detector as the on-chip network
    (:mod:`cuneate.hdl.network`, :func:`network_config`): the afferent currents are written by
    the host before each tick and the afferent spikes reach the detector over the chip's link.
    Engines that run the network but not the detector alone (``board``: the network behind the
    board's UART link) always run on chip.
    """
    spec = spec or RidgeSpec()
    cfg = detector_config(spec)
    cur, angles, per = afferent_currents(spec)
    if trials is not None:
        idx = [int(i) for i in trials]
        if not idx or any(not 0 <= i < len(angles) for i in idx):
            raise ValueError(f"trials must be indices in 0 .. {len(angles) - 1}, got {trials}")
        angles = [angles[i] for i in idx]
        cur = np.concatenate([cur[i * per:(i + 1) * per] for i in idx])
    n = cur.shape[0]
    dt = cfg.dt_ms
    on_chip = on_chip or engine not in block_engines("coincidence")
    if on_chip:
        ncfg = network_config(spec)
        pad = np.zeros((n, ncfg.n_afferents))
        pad[:, :4] = cur
        run = run_network(engine, ncfg, pad, build_dir=build_dir)
        aff_ticks = [giz.spike_ticks(sp, dt) + 1 for sp in run.population("afferent")[:4]]
        run.spikes_ms = run.population("cuneate")
        engine = f"{engine} (on-chip network)"
    else:
        aff_ticks = afferent_spikes(spec, cur, fixed=engine != "golden")
        run = run_coincidence(engine, cfg, aff_ticks, n, build_dir=build_dir)

    def per_trial(ticks_of, width):
        """Spikes per trial of each train (tick ``k + 1`` of update ``k``)."""
        out = np.zeros((len(angles), width), dtype=np.int64)
        for j, ks in enumerate(ticks_of):
            k = (np.asarray(ks, dtype=np.int64) - 1) // per
            np.add.at(out[:, j], k[k < len(angles)], 1)
        return out
    cn_ticks = [giz.spike_ticks(sp, dt) + 1 for sp in run.spikes_ms]
    counts = per_trial(cn_ticks, cfg.n_targets)
    aff_counts = per_trial(aff_ticks, 4)
    patterns = [tuple(int(j) for j in np.flatnonzero(c)) for c in counts]
    if table is None:
        # training: every other trial of each angle (stratified), tested on the rest
        seen = Counter()
        train = []
        for a in angles:
            train.append(seen[a] % 2 == 0)
            seen[a] += 1
        table, acc = decode(patterns, angles, train)
    else:
        train = [False] * len(angles)
        acc = float(np.mean([table.get(p) == a for p, a in zip(patterns, angles)]))
    decoded = [table.get(p) for p in patterns]
    return RidgeResult(engine, list(spec.angles_deg), angles, patterns, counts, table, acc,
                       run.wall_s, decoded, [not t for t in train], aff_counts,
                       dict(getattr(run, "counters", None) or {}),
                       [np.asarray(k, dtype=np.int64) for k in aff_ticks], cn_ticks, per)


def ridge_comparison(spec: RidgeSpec | None = None, hdl_engines=("verilator",),
                     hdl_trials_per_angle: int = 1, build_dir=None,
                     on_chip: bool = False) -> dict:
    """Golden and fixed on every trial; each HDL engine on the first ``hdl_trials_per_angle``
    trials of each angle, decoded with the table the fixed engine learnt, and compared with
    the fixed engine run on the same trials. Returns ``{"results": [...],
    "golden_fixed_same": bool, "hdl_fixed_same": {engine: bool}, "hdl_trials": [...]}``
    (same = identical active neurons and decoded angle on every trial). With ``on_chip`` the
    HDL engines run the on-chip afferent -> cuneate network instead of the detector alone."""
    spec = spec or RidgeSpec()
    g = ridge_experiment("golden", spec)
    f = ridge_experiment("fixed", spec)
    seen: Counter = Counter()
    pick = []
    for i, a in enumerate(f.trial_angle):
        if seen[a] < hdl_trials_per_angle:
            pick.append(i)
        seen[a] += 1
    out = {"results": [g, f], "golden_fixed_same": g.decoded == f.decoded and
           g.patterns == f.patterns, "hdl_fixed_same": {}, "hdl_trials": pick}
    f_sub = ridge_experiment("fixed", spec, table=f.table, trials=pick) if hdl_engines else None
    for e in hdl_engines:
        bd = None if build_dir is None else f"{build_dir}/{e}"
        r = ridge_experiment(e, spec, build_dir=bd, table=f.table, trials=pick,
                             on_chip=on_chip)
        out["results"].append(r)
        out["hdl_fixed_same"][e] = r.decoded == f_sub.decoded and r.patterns == f_sub.patterns
    return out


def format_ridge(res: RidgeResult) -> str:
    how = ("lookup table from every other trial of each angle, tested on the rest"
           if not all(res.tested) else "lookup table given, every trial tested")
    lines = [f"ridge angle on {res.engine}: {len(res.trial_angle)} trials, decode accuracy "
             f"{100 * res.accuracy:.1f} % ({how})"]
    for a in res.angles:
        pats = Counter(p for p, x in zip(res.patterns, res.trial_angle) if x == a)
        if not pats:
            continue
        lines.append(f"  {a:+6.1f} deg: active cuneate neurons "
                     + ", ".join(f"{list(p) or '[]'} x{n}" for p, n in pats.most_common()))
    lines.append("  table: " + "; ".join(f"{list(p) or '[]'} -> {a:+g} deg"
                                         for p, a in sorted(res.table.items())))
    return "\n".join(lines)


def format_comparison(cmp: dict) -> str:
    lines = [format_ridge(r) for r in cmp["results"]]
    lines.append("golden and fixed decode every trial the same: "
                 + ("yes" if cmp["golden_fixed_same"] else "NO"))
    for e, same in cmp["hdl_fixed_same"].items():
        lines.append(f"{e} and fixed: same active neurons and angle on every trial run: "
                     + ("yes" if same else "NO"))
    return "\n".join(lines)
