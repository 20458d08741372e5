"""Bad, extreme and hostile input to every command: exit status 2 and one line naming the input,
in bounded time and memory; an unexpected error is one line (exit 3) unless ``--debug``.

One table (:data:`CASES`): the command line, the files it reads, the expected exit status and a
fragment of the expected message. Runaways are refused by their estimate, before allocating:
the table runs under a fixed memory limit (:func:`cuneate.golden.budget.limited`), and a few of
them once more in a child process under an address-space limit (``ulimit -v``).
"""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import scipy.io

from cuneate.golden import budget
from cuneate.sim.cli import main

#: The memory every case may use (the runaways below ask for far more).
MEMORY_LIMIT = 2 << 30

POP = """
[[population]]
name = "sa"
model = "izhikevich"
preset = "RS"
encoding = "SA"
"""


def scene(body: str, trials: int = 1, duration_ms: float = 60.0) -> str:
    """A small afferent scene (one SA population, golden engine) with ``body`` added."""
    return (f"[scene]\nduration_ms = {duration_ms}\ntrials = {trials}\n{textwrap.dedent(body)}"
            f"\n{POP}\n[run]\nengines = [\"golden\"]\n")


def _trace_csv(values) -> str:
    t = np.arange(len(values)) / 1000.0
    return "Time,g0\n" + "".join(f"{float(ti)!r},{float(v)!r}\n" for ti, v in zip(t, values))


def _complex_npz(path):
    np.savez(path, Time=np.arange(60) / 1e3, DeltaBraggW=np.zeros((60, 1)) + 1e-3j)


def _mat_struct_time(path):
    scipy.io.savemat(path, {"Time": {"inner": np.arange(5) / 1e3},
                            "DeltaBraggW": np.zeros((5, 1))})


RECORDED = """
[sensor]
channels = 1
{sensor}
[stimulus]
kind = "recorded"
file = "{file}"
"""

def recorded(file: str, sensor: str = "") -> str:
    """A scene of the recorded trace ``file`` (one grating) with ``sensor`` keys added."""
    return scene(RECORDED.format(file=file, sensor=sensor))


