"""Running the ``cuneate`` command in a test (in process, output captured by ``capsys``)."""

import json

import numpy as np

from cuneate.sim.cli import main


def run_cli(capsys, argv):
    """``(exit code, stdout, stderr)`` of ``cuneate argv``."""
    rc = main(argv)
    out = capsys.readouterr()
    return rc, out.out, out.err


def simulate_json(capsys, block, *args):
    """The JSON of ``cuneate simulate block --json args``, which must exit 0."""
    rc, out, err = run_cli(capsys, ["simulate", block, "--json", *args])
    assert rc == 0, err
    return json.loads(out)


def assert_refused(capsys, argv, match):
    """``cuneate argv`` exits 2 with one line on stderr that says ``match``."""
    rc, out, err = run_cli(capsys, argv)
    assert rc == 2 and match in err and err.count("\n") == 1, err


def python_engine_runs(capsys, block, *args):
    """:func:`simulate_json` of ``block`` on the golden, fixed and amaranth engines, by engine;
    each run's spike times must lie on its update grid (update ``k`` reports at ``(k+1) dt``)."""
    runs = {e: simulate_json(capsys, block, "--engine", e, *args)
            for e in ("golden", "fixed", "amaranth")}
    for r in runs.values():
        for s in r["spikes_ms"]:
            k = np.asarray(s) / r["dt_ms"] - 1
            assert np.allclose(k, np.round(k)) and np.all(k >= 0)
    return runs
