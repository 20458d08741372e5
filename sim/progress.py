"""What a long command is doing, shown the same way by every command: one progress module.

Every step that can take more than a moment (synthesizing a stimulus, compiling Verilator,
simulating, building a sweep's reference, decoding, writing figures, placing and routing) runs
inside :func:`step`, which says what it is doing:

* in a terminal (``mode="bar"``): a tqdm bar per active step on stderr (a count when the step
  knows its total, the elapsed time otherwise), refreshed at least once a second;
* when stderr is not a terminal (``mode="log"``: pipes, CI logs): timestamped lines,
  ``[HH:MM:SS] what``, when a step starts and ends, and while steps run a heartbeat line
  naming every active step with its progress at least every :data:`HEARTBEAT_S` seconds, so a
  log never stays silent for long;
* ``mode="quiet"`` (``-q``): nothing.

The library is quiet until a command calls :func:`configure` (``mode="auto"`` picks ``bar``
or ``log`` from stderr). Steps may run in several threads at once (a scene's HDL simulator in
the background beside the Python engines); output is serialized.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time

__all__ = ["configure", "mode", "step", "say", "Step", "HEARTBEAT_S", "callback", "plural"]

#: Longest silence in ``log`` mode while a step runs (seconds).
HEARTBEAT_S = 5.0

_lock = threading.RLock()
_state = {"mode": "quiet", "stream": None, "heartbeat_s": HEARTBEAT_S, "verbose": False,
          "last_line": 0.0}
_active: list = []
_ticker: dict = {"thread": None, "stop": None}


def plural(unit: str, n: float) -> str:
    """``unit`` for ``n`` of it: ``tick`` for 1, ``ticks`` otherwise (``11200 ticks``)."""
    return unit if n == 1 or not unit or unit.endswith("s") else unit + "s"


def configure(mode: str = "auto", stream=None, heartbeat_s: float = HEARTBEAT_S,
              verbose: bool = False) -> str:
    """Choose how steps are shown: ``"auto"`` (``"bar"`` on a terminal, ``"log"`` otherwise),
    ``"bar"``, ``"log"`` or ``"quiet"``; ``stream`` defaults to stderr; ``verbose`` also
    prints the end of every step in ``bar`` mode. Returns the mode chosen."""
    if mode == "auto":
        isatty = getattr(stream if stream is not None else sys.stderr, "isatty", None)
        mode = "bar" if isatty is not None and isatty() else "log"
    if mode not in ("bar", "log", "quiet"):
        raise ValueError(f"unknown progress mode {mode!r}")
    with _lock:
        _state.update(mode=mode, stream=stream, heartbeat_s=float(heartbeat_s),
                      verbose=bool(verbose))
    return mode


def mode() -> str:
    """The current mode (``"quiet"`` until :func:`configure` is called)."""
    return _state["mode"]


def _stream():
    """The stream given to :func:`configure`, else the current ``sys.stderr`` (looked up at
    each line, so a replaced stderr is followed)."""
    return _state["stream"] or sys.stderr


def _line(text: str) -> None:
    """One line on the stream (timestamped in ``log`` mode, above the bars in ``bar`` mode)."""
    with _lock:
        m = _state["mode"]
        if m == "quiet":
            return
        if m == "log":
            print(f"[{time.strftime('%H:%M:%S')}] {text}", file=_stream(), flush=True)
        else:
            from tqdm import tqdm
            tqdm.write(text, file=_stream())
        _state["last_line"] = time.monotonic()


def say(text: str) -> None:
    """A line about what is happening (a stage's result, a cache hit)."""
    _line(text)


class Step:
    """One running step: :meth:`set` / :meth:`update` its progress, :meth:`note` a detail."""

    def __init__(self, what: str, total: float | None, unit: str):
        self.what, self.total, self.unit = what, total, unit
        self.done = 0
        self.t0 = time.monotonic()
        self.detail = ""
        self.bar = None

    def set(self, done: float) -> None:
        """The step has done ``done`` of its total (absolute)."""
        with _lock:
            self.done = done
            if self.bar is not None:
                self.bar.n = done
                self.bar.refresh()

    def update(self, n: float = 1) -> None:
        """``n`` more units done."""
        self.set(self.done + n)

    def note(self, detail: str) -> None:
        """What the step is doing now (shown in the bar and in heartbeat lines)."""
        with _lock:
            self.detail = detail
            if self.bar is not None:
                self.bar.set_postfix_str(detail, refresh=True)

    def status(self) -> str:
        el = time.monotonic() - self.t0
        if self.total:
            frac = min(1.0, self.done / self.total)
            s = (f"{self.what} {100 * frac:.0f} % ({self.done:g}/{self.total:g}"
                 f"{' ' + plural(self.unit, self.total) if self.unit else ''})")
        else:
            s = self.what
        if self.detail:
            s += f" [{self.detail}]"
        return f"{s}, {el:.0f} s"


def _tick_loop(stop: threading.Event) -> None:
    while not stop.wait(min(1.0, _state["heartbeat_s"] / 4)):
        with _lock:
            if not _active:
                continue
            m = _state["mode"]
            if m == "bar":
                for s in _active:
                    if s.bar is not None:
                        s.bar.refresh()
            elif m == "log" and time.monotonic() - _state["last_line"] >= _state["heartbeat_s"]:
                _line("... " + "; ".join(s.status() for s in _active))


def _ensure_ticker() -> None:
    if _ticker["thread"] is None or not _ticker["thread"].is_alive():
        stop = threading.Event()
        t = threading.Thread(target=_tick_loop, args=(stop,), daemon=True,
                             name="cuneate-progress")
        _ticker.update(thread=t, stop=stop)
        t.start()


@contextlib.contextmanager
def step(what: str, total: float | None = None, unit: str = ""):
    """Run a step that says what it does (see the module docstring); yields its :class:`Step`.
    ``total``/``unit``: how much work it has, when known (``step.set(done)`` reports it)."""
    s = Step(what, total, unit)
    m = _state["mode"]
    with _lock:
        if m == "bar":
            from tqdm import tqdm
            s.bar = tqdm(total=total, desc=what, unit=unit or "it", leave=False,
                         file=_stream(), dynamic_ncols=True,
                         bar_format=None if total else "{desc}: {elapsed}{postfix}")
        elif m == "log":
            _line(what + (f" ({total:g} {plural(unit, total)})" if total else "") + " ...")
        _active.append(s)
        if m != "quiet":
            _ensure_ticker()
    ok = False
    try:
        yield s
        ok = True
    finally:
        with _lock:
            _active.remove(s)
            if s.bar is not None:
                s.bar.close()
            el = time.monotonic() - s.t0
            if m == "log" or (m == "bar" and _state["verbose"]):
                _line(f"{what}: {'done' if ok else 'stopped'} in {el:.1f} s")


def callback(s: Step | None):
    """A ``progress(done)`` callback (the engines' convention) that reports into step ``s``
    (``None`` when ``s`` is ``None``)."""
    return None if s is None else s.set