# (id, argv, files {name: text | bytes | callable(path)}, exit status, message fragment)
CASES = [
    # --- runaways: refused by the estimate, before the first large allocation
    ("scene-10MHz-update", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[hardware]\nupdate_hz = 1e7\nclock_hz = 1e9\n", duration_ms=200)},
     2, "more than the limit of 60 min"),
    ("scene-many-long-trials", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[hardware]\nclock_hz = 1e9\n", trials=2000, duration_ms=600000)},
     2, "of memory, more than"),
    ("generate-coincidence-1e8-delay", ["generate", "coincidence", "--max-delay-ticks",
                                        "100000000", "--out", "{tmp}/o"], {},
     2, "does not fit the block RAM"),
    ("simulate-coincidence-1e9-delay", ["simulate", "coincidence", "--max-delay-ticks",
                                        "1000000000", "--duration-ms", "1"], {},
     2, "at most 958464 ticks"),
    ("sweep-1e9-ms", ["sweep", "--battery", "yardstick", "--duration-ms", "1e9",
                      "--scheduler", "sync", "--out", "{tmp}/o"], {},
     2, "more than the limit of 60 min"),
    ("sweep-pack-registers-without-fmax", ["sweep", "--battery", "yardstick",
                                           "--pack-registers", "--scheduler", "sync", "--out",
                                           "{tmp}/o"], {},
     2, "--pack-registers: packs the netlist that --fmax places and routes"),
    ("lif-quantization-1e5", ["lif", "quantization", "--inputs", "100000", "--neurons",
                              "100000"], {}, 2, "of memory, more than"),
    # --- divergence, files, tools, schedulers: one line, exit 2
    ("scene-sa-gain-diverges", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[frontend]\nsa_gain = 1e12\n")}, 2, "the golden engine diverged"),
    ("scene-noise-diverges", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[sensor]\neffects = [\"strain\", \"noise\"]\nnoise = {sigma_pm = 1e4}\n")},
     2, "the golden engine diverged"),
    ("sweep-scene-diverges", ["sweep", "--battery", "scene:{tmp}/s.toml", "--scheduler", "sync",
                              "--out", "{tmp}/o"],
     {"s.toml": scene("[frontend]\nsa_gain = 1e12\n")}, 2, "(at --reference-hz 256000) diverged"),
    ("recorded-1e300", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.csv": _trace_csv([0.0, 1e300] + [0.0] * 60),
      "s.toml": recorded("{tmp}/t.csv")}, 2, "t.csv: row 1"),
    ("simulate-lif-1e300", ["simulate", "lif", "--current", "1e300"], {}, 2, "diverged"),
    ("scene-not-utf8", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": b"[scene]\nname = \"\xff\xfe\"\n"}, 2, "line 2: not UTF-8"),
    ("trace-not-utf8", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.csv": b"Time,g0\n0.0,\xff\n", "s.toml": recorded("{tmp}/t.csv")},
     2, "t.csv: line 2: not UTF-8"),
    ("mat-time-is-struct", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.mat": _mat_struct_time, "s.toml": recorded("{tmp}/t.mat")},
     2, "the time field 'Time' is not numeric"),
    ("generate-bad-module-name", ["generate", "coincidence", "--name", "bad name!", "--out",
                                  "{tmp}/o"], {}, 2, "not a Verilog module name"),
    ("ridge-near-zero-speed", ["coincidence", "ridge", "--speed", "1e-9"], {}, 2,
     "--speed: at 1e-09 mm/s"),
    ("sweep-nan-rate", ["sweep", "--update-hz", "nan", "--scheduler", "sync", "--out",
                        "{tmp}/o"], {}, 2, "--update-hz: not a finite number"),
    ("sweep-inf-rate", ["sweep", "--update-hz", "4000,inf", "--scheduler", "sync", "--out",
                        "{tmp}/o"], {}, 2, "--update-hz: not a finite number"),
    ("sweep-unreachable-scheduler", ["sweep", "--scheduler", "tcp://127.0.0.1:1",
                                     "--scheduler-timeout-s", "1", "--out", "{tmp}/o"], {},
     2, "no dask scheduler answered within 1 s"),
    ("sweep-malformed-scheduler", ["sweep", "--scheduler", "not an address", "--out",
                                   "{tmp}/o"], {}, 2, "not a dask scheduler address"),
    ("negative-number-is-a-value", ["simulate", "izhikevich", "--duration-ms", "-5"], {}, 2,
     "must be > 0"),
    ("recorded-effects-are-applied", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.csv": _trace_csv([0.0] * 60),
      "s.toml": recorded("{tmp}/t.csv", "effects = [\"strain\", \"noise\"]\n"
                                                "noise = {sigma_pm = 1e4}")},
     2, "the golden engine diverged"),
    ("complex-npz", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.npz": _complex_npz, "s.toml": recorded("{tmp}/t.npz")},
     2, "holds complex values"),
    # --- nonsense refused before anything runs
    ("pulse-amplitude-twice", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[stimulus]\nkind = \"pulses\"\npulse_amplitudes_N = [1.0, 1.0]\n")},
     2, "lists an amplitude twice"),
    ("saturation-min-above-max", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[sensor]\neffects = [\"strain\", \"saturation\"]\n"
                      "saturation = {min_nm = 1.0, max_nm = -1.0}\n")},
     2, "min_nm (1) must be below max_nm (-1)"),
    ("decoder-window-outside-run", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[decoder]\nwindow_ms = [500.0, 900.0]\n")}, 2,
     "decoder.window_ms: [500, 900] ms lies outside the run"),
    ("decoder-winner-on-gratings", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[decoder]\nkind = \"winner\"\n")}, 2,
     "a scene of FBG afferents takes"),
    ("knn-more-neighbours-than-samples", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[decoder]\nkind = \"knn\"\nfeatures = \"trial\"\nneighbours = 50\n"
                      "cv_folds = 2\n", trials=2)}, 2,
     "decoder.neighbours: 50 neighbours, but the smallest training fold holds 4 trial(s)"),
    ("scene-seed-above-2-32", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("").replace("trials = 1", "trials = 1\nseed = 4294967296")}, 2,
     "scene.seed"),
    ("cli-seed-above-2-32", ["coincidence", "ridge", "--seed", "4294967296"], {}, 2,
     "a seed must be at most 2**32 - 1"),
    ("duration-1e300-no-300-digit-number", ["simulate", "lif", "--duration-ms", "1e300"], {},
     2, "1.6e+301 sweeps"),
    ("range-search-at-10MHz", ["simulate", "izhikevich", "--engine", "fixed", "--clock-hz",
                               "1e9", "--update-hz", "1e7", "--duration-ms", "1"], {}, 2,
     "the state-range search (1 parameter set(s), 5e+06 steps"),
    ("sweep-reference-without-spikes", ["sweep", "--battery", "yardstick", "--duration-ms",
                                        "0.5", "--update-hz", "4000", "--scheduler", "sync",
                                        "--out", "{tmp}/o"], {}, 2, "has no spike in 0.5 ms"),
    ("delay-1e300-ms-never-a-negative-tick", ["simulate", "coincidence", "--delays-ms", "1e300",
                                              "--duration-ms", "1"], {}, 2,
     "--delays-ms: 1e+300 ms is out of range"),
    ("out-empty", ["generate", "coincidence", "--out", ""], {}, 2, "empty directory name"),
    ("lif-probability-above-1", ["simulate", "lif", "--input-rate", "2"], {}, 2,
     "a probability must be in [0, 1]"),
    ("lif-negative-probability", ["simulate", "lif", "--input-rate", "-0.5"], {}, 2,
     "a probability must be in [0, 1]"),
    # --- valid input accepted
    ("neuron-sets-below-8-neurons", ["simulate", "izhikevich", "--neurons", "3",
                                     "--neuron-sets", "0,0,0", "--duration-ms", "10"], {},
     0, ""),
]


