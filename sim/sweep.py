"""What accuracy costs: the sweep framework. Blocks register their batteries; a sweep evaluates
points (configurations of a block or of its golden model) on a battery against one reference.

A **battery** is a population to simulate; each block's sweep module
(``cuneate.sim.<block>.sweep``) registers its batteries with :func:`register_battery` and
provides their reference trains (``reference_trains(spec)``), their points from the command
line (``points_from_args``) and the report's columns (``COLUMNS``). A **point** evaluates itself
(``point.evaluate(spec, ref)``) against the reference into a row: accuracy (:func:`ok_row`,
:func:`accuracy_row`: fraction of reference spikes within one of the point's ticks, spike-count
error, matched spike-time error, Victor-Purpura distance at q = 5/s, first-spike latency error;
:func:`same_dt_columns`: the arithmetic's error alone, against float64 at the point's own dt) and
cost (neurons per core, multipliers, state bits, host time, and with synthesis LUT/FF/DSP/BRAM
and fmax).

Points run in parallel with Dask (``dask.distributed``: a local cluster by default, or a
scheduler address); each result is cached on disk under its key (:func:`point_key`), so an
interrupted sweep resumes where it stopped. :func:`write_sweep` writes CSV, JSON, a Pareto plot
and an HTML page.
"""

from __future__ import annotations

import csv
import hashlib
import html
import importlib
import importlib.util
import json
import logging
import pkgutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

__all__ = ["Point", "SweepSpec", "register_battery", "battery_module", "battery_names",
           "reference_trains", "evaluate", "accuracy_row", "ok_row", "same_dt_columns",
           "refused", "point_key", "n_steps", "run_sweep", "pareto_front", "write_sweep",
           "BLOCK_SAME_DT_KEYS", "VP_Q_PER_MS", "HEADLINE_ERROR", "COSTS", "estimate_sweep",
           "dask_connect", "dask_map"]

from ..golden.metrics import VP_Q_PER_MS, compare_populations
from . import progress as prog
from .engines.registry import estimate_seconds
from .provenance import provenance
from .report import figures_html, html_table, page_head, printable, pyplot, save_figure
from ..golden.budget import BASE_BYTES
from ..golden.izhikevich import DivergenceError

#: battery name -> the block sweep module that owns it; prefixes (``scene:``) apart
_BATTERIES: dict = {}
_PREFIXES: dict = {}
_DISCOVERED = False


def register_battery(name: str, module, prefix: bool = False) -> None:
    """Declare battery ``name`` (or, with ``prefix``, every name starting with it) as owned by
    the block sweep ``module`` (called by ``cuneate.sim.<block>.sweep`` at import)."""
    (_PREFIXES if prefix else _BATTERIES)[name] = module


def _discover() -> None:
    """Import every block's sweep module (``cuneate.sim.<package>.sweep``) once, so that they
    register their batteries."""
    global _DISCOVERED
    if _DISCOVERED:
        return
    _DISCOVERED = True
    root = importlib.import_module(__package__)
    for info in pkgutil.iter_modules(root.__path__):
        name = f"{__package__}.{info.name}.sweep"
        if info.ispkg and importlib.util.find_spec(name) is not None:
            importlib.import_module(name)


def battery_names() -> list[str]:
    """Every registered battery (prefixed families as ``prefix...``)."""
    _discover()
    return list(_BATTERIES) + [f"{p}NAME" for p in _PREFIXES]


def battery_module(name: str):
    """The block sweep module that owns battery ``name``; ``ValueError`` names the known ones."""
    _discover()
    if name in _BATTERIES:
        return _BATTERIES[name]
    for p, mod in _PREFIXES.items():
        if name.startswith(p):
            return mod
    raise ValueError(f"unknown battery {name!r} (known: {', '.join(battery_names())})")


