"""Bad, extreme and hostile input to every command: exit status 2 and one line naming the input,
in bounded time and memory; an unexpected error is one line (exit 3) unless ``--debug``.

One table (:data:`CASES`): the command line, the files it reads, the expected exit status and a
fragment of the expected message. Runaways are refused by their estimate, before allocating:
the table runs under a fixed memory limit (:func:`cuneate.golden.budget.limited`), and a few of
them once more in a child process under an address-space limit (``ulimit -v``).
"""

import json
import math
import os
import re
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


def _npz(**arrays):
    """A writer of an NPZ file of ``arrays``."""
    return lambda path: np.savez(path, **arrays)


def _truncated_npz(path):
    np.savez(path, Time=np.arange(60) / 1e3, DeltaBraggW=np.zeros((60, 1)))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _nir(n_in: int, n_out: int, weight: float = 0.05, threshold: float = 1.0,
         tau: float = 0.02):
    """A writer of a NIR graph: Input -> Affine (every weight ``weight``) -> LIF -> Output."""
    def write(path):
        import nir
        g = nir.NIRGraph(
            nodes={"input": nir.Input(input_type=np.array([n_in])),
                   "fc": nir.Affine(weight=np.full((n_out, n_in), weight), bias=np.zeros(n_out)),
                   "lif": nir.LIF(tau=np.full(n_out, tau), r=np.ones(n_out),
                                  v_leak=np.zeros(n_out), v_threshold=np.full(n_out, threshold)),
                   "output": nir.Output(output_type=np.array([n_out]))},
            edges=[("input", "fc"), ("fc", "lif"), ("lif", "output")])
        nir.write(path, g)
    return write


def _ridge_with_preset(preset: str) -> str:
    from cuneate.sim.scenes import example_path
    text = example_path("ridge_angle").read_text()
    return text.replace('model = "cuneate"\n', f'model = "cuneate"\npreset = "{preset}"\n')