def _materialize(tmp_path, argv, files):
    for name, content in files.items():
        p = tmp_path / name
        if callable(content):
            content(p)
        elif isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content.replace("{tmp}", str(tmp_path)))
    return [a.replace("{tmp}", str(tmp_path)) for a in argv]


@pytest.mark.parametrize("argv, files, status, fragment", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_exits_with_one_line(tmp_path, capsys, argv, files, status, fragment):
    argv = _materialize(tmp_path, argv, files)
    with budget.limited(memory_bytes=MEMORY_LIMIT):
        rc = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == status, err
    if status:
        # the refusal is the last line (a command may have logged progress before it)
        assert fragment in err[-1], err
        assert err[-1].startswith("cuneate"), err


def test_latency_past_the_end_is_counted_not_blamed_on_currents(tmp_path, capsys):
    """With a latency longer than the run no sample reaches the core: run.json, the page and
    the printed lines say so (the samples are counted), instead of blaming weak currents."""
    text = scene("[frontend]\nlatency_ticks = 1000000\n", duration_ms=30.0)
    # a NUL in the scene's name never reaches the page raw
    (tmp_path / "s.toml").write_text(text.replace("[scene]", "[scene]\nname = \"a\\u0000b\""))
    rc = main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert rc == 0
    sat = json.loads((tmp_path / "o" / "run.json").read_text())["saturations"]
    assert sat["samples_past_end"] == sat["samples"] == 30
    assert "30 of 30 samples fall past the run's end" in out
    assert "no sample reached the core" in out and "no neuron spiked" not in out
    page = (tmp_path / "o" / "index.html").read_text()
    assert "30 of 30 samples past the run's end" in page
    assert "\x00" not in page and "a\ufffdb" in page


def test_unexpected_error_is_one_line_and_debug_shows_the_traceback(monkeypatch, capsys):
    from cuneate.sim import cli

    def broken(args):
        raise RuntimeError("an internal fault\nover two lines")
    real = cli.build_parser
    monkeypatch.setattr(cli, "build_parser", lambda: _rebind(real(), broken))
    argv = ["simulate", "izhikevich", "--duration-ms", "1"]
    assert main(argv) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "RuntimeError: an internal fault over two lines" in err
    assert "run with --debug for the traceback" in err
    assert main(argv[:1] + ["--debug"] + argv[1:]) == 3
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and "over two lines" in err


def _rebind(parser, func):
    """``parser`` with ``simulate izhikevich`` bound to ``func``."""
    sub = next(a for a in parser._actions if a.dest == "command").choices["simulate"]
    izh = next(a for a in sub._actions if a.dest == "model").choices["izhikevich"]
    izh.set_defaults(func=func)
    return parser


RUNAWAYS = [c for c in CASES if c[0] in ("generate-coincidence-1e8-delay",
                                         "lif-quantization-1e5", "sweep-1e9-ms")]


def test_runaways_refused_under_an_address_space_limit(tmp_path):
    """The runaways in a child process under ``ulimit -v`` (3 GiB of address space): each is
    refused by its estimate (exit 2, one line) instead of dying in a MemoryError."""
    script = textwrap.dedent(f"""
        import resource, sys
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
        from cuneate.sim.cli import main
        for argv in {[_materialize(tmp_path, c[1], c[2]) for c in RUNAWAYS]!r}:
            print(main(argv), flush=True)
    """)
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=300, env=env)
    assert r.stdout.split() == ["2"] * len(RUNAWAYS), (r.stdout, r.stderr[-2000:])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == len(RUNAWAYS), lines
    for line, c in zip(lines, RUNAWAYS):
        assert c[4] in line, line


def test_narrow_state_formats_state_their_rounding_and_warn(capsys):
    """Fraction bits far below the default's: the run goes on, with one warning line that
    states the per-update rounding and how far it is above the default formats'."""
    rc = main(["-q", "simulate", "izhikevich", "--engine", "fixed", "--v-frac-bits", "6",
               "--u-frac-bits", "8", "--duration-ms", "10"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 0
    assert err == ["cuneate: warning: state formats sQ9.6 (v) and sQ10.8 (u) round v by up to "
                   "0.00781 mV and u by up to 0.00195 per update, 4096 times the default "
                   "formats' (v_frac_bits 18, u_frac_bits 20): spike counts may differ from the "
                   "golden model's many-fold"], err


def test_input_spike_after_the_run_is_refused_not_dropped(capsys):
    """A spike time far beyond the run (1e300 ms) is refused naming it (it once wrapped to tick
    -9223372036854775808, then was dropped without a word)."""
    rc = main(["simulate", "coincidence", "--input", "1e300", "--input", "", "--input", "",
               "--input", "", "--duration-ms", "1", "--json"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert "a spike at 1e+300 ms falls after the run's last tick (0.9375 ms)" in err[0]