def point_key(*parts) -> str:
    """A point's cache key: a hash of ``parts`` (its fields and the spec fields its result
    depends on), shared by every block's points."""
    blob = json.dumps(list(parts), sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def n_steps(duration_ms: float, dt_ms: float) -> int:
    """Updates in ``duration_ms`` at a step of ``dt_ms``."""
    return int(round(duration_ms / dt_ms))


@dataclass(frozen=True)
class Point:
    """What every block's sweep point has: ``engine`` (``fixed``: the block's bit-exact twin,
    configured from the point's knobs; ``float64``/``float32``: its golden model in that
    arithmetic), the update rate and, for ``fixed``, the multiplier operand width and the
    rounding. A block's point adds its own knobs and evaluates itself
    (``evaluate(spec, ref)``)."""

    engine: str
    update_hz: float = 16e3
    operand_width: int = 18
    rounding: str = "nearest"

    #: prefix of the point's cache key (the block)
    BLOCK: ClassVar[str] = ""

    def key(self, spec: "SweepSpec") -> str:
        """Cache key of the point on ``spec`` (its fields, the battery, duration, reference
        rate and clock)."""
        return point_key(self.BLOCK, asdict(self), spec.battery, spec.duration_ms,
                         spec.reference_hz, spec.clock_hz)


@dataclass
class SweepSpec:
    battery: str = "yardstick"
    duration_ms: float = 1000.0
    reference_hz: float = 256e3
    clock_hz: float = 40e6
    synth: bool = False
    fmax: bool = False
    pipeline_stages: int = 5
    seeds: tuple = (1,)
    pack_registers: bool = False
    """with ``fmax``: the flip-flops around the multipliers and after the block RAMs packed
    into their DSP and block-RAM registers before place and route
    (:mod:`cuneate.hdl.flow.ecp5_pack`)"""


def reference_trains(spec: SweepSpec) -> list[np.ndarray]:
    """The accuracy reference of the spec's battery (its block decides: float64 RK4 at
    ``reference_hz`` for the Izhikevich batteries). Refused (``ValueError``, one line): a
    reference that diverges or has no spike at all (nothing to measure a point against)."""
    try:
        ref = battery_module(spec.battery).reference_trains(spec)
    except DivergenceError as exc:
        raise ValueError(f"the reference of battery {spec.battery!r} (at --reference-hz "
                         f"{spec.reference_hz:g}) diverged: {exc}") from None
    if not any(len(r) for r in ref):
        raise ValueError(f"the reference of battery {spec.battery!r} at --reference-hz "
                         f"{spec.reference_hz:g} has no spike in {spec.duration_ms:g} ms: "
                         f"nothing to measure the points against (lengthen --duration-ms or "
                         f"raise --reference-hz)")
    return ref


def estimate_sweep(points: list, spec: SweepSpec, workers: int = 1) -> dict:
    """Memory (bytes) and time (s) of a sweep before it runs, from the battery's size
    (``battery_size(name)`` of its block's sweep module: trains, inputs, bytes held per step;
    ``BLOCK``: the block whose engine speeds apply), the duration and each point's update rate:
    the reference (RK4, four evaluations per step) and every point (the fixed points and the
    non-Euler float points also run float64 Euler at their dt), at the engine registry's
    speeds; the points share ``workers`` processes, each holding one point's per-step
    arrays."""
    mod = battery_module(spec.battery)
    size = mod.battery_size(spec.battery)
    n, per_step = size["trains"], size["bytes_per_step"]
    ref_steps = spec.duration_ms * spec.reference_hz / 1000.0
    seconds = 4 * estimate_seconds(mod.BLOCK, "golden", ref_steps * n)
    peak = ref_steps * per_step
    work = 0.0
    for p in points:
        steps = spec.duration_ms * p.update_hz / 1000.0
        fixed = p.engine == "fixed"
        work += estimate_seconds(mod.BLOCK, "fixed" if fixed else "golden", steps * n)
        if fixed or p.engine != "float64" or getattr(p, "scheme", "euler") != "euler":
            work += estimate_seconds(mod.BLOCK, "golden", steps * n)
        peak = max(peak, steps * per_step)
    lanes = max(1, min(workers, len(points)))
    return {"bytes": BASE_BYTES + lanes * peak, "seconds": seconds + work / lanes,
            "what": f"the sweep of {len(points)} point(s) on battery {spec.battery!r} "
                    f"({n} trains, {spec.duration_ms:g} ms, reference at "
                    f"{spec.reference_hz:g} Hz)"}


def accuracy_row(ref: list, trains: list, dt_ms: float) -> dict:
    """The accuracy columns of a row: ``trains`` against ``ref`` with a tick of ``dt_ms``."""
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
    """The columns of a simulated point: status, accuracy against ``ref``, the deterministic
    cost ``updates_per_bio_s`` (neuron updates per biological second per neuron, 1/dt) and
    host time since ``t0`` per biological second (in all, and per neuron; measured on a shared
    machine, see :func:`run_sweep`'s ``host_time`` column)."""
    wall = time.perf_counter() - t0
    bio_s = spec.duration_ms / 1000.0
    return dict(status="ok", trains=len(trains), **accuracy_row(ref, trains, dt_ms),
                updates_per_bio_s=1000.0 / dt_ms,
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
    """Simulate the battery at point ``p`` and measure it against ``ref`` (every block's points
    evaluate themselves)."""
    return p.evaluate(spec, ref)


def _evaluate_task(p, spec: SweepSpec, ref: list, repeats: int = 1) -> dict:
    """Evaluate ``p`` ``repeats`` times; the row of the fastest run, with every run's host
    seconds per biological second (the points are deterministic: only the host time varies)."""
    rows = [evaluate(p, spec, ref) for _ in range(max(1, int(repeats)))]
    if rows[0].get("status") != "ok" or len(rows) == 1:
        return rows[0]
    best = min(rows, key=lambda r: r["host_s"])
    best["host_s_per_bio_s_runs"] = [r["host_s_per_bio_s"] for r in rows]
    return best


def run_sweep(points: list, spec: SweepSpec, cache_dir: Path,
              scheduler: str | None = None, workers: int = 2, progress: bool = False,
              log=None, repeats: int = 1,
              scheduler_timeout_s: float = 10.0) -> list[dict]:
    """Evaluate ``points`` (cached per point in ``cache_dir``) with Dask; returns the rows in
    the order of ``points``. ``scheduler``: ``None`` (a local cluster of ``workers``
    processes), ``"sync"`` (in this process, no Dask) or a ``dask.distributed`` address, refused
    (``ValueError``, one line) when it does not answer within ``scheduler_timeout_s``.
    Building the reference and running the points are progress steps
    (:mod:`cuneate.sim.progress`; ``progress`` turns them on when no command has). Every row
    run here gets ``host_time``: how its host seconds were measured (one point at a time, or
    alongside other points: then they are not comparable between runs). ``repeats`` > 1 runs
    each point that many times and keeps the fastest (the minimum is the figure least
    disturbed by other load)."""
    if progress and prog.mode() == "quiet":
        prog.configure("auto")

    def say(msg):
        prog.say(msg)
        if log is not None:
            log(msg)
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
        remote = dask_connect(scheduler, scheduler_timeout_s)   # a bad address fails fast
        ref_file = cache_dir / f"reference-{point_key('reference', asdict(spec))}.json"
        try:
            if ref_file.exists():
                ref = [np.asarray(x) for x in json.loads(ref_file.read_text())]
                prog.say(f"sweep: the reference of {spec.battery} is cached ({ref_file.name})")
            else:
                with prog.step(f"building the reference of battery {spec.battery} "
                               f"({spec.duration_ms:g} ms; cached for later sweeps)"):
                    ref = reference_trains(spec)
                ref_file.write_text(json.dumps([r.tolist() for r in ref]))
        except BaseException:
            if remote is not None:
                remote.close()
            raise
        parallel = len(todo) > 1 and scheduler != "sync" and not (scheduler is None
                                                                   and workers == 1)
        how = (f"alongside other points ({workers if scheduler is None else 'cluster'} "
               f"workers): not comparable between runs" if parallel
               else "one point at a time")
        st_cm = prog.step(f"running {len(todo)} sweep point(s)", total=len(todo), unit="point")
        st = st_cm.__enter__()

        def done(p, row):
            if row.get("status") == "ok":
                row["host_time"] = how + (f", fastest of {repeats} runs" if repeats > 1
                                          else "")
            (cache_dir / f"{p.key(spec)}.json").write_text(json.dumps(row, default=float))
            rows[p] = row
            st.update(1)
            st.note(p.label())
        dask_map(_evaluate_task, todo, (spec, ref, repeats), done, scheduler, workers, remote,
                 shared=1)
        st_cm.__exit__(None, None, None)
    return [rows[p] for p in points]


def dask_connect(scheduler: str | None, timeout_s: float = 10.0):
    """A client of the ``dask.distributed`` scheduler at ``scheduler`` (``None`` for ``None``
    or ``"sync"``: no remote scheduler), refused (``ValueError``, one line) when the address is
    not one or no scheduler answers within ``timeout_s``."""
    if scheduler in (None, "", "sync"):
        return None
    from dask.distributed import Client
    try:
        return Client(scheduler, timeout=timeout_s)
    except (ValueError, TypeError) as exc:
        why = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise ValueError(f"scheduler {scheduler!r}: not a dask scheduler address "
                         f"({why})") from None
    except (OSError, TimeoutError) as exc:
        why = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise ValueError(f"scheduler {scheduler!r}: no dask scheduler answered "
                         f"within {timeout_s:g} s ({why})") from None


def dask_map(fn, items: list, args: tuple, done, scheduler: str | None = None,
             workers: int = 2, remote=None, shared: int | None = None) -> None:
    """``fn(item, *args)`` for every item, ``done(item, result)`` as each finishes:
    ``scheduler`` ``"sync"`` in this process, ``None`` (or ``""``) on a local cluster of
    ``workers`` processes, else on ``remote`` (:func:`dask_connect`). ``shared``: the index in
    ``args`` of a value scattered once to every worker. The client (and a local cluster) is
    closed at the end, whatever happens."""
    if scheduler == "sync":
        for it in items:
            done(it, fn(it, *args))
        return

    from dask.distributed import Client, LocalCluster, as_completed
    cluster = None
    if remote is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.CRITICAL)
        client = Client(cluster)
    else:
        client = remote
    try:
        args = list(args)
        if shared is not None:
            args[shared] = client.scatter(args[shared], broadcast=True)
        futs = {client.submit(fn, it, *args, pure=False): it for it in items}
        for fut in as_completed(futs):
            done(futs[fut], fut.result())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


#: The error the sweep leads with (docs/accuracy.md): Victor-Purpura distance (q = 5/s) to the
#: fine-step float64 reference, lower is better; the spike-count error beside it.
HEADLINE_ERROR = "mean_vp"
#: The deterministic costs of a point (the Pareto fronts and the plot): neuron updates per
#: biological second (1/dt: neurons per core ~ clock / update rate), state bits, multipliers.
COSTS = ("updates_per_bio_s", "state_bits", "multipliers")


def pareto_front(rows: list[dict], cost: str, accuracy: str = HEADLINE_ERROR,
                 lower_is_better: bool = True) -> list[str]:
    """Keys of the rows not dominated in (better ``accuracy``, lower ``cost``); ``accuracy`` is
    an error (lower is better) unless ``lower_is_better`` is false."""
    ok = [r for r in rows if r.get("status") == "ok" and r.get(cost) is not None
          and r.get(accuracy) is not None]
    sign = -1.0 if lower_is_better else 1.0
    front = []
    for r in ok:
        a = sign * r[accuracy]
        if not any((sign * o[accuracy] >= a and o[cost] <= r[cost])
                   and (sign * o[accuracy] > a or o[cost] < r[cost]) for o in ok):
            front.append(r["key"])
    return front


def write_sweep(rows: list[dict], spec: SweepSpec, out: Path, columns=None) -> Path:
    """``sweep.csv`` (``columns``, default the battery's block's ``COLUMNS``), ``sweep.json``,
    ``pareto.png`` and ``index.html`` in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "sweep.csv", "w", newline="") as f:
        cols = columns or battery_module(spec.battery).COLUMNS
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k) for k in cols})
    fronts = {c: pareto_front(rows, c) for c in COSTS}
    (out / "sweep.json").write_text(json.dumps({"spec": asdict(spec), "rows": rows,
                                                "pareto": fronts, "provenance": provenance()},
                                               indent=1, default=float))
    plt = pyplot()
    ok = [r for r in rows if r.get("status") == "ok"]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    labels = {"updates_per_bio_s": "updates per neuron per biological s (1/dt)",
              "state_bits": "state bits per neuron", "multipliers": "multipliers per core"}
    for ax, cost in zip(axes, COSTS):
        for eng, mk in (("fixed", "o"), ("float64", "s"), ("float32", "^")):
            pts = [(r[cost], r[HEADLINE_ERROR]) for r in ok if r.get("engine") == eng
                   and r.get(cost) is not None and r.get(HEADLINE_ERROR) is not None]
            if pts:
                ax.scatter(*zip(*pts), marker=mk, label=eng, alpha=0.7)
        ax.set(xlabel=labels[cost], ylabel="mean VP distance to the reference (q = 5/s)",
               title=f"error vs {labels[cost].split(' (')[0]}")
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, out / "pareto.png")
    front = set(fronts["updates_per_bio_s"])

    def fmt(x, nd=4):
        return "-" if x is None else (f"{x:.{nd}g}" if isinstance(x, float) else str(x))
    table = [[("* " if r["key"] in front else "") + r["label"], r.get("status"),
              fmt(r.get("count_error")), fmt(r.get("mean_vp")),
              fmt(r.get("vs_euler_fraction_within_tick",
                        r.get("vs_float64_fraction_within_tick"))),
              fmt(r.get("fraction_within_tick")), fmt(r.get("mean_abs_error_ms")),
              fmt(r.get("neurons_per_core")), fmt(r.get("updates_per_bio_s")),
              fmt(r.get("multipliers")), fmt(r.get("state_bits")),
              fmt(r.get("host_s_per_bio_s"), 3) + (" (parallel)" if str(
                  r.get("host_time", "")).startswith("alongside") else ""),
              fmt(r.get("LUT4")), fmt(r.get("MULT18X18D")), fmt(r.get("fmax_mhz"), 3),
              r.get("reason", "")]
             for r in rows]
    page = f"""{page_head("cuneate sweep: what accuracy costs")}
<p>Battery <b>{html.escape(spec.battery)}</b>, {spec.duration_ms:g} ms, against float64 RK4 at
{spec.reference_hz / 1e3:g} kHz; neurons per core at {spec.clock_hz / 1e6:g} MHz. The error
against the reference is the spike-count error and the Victor-Purpura distance (q = 5/s);
within one tick of float64 Euler at the same dt isolates the arithmetic (within one tick of the
fine reference is given last: every scheme at 16 kHz misses it alike). * marks the Pareto front
of VP against updates per biological second. Host seconds are measured on a shared machine;
"(parallel)" marks points measured alongside others, not comparable between runs.</p>
{html_table(table, ["point", "status", "count error", "mean VP (q=5/s)",
                "within 1 tick of float64 (Euler; same dt)", "within 1 tick of reference",
                "mean |dt| ms", "neurons/core", "updates / bio s", "multipliers",
                "state bits", "host s / bio s", "LUT4", "MULT18", "fmax MHz", "reason"])}
{figures_html([("pareto.png", "Error against the reference (mean VP, q = 5/s) against the "
                             "deterministic costs")])}
</body></html>
"""
    (out / "index.html").write_text(printable(page))
    return out / "index.html"