# (id, argv, files {name: text | bytes | callable(path)}, exit status, message fragment)
CASES = [
    # --- runaways: refused by the estimate, before the first large allocation
    ("scene-10MHz-update", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("[hardware]\nupdate_hz = 1e7\nclock_hz = 1e9\n", duration_ms=200000)},
     2, "2e+09 ticks on golden) needs about 242 GiB of memory, more than"),
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
                               "1e13", "--update-hz", "1e10", "--duration-ms", "1"], {}, 2,
     "the state-range search (1 parameter set(s), 5e+09 steps"),
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
    # --- no estimate before allocating (issue 39, class 2): refused by the estimate
    ("fanout-1e8-afferents", ["simulate", "fanout", "--afferents", "100000000"], {}, 2,
     "--afferents: the fan-out table of 100000000 afferents needs 3900000000 bits"),
    ("nir-1e12-steps", ["simulate", "nir", "{tmp}/g.nir", "--steps", "1000000000000"],
     {"g.nir": _nir(4, 4)}, 2, "1e+12 steps of"),
    ("scene-label-100k-chars", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.npz": _npz(Time=np.arange(60) / 1e3, DeltaBraggW=np.zeros((60, 1))),
      "s.toml": recorded("{tmp}/t.npz").replace("[stimulus]\n", "[stimulus]\nlabel = \""
                                                 + "x" * 100_000 + "\"\n")},
     2, "stimulus.label: 100000 characters; at most 200"),
    ("scene-name-5000-chars", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": scene("").replace("[scene]\n", "[scene]\nname = \"" + "n" * 5000 + "\"\n")},
     2, "scene.name: 5000 characters; at most 200"),
    # --- trained layers too large (class 3): refused with the figure, not a RecursionError
    ("nir-layer-beyond-the-largest-fpga", ["nir", "import", "{tmp}/g.nir", "--out", "{tmp}/o"],
     {"g.nir": _nir(1000, 600, 0.01)}, 2,
     "the weight memory of 600 neurons x 1000 inputs x 8 bits needs 4.8e+06 bits"),
    ("nir-every-weight-rounds-to-0", ["nir", "import", "{tmp}/g.nir", "--weight-frac-bits",
                                      "7", "--out", "{tmp}/o"],
     {"g.nir": _nir(20, 20)}, 2, "every one of its weights rounds to 0"),
    # --- bad files, values and paths that exited 3 (class 4)
    ("empty-mat", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.mat": b"", "s.toml": recorded("{tmp}/t.mat")}, 2,
     "t.mat: not a readable MAT file (the file is empty)"),
    ("empty-npz", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.npz": b"", "s.toml": recorded("{tmp}/t.npz")}, 2,
     "t.npz: not a readable NPZ file (the file is empty)"),
    ("truncated-npz", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.npz": _truncated_npz, "s.toml": recorded("{tmp}/t.npz")}, 2,
     "t.npz: not a readable NPZ file (BadZipFile"),
    ("nir-weights-1e300", ["nir", "import", "{tmp}/g.nir", "--out", "{tmp}/o"],
     {"g.nir": _nir(4, 4, weight=1e300)}, 2, "node 'lif' (LIF): no 8-bit signed format holds"),
    ("nir-threshold-1e300", ["nir", "import", "{tmp}/g.nir", "--out", "{tmp}/o"],
     {"g.nir": _nir(4, 4, threshold=1e300)}, 2, "the state exceeds the 60 bits the twin's"),
    ("prove-work-dir-in-proc", ["prove", "fanout", "--work-dir", "/proc/cuneate-no-dir"], {},
     2, "'/proc/cuneate-no-dir"),
    ("prove-work-dir-is-a-file", ["prove", "banked", "--neurons", "8", "--bank-depth", "4",
                                  "--work-dir", "{tmp}/f"], {"f": "x"}, 2, "Not a directory"),
    ("scene-argument-5000-chars", ["run", "s" * 5000, "--out", "{tmp}/o"], {}, 2,
     "File name too long: 'sss"),
    # --- nonsense that was accepted (class 6)
    ("coincidence-negative-rate", ["simulate", "coincidence", "--input-rate-hz", "-5",
                                   "--duration-ms", "5"], {}, 2, "a rate must be >= 0 Hz"),
    ("boolean-shifts", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"t.npz": _npz(Time=np.arange(60) / 1e3, DeltaBraggW=np.ones((60, 1), dtype=bool)),
      "s.toml": recorded("{tmp}/t.npz")}, 2, "holds booleans (true/false), not numbers"),
    ("ridge-cuneate-preset-not-applied", ["run", "{tmp}/s.toml", "--out", "{tmp}/o"],
     {"s.toml": _ridge_with_preset("FS")}, 2, "population[2].preset: 'FS'"),
    ("engines-empty", ["run", "{tmp}/s.toml", "--engines", "", "--out", "{tmp}/o"],
     {"s.toml": scene("")}, 2, "--engines: '' names an empty engine"),
    ("engines-commas", ["run", "{tmp}/s.toml", "--engines", ",,,", "--out", "{tmp}/o"],
     {"s.toml": scene("")}, 2, "--engines: ',,,' names an empty engine"),
    ("engines-twice", ["run", "{tmp}/s.toml", "--engines", "golden,golden", "--out",
                       "{tmp}/o"], {"s.toml": scene("")}, 2, "names golden twice"),
    ("build-update-hz-0", ["build", "ulx3s", "--update-hz", "0", "--no-bitstream", "--out",
                           "{tmp}/o"], {}, 2, "--update-hz: must be > 0"),
    ("nir-input-of-two-arrays", ["simulate", "nir", "{tmp}/g.nir", "--input", "{tmp}/x.npz"],
     {"g.nir": _nir(4, 4), "x.npz": _npz(a=np.zeros((5, 4)), b=np.ones((5, 4)))}, 2,
     "holds 2 arrays (a, b) and none named 'input'"),
    ("nir-input-rate-above-1", ["simulate", "nir", "{tmp}/g.nir", "--input-rate", "5"],
     {"g.nir": _nir(4, 4)}, 2, "a probability must be in [0, 1]"),
    ("nir-1000-bit-weights", ["nir", "import", "{tmp}/g.nir", "--weight-bits", "1000",
                              "--out", "{tmp}/o"], {"g.nir": _nir(4, 4)}, 2,
     "weight_bits must be an integer in 2 .. 32"),
    ("nir-1000-bit-state", ["nir", "import", "{tmp}/g.nir", "--v-frac-bits", "1000",
                            "--out", "{tmp}/o"], {"g.nir": _nir(4, 4)}, 2,
     "v_frac_bits must be an integer in 2 .. 40"),
    # --- misleading output (class 7)
    ("waves-start-after-the-run", ["simulate", "izhikevich", "--engine", "amaranth",
                                   "--neurons", "8", "--duration-ms", "1", "--waves", "{tmp}/w",
                                   "--waves-start", "100000"], {}, 2,
     "starts at tick 100000, after the run's last tick 15"),
    ("filter-check-unstable", ["filter", "check", "--b", "1", "--a", "1", "-1.919", "0.91"], {},
     2, "is unstable: pole z = 1.06"),
    # --- valid input accepted
    ("nir-export-of-a-shipped-example", ["nir", "export", "examples/skin_3x3.toml", "--out",
                                         "{tmp}/skin.nir"], {}, 0, ""),
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


