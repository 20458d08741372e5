"""Spike files: the spikes one engine produced, in one documented format, and their loader.

Format ``cuneate-spikes/1``: a NumPy ``.npz`` archive (:func:`numpy.savez_compressed`, no
pickled objects) with

=============== ============ ==========================================================
key             dtype        holds
=============== ============ ==========================================================
``format``      str          ``"cuneate-spikes/1"``
``engine``      str          the engine that produced the spikes
``times_ms``    float64      every spike time (ms), grouped by neuron, each neuron's in
                             time order
``neuron``      int64        the neuron of each spike (an index into the neuron table)
``population``  str          per neuron: its population (a scene's ``[[population]]``
                             name, or the block for ``cuneate simulate``)
``trial``       int64        per neuron: the trial it belongs to (0 for ``simulate``)
``grating``     int64        per neuron: the grating, taxel or input it encodes (-1: none)
``class``       str          per neuron: the class of its trial ("" when there is none)
``dt_ms``       float64      the engine's time step (NaN when it has none)
``t_stop_ms``   float64      the end of the run (ms)
=============== ============ ==========================================================

A spike of update ``k`` is at ``(k + 1) dt`` (the convention of every engine).
:func:`load_spikes` returns a :class:`SpikeFile` whose :meth:`SpikeFile.trains` gives one array
per neuron and :meth:`SpikeFile.to_neo` one :class:`neo.core.SpikeTrain` per neuron (in ms,
annotated with population, trial, grating, class and neuron index), ready for Elephant.
"""

from __future__ import annotations

import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["FORMAT", "SpikeFile", "write_spikes", "load_spikes"]

FORMAT = "cuneate-spikes/1"
#: the arrays a spike file holds (besides ``format``)
KEYS = ("engine", "times_ms", "neuron", "population", "trial", "grating", "class", "dt_ms",
        "t_stop_ms")


def write_spikes(path, trains_ms, engine: str, t_stop_ms: float, population, trial=None,
                 grating=None, classes=None, dt_ms: float | None = None) -> Path:
    """Write ``trains_ms`` (one array of spike times per neuron) and the neuron table
    (``population``, ``trial``, ``grating``, ``classes``: one entry per neuron; missing ones
    default to 0, -1 and "") to ``path`` in the format of the module docstring."""
    n = len(trains_ms)
    trains = [np.asarray(t, dtype=np.float64).ravel() for t in trains_ms]
    table = {"population": population, "trial": trial if trial is not None else [0] * n,
             "grating": grating if grating is not None else [-1] * n,
             "class": classes if classes is not None else [""] * n}
    for k, v in table.items():
        if len(v) != n:
            raise ValueError(f"the neuron table's {k!r} has {len(v)} entries for {n} neurons")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        np.savez_compressed(
            f, format=np.array(FORMAT), engine=np.array(engine),
            times_ms=np.concatenate(trains) if trains else np.zeros(0),
            neuron=np.repeat(np.arange(n, dtype=np.int64), [t.size for t in trains]),
            population=np.array([str(x) for x in table["population"]], dtype=str),
            trial=np.asarray(table["trial"], dtype=np.int64),
            grating=np.asarray(table["grating"], dtype=np.int64),
            **{"class": np.array([str(x) for x in table["class"]], dtype=str)},
            dt_ms=np.float64(np.nan if dt_ms is None else dt_ms),
            t_stop_ms=np.float64(t_stop_ms))
    return path


@dataclass
class SpikeFile:
    """The contents of a spike file (arrays as stored)."""

    engine: str
    times_ms: np.ndarray
    neuron: np.ndarray
    population: np.ndarray
    trial: np.ndarray
    grating: np.ndarray
    classes: np.ndarray
    dt_ms: float
    t_stop_ms: float

    def __len__(self) -> int:
        return int(self.population.size)

    def trains(self) -> list[np.ndarray]:
        """One array of spike times (ms) per neuron, in the neuron table's order."""
        order = np.argsort(self.neuron, kind="stable")
        bounds = np.searchsorted(self.neuron[order], np.arange(len(self) + 1))
        t = self.times_ms[order]
        return [t[bounds[i]:bounds[i + 1]] for i in range(len(self))]

    def to_neo(self) -> list:
        """One :class:`neo.core.SpikeTrain` per neuron (ms, ``t_stop`` the run's end),
        annotated with ``population``, ``trial``, ``grating``, ``class``, ``neuron`` and
        ``engine``."""
        import neo
        import quantities as pq
        out = []
        for i, t in enumerate(self.trains()):
            st = neo.SpikeTrain(t * pq.ms, t_stop=max(self.t_stop_ms, float(t.max(initial=0)))
                                * pq.ms, name=f"{self.population[i]}[{i}]")
            st.annotate(population=str(self.population[i]), trial=int(self.trial[i]),
                        grating=int(self.grating[i]), neuron=i, engine=self.engine,
                        **{"class": str(self.classes[i])})
            out.append(st)
        return out


def load_spikes(path, as_neo: bool = False):
    """Read a spike file; a :class:`SpikeFile`, or with ``as_neo`` its
    :meth:`SpikeFile.to_neo` trains. A file of another format, an unreadable or incomplete one,
    or one whose spikes name neurons outside its table or disagree with its times, is refused
    (``ValueError`` naming the file; a missing file is ``FileNotFoundError``)."""
    try:
        with np.load(Path(path), allow_pickle=False) as z:
            fmt = str(z["format"]) if "format" in z.files else None
            if fmt != FORMAT:
                raise ValueError(f"{path}: not a {FORMAT} file (format {fmt!r})")
            missing = [k for k in KEYS if k not in z.files]
            if missing:
                raise ValueError(f"{path}: a {FORMAT} file without {', '.join(missing)}")
            f = SpikeFile(str(z["engine"]), z["times_ms"], z["neuron"], z["population"],
                          z["trial"], z["grating"], z["class"], float(z["dt_ms"]),
                          float(z["t_stop_ms"]))
    except (EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise ValueError(f"{path}: not a readable spike file ({type(exc).__name__}: "
                         f"{exc})") from None
    n = len(f)
    if f.neuron.shape != f.times_ms.shape:
        raise ValueError(f"{path}: {f.neuron.size} neuron indices for {f.times_ms.size} spikes")
    if f.neuron.size and (f.neuron.min() < 0 or f.neuron.max() >= n):
        bad = int(f.neuron[(f.neuron < 0) | (f.neuron >= n)][0])
        raise ValueError(f"{path}: a spike of neuron {bad}, outside its table of {n} neurons")
    for k in ("trial", "grating", "classes"):
        if getattr(f, k).size != n:
            raise ValueError(f"{path}: the neuron table's {k} has {getattr(f, k).size} entries "
                             f"for {n} neurons")
    return f.to_neo() if as_neo else f