@pytest.mark.timeout(120)
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
                                         "lif-quantization-1e5", "sweep-1e9-ms",
                                         "fanout-1e8-afferents", "nir-1e12-steps",
                                         "scene-label-100k-chars")]


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


# --- the API's probe-style inputs (issue 39, class 6): a ValueError (or the transport's error)
# naming the input, never a silent result

def _spike_file_with_neuron_outside(path):
    from cuneate.sim.spikes import write_spikes
    write_spikes(path, [[1.0]], "fixed", 10.0, ["p"])
    z = dict(np.load(path))
    z["neuron"] = np.array([5])
    np.savez(path, **z)


def _load_spikes(content):
    def probe(tmp_path):
        from cuneate.sim.spikes import load_spikes
        p = tmp_path / "s.npz"
        if callable(content):
            content(p)
        else:
            p.write_bytes(content)
        load_spikes(p)
    return probe


def _driver(**kw):
    from cuneate.hdl.izhikevich import IzhikevichConfig
    from cuneate.sim.host.driver import AfferentEncoding, FbgDriver
    return FbgDriver(IzhikevichConfig(n_neurons=8), [AfferentEncoding(mode="SA")], **kw)


def _twin_run(n):
    def probe(tmp_path):
        from cuneate.hdl.izhikevich import IzhikevichConfig
        from cuneate.sim.izhikevich.engines import TwinTransport
        tr = TwinTransport()
        tr.open(IzhikevichConfig(n_neurons=8))
        tr.run(n)
    return probe


API_CASES = [
    ("load_spikes-empty-file", _load_spikes(b""), ValueError, "not a readable spike file"),
    ("load_spikes-incomplete", _load_spikes(
        lambda p: np.savez(p, format=np.array("cuneate-spikes/1"))), ValueError,
     "a cuneate-spikes/1 file without engine"),
    ("load_spikes-neuron-outside-its-table", _load_spikes(_spike_file_with_neuron_outside),
     ValueError, "a spike of neuron 5, outside its table of 1 neurons"),
    ("AfferentEncoding-nan-gain", lambda tmp_path: __import__(
        "cuneate.sim.host.driver", fromlist=["x"]).AfferentEncoding(mode="SA", gain=math.nan),
     ValueError, "gain must be a finite number"),
    ("AfferentEncoding-inf-gain", lambda tmp_path: __import__(
        "cuneate.sim.host.driver", fromlist=["x"]).AfferentEncoding(mode="SA", gain=math.inf),
     ValueError, "gain must be a finite number"),
    ("FbgDriver-rate-0", lambda tmp_path: _driver(fs_hz=0), ValueError,
     "fs_hz must be a finite rate > 0 Hz"),
    ("FbgDriver-complex-shifts", lambda tmp_path: _driver().currents(np.zeros((3, 1)) + 1j),
     ValueError, "d_lambda holds complex numbers"),
    ("TwinTransport-negative-sweeps", _twin_run(-5), "TransportError",
     "fixed: cannot run -5 sweeps"),
    ("TwinTransport-fractional-sweeps", _twin_run(2.5), "TransportError",
     "fixed: cannot run 2.5 sweeps"),
    ("LifConfig-leak-that-never-acts", lambda tmp_path: __import__(
        "cuneate.hdl.lif", fromlist=["x"]).LifConfig(
        form="discrete", param_sets=[{"alpha": 1 - 1e-9, "u_th": 1.0}]), "ConfigError",
     "so it never acts: the neuron would be an IF neuron"),
]


@pytest.mark.parametrize("probe, error, fragment", [c[1:] for c in API_CASES],
                         ids=[c[0] for c in API_CASES])
def test_api_bad_input_raises_naming_it(tmp_path, probe, error, fragment):
    with pytest.raises(Exception) as info:
        probe(tmp_path)
    assert (type(info.value).__name__ == error if isinstance(error, str)
            else isinstance(info.value, error)), info.value
    assert fragment in str(info.value)


def test_frame_decoder_counts_garbage_without_raising():
    from cuneate.hdl.link.codec import FrameDecoder
    d = FrameDecoder()
    rng = np.random.default_rng(3)
    got = d.feed(rng.integers(0, 256, 65536, dtype=np.uint8).tobytes())
    assert got == [] and sum(d.errors.values()) > 100


# --- environment failures (class 4): one line naming the path or the resource

def test_closed_stdout_is_not_an_error():
    r = subprocess.run(["bash", "-o", "pipefail", "-c",
                        f"{sys.executable} -m cuneate.sim.cli run --list-examples | head -1"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stderr == "" and r.stdout.startswith("(default: run")


@pytest.mark.parametrize("exc, fragment", [
    (OSError(28, "No space left on device", "/data/out/run.json"),
     "cuneate simulate izhikevich: No space left on device: '/data/out/run.json'"),
    (MemoryError("Unable to allocate 21.8 TiB"),
     "cuneate simulate izhikevich: out of memory (Unable to allocate 21.8 TiB): this process "
     "can get about"),
], ids=["disk-full", "memory"])
def test_environment_failure_is_one_line_naming_it(monkeypatch, capsys, exc, fragment):
    from cuneate.sim import cli

    def failing(args):
        raise exc
    real = cli.build_parser
    monkeypatch.setattr(cli, "build_parser", lambda: _rebind(real(), failing))
    assert main(["simulate", "izhikevich", "--duration-ms", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(fragment), err


#: a progress line: its time stamp, then the step
PROGRESS = re.compile(r"^\[\d\d:\d\d:\d\d\] ")


def test_a_proof_out_of_memory_says_so():
    """SymbiYosys under an address-space limit its tools cannot work in: one line that says
    memory ran out (it was exit 2 with SymbiYosys's raw ERROR)."""
    script = textwrap.dedent("""
        import resource, sys
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
        from cuneate.sim.cli import main
        sys.exit(main(["prove", "banked", "--neurons", "8", "--bank-depth", "4"]))
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=300)
    # the progress lines of the run (time-stamped) stand before the one error line
    lines = [ln for ln in r.stderr.strip().splitlines() if not PROGRESS.match(ln)]
    assert r.returncode == 2 and len(lines) == 1, r.stderr[-2000:]
    assert lines[0].startswith("cuneate prove banked: the proof ran out of memory (")


# --- one run folder, one run (class 5)

def test_a_second_run_into_a_folder_in_use_is_refused(tmp_path, capsys):
    from cuneate.sim.cli.options import claim_output
    out = tmp_path / "o"
    out.mkdir()
    (tmp_path / "s.toml").write_text(scene(""))
    argv = ["run", str(tmp_path / "s.toml"), "--out", str(out)]
    with claim_output(out, "cuneate run"):          # a first run, still working
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "is in use by another run (pid " in err[0], err
        assert (out / "INCOMPLETE").exists()
    assert not (out / "INCOMPLETE").exists()        # the first finished
    assert main(argv) == 0 and not (out / "INCOMPLETE").exists()


def test_a_failed_run_leaves_its_folder_marked(tmp_path):
    from cuneate.sim.cli.options import claim_output
    with pytest.raises(RuntimeError):
        with claim_output(tmp_path, "cuneate run"):
            (tmp_path / "partial.png").write_bytes(b"x")
            raise RuntimeError("the engine stopped")
    text = (tmp_path / "INCOMPLETE").read_text()
    assert "did not finish (stopped by RuntimeError: the engine stopped)" in text


# --- output that said what did not happen (class 7)

def test_a_waveform_window_past_the_run_ends_with_it(tmp_path, capsys):
    rc = main(["simulate", "izhikevich", "--engine", "amaranth", "--neurons", "8",
               "--duration-ms", "1", "--waves", str(tmp_path), "--waves-ticks", "100000",
               "--json"])
    w = json.loads(capsys.readouterr().out)["waves"]
    assert rc == 0 and (w["start_tick"], w["ticks"]) == (0, 16)      # the run's 16 ticks
    assert w["time_axis"].startswith("time axis: 1000 ns a clock cycle (the amaranth "
                                      "simulation's clock; the configured clock is")


def test_agreement_figures_tell_a_difference_from_none():
    from cuneate.sim.report import fmt_distinct
    assert [fmt_distinct(x) for x in (1.0, 0.0, 0.99975, 1.2e-4, 0.5, None)] == \
        ["1", "0", "0.99975", "0.00012", "0.500", "-"]


def test_boards_bounds_are_labelled_neurons_and_the_fmax_megahertz(capsys):
    assert main(["boards"]) == 0
    head, ulx3s = capsys.readouterr().out.splitlines()[:2]
    assert "block-RAM bound (neurons)" in head and "logic x fmax bound (neurons)" in head
    # the logic bound is neurons at the measured fmax, in MHz (it once read "fmax 212100")
    assert re.search(r" \d[\d ]* \(at \d+(\.\d+)? MHz\) ", ulx3s), ulx3s


def test_a_decay_near_1_is_printed_to_its_digits(tmp_path, capsys):
    _nir(4, 4, tau=1e4)(tmp_path / "g.nir")           # alpha = 1 - 1e-8 (was "1 -> 1")
    assert main(["-q", "nir", "import", str(tmp_path / "g.nir"), "--out",
                 str(tmp_path / "o")]) == 0
    assert "decay   1 - 1e-08 -> 1 - 1e-08" in capsys.readouterr().out


def test_a_pulse_report_says_only_what_it_computed(tmp_path, capsys):
    """Per-trial features: no published per-ISI row was computed, so neither the page nor the
    printed lines speak of one, and trials are pulses, not grasps."""
    from cuneate.sim.scenes import example_path
    text = example_path("pulse_amplitudes").read_text().replace("trials = 8", "trials = 4") \
        .replace("cv_folds = 8", "cv_folds = 4").replace('engines = ["golden", "fixed"]',
                                                         'engines = ["golden"]')
    (tmp_path / "s.toml").write_text(text)
    assert main(["-q", "run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    page = (tmp_path / "o" / "index.html").read_text()
    summ = json.loads((tmp_path / "o" / "run.json").read_text())
    assert "published" not in out and "published protocol" not in page
    assert "per-pulse decision" in out and "what the system decides per pulse" in page
    assert "grasp" not in out and "grasp" not in page.split("<h2>What ran")[0]
    assert summ["accuracy_is"].startswith("balanced accuracy of the per-pulse decision")
    assert summ["decoded"]["golden"]["protocols"][0]["name"] == "pulse-grouped, per pulse"
