"""A block behind a bus face on a cocotb simulator, checked against its twin: :func:`run_face`
builds the top (:class:`~cuneate.hdl.axi.AxiTop` or
:class:`~cuneate.hdl.wishbone.WishboneTop`), plays a schedule through the bench
(:mod:`cuneate.sim.axi.bench`, cocotbext-axi and cocotbext-wishbone bus models) and
:func:`check_face` compares what came back with :func:`reference`: the block's bit-exact
payload twin (:meth:`~cuneate.hdl.lib.payload.PayloadSpec.twin`, the model the UART link's
protocol model drives too) fed the same schedule.

A *schedule* is ``{sweep: [(first, raw values), ...]}``: each entry one burst, in effect from
that sweep (the face's write rule)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...hdl.flow.verilog import verilog_text
from ...hdl.lib.regmap import COUNTERS, MAP_BYTES, REGISTERS, constants, stream_format
from ..engines.cocotb import run_cocotb

__all__ = ["reference", "check_packets", "pack_write", "run_face", "check_face", "FaceRun"]


@dataclass
class FaceRun:
    """What the twin says a run must give: the ids per sweep and the sticky clamp flags."""

    sweeps: list
    clamp_flags: int


def reference(spec, schedule: dict, n_sweeps: int) -> FaceRun:
    """The ids each of ``n_sweeps`` sweeps sends, sorted, and the clamp flags after them, on
    the twin of ``spec``."""
    twin = spec.twin()
    out = []
    for k in range(n_sweeps):
        for first, raw in schedule.get(k, []):
            for i, v in enumerate(raw):
                twin.write(first + i, int(v))
            twin.end_burst()
        out.append(sorted(int(i) for i in twin.sweep()))
    return FaceRun(out, twin.clamp_flags())


def pack_write(info, addr: int, raw: int) -> int:
    """A write beat's TDATA: ``raw`` sign-extended in the low field, ``addr`` in the high."""
    F = 8 * stream_format(info)["write_field_bytes"]
    return (int(raw) & ((1 << F) - 1)) | (int(addr) << F)


def check_packets(info, packets, expect: list[list[int]]) -> int:
    """``packets`` (one per sweep: ``[(tdata, tuser), ...]`` of its beats, the last carrying
    TLAST) against ``expect``: the sweep numbers, the ids, and an empty sweep's lone marker.
    Returns the spikes compared; raises ``AssertionError`` naming the first difference."""
    sf = stream_format(info)
    F, sw = 8 * sf["spike_field_bytes"], info.sweep_width
    assert len(packets) == len(expect), f"{len(packets)} sweeps sent, {len(expect)} run"
    n = 0
    for k, (beats, want) in enumerate(zip(packets, expect)):
        beats = [tuple(b) for b in beats]
        sweeps = {d >> F for d, _ in beats}
        assert sweeps == {k % (1 << sw)}, f"sweep {k}: beats of sweeps {sorted(sweeps)}"
        if not want:
            assert beats == [(sf["marker_id"] | (k % (1 << sw)) << F, 1)], \
                f"sweep {k}: {beats} instead of the empty sweep's marker"
            continue
        assert all(u == 0 for _, u in beats), f"sweep {k}: a marker among spikes"
        got = sorted(d & ((1 << F) - 1) for d, _ in beats)
        assert got == want, f"sweep {k}: ids {got}, the twin's {want}"
        n += len(got)
    return int(n)


def _top(face: str, spec):
    from ...hdl.axi import AxiTop
    from ...hdl.wishbone import WishboneTop
    return {"axi": AxiTop, "wishbone": WishboneTop}[face](spec)


def run_face(simulator: str, spec, face: str, schedule: dict, n_sweeps: int, build_dir: Path,
             seed: int = 1, gaps: float = 0.3, stalls: float = 0.3) -> dict:
    """Play ``schedule`` for ``n_sweeps`` sweeps on ``spec`` (external tick) behind ``face``
    on ``simulator`` with source gaps and sink stalls of these probabilities; the bench's
    report. Icarus 11 gets the yosys-lowered netlist (see
    :func:`~cuneate.hdl.flow.verilog.lowered_verilog`)."""
    top = _top(face, spec)
    info = spec.info
    build_dir = Path(build_dir)
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / f"{face}_top.v"
    src.write_text(verilog_text(top, f"{face}_top", lowered=simulator == "icarus"))
    rows = [[k, [[pack_write(info, first + i, v) for i, v in enumerate(raw)]
                 for first, raw in schedule[k]]] for k in sorted(schedule)]
    cfg = {"face": face, "registers": {r.name: r.offset for r in REGISTERS},
           "schedule": rows, "sweeps": n_sweeps, "seed": seed, "gaps": gaps,
           "stalls": stalls, "patience": 64 * n_sweeps * info.cycles_per_tick,
           "outside": MAP_BYTES, "bad_beat": pack_write(info, info.n_written, 0)}
    return run_cocotb(simulator, [src], f"{face}_top", "cuneate.sim.axi.bench", build_dir,
                      config=cfg, testcase="face").report


def check_face(spec, schedule: dict, n_sweeps: int, report: dict) -> dict:
    """``report`` of :func:`run_face` against the twin: every sweep's ids, the constants,
    the counters (the refused beat of the bench counted, nothing else), the refusals
    answered with an error, the clamp flags as the twin's and cleared over the bus. Returns
    ``{"spikes": compared, "clamp_flags": raised}``; raises ``AssertionError`` on the first
    difference."""
    info = spec.info
    want = reference(spec, schedule, n_sweeps)
    n = check_packets(info, report["packets"], want.sweeps)
    regs = report["registers"]
    for name, value in constants(info).items():
        assert regs[name] == value, f"{name} reads {regs[name]}, the configuration's {value}"
    values = sum(len(raw) for rows in schedule.values() for _, raw in rows)
    bursts = sum(len(rows) for rows in schedule.values())
    expect = {"writes": values, "bursts": bursts + 1, "writes_refused": 1, "spikes": n,
              "sweeps": n_sweeps, "empty_sweeps": sum(not s for s in want.sweeps),
              "ticks": n_sweeps, "tick_overruns": 0}
    got = {name: regs[name.upper()] for name, _ in COUNTERS}
    assert got == expect, f"counters {got}, expected {expect}"
    assert report["responses"] == {"id": [regs["ID"], 0], "write_to_const": 2,
                                   "read_outside": 2}, report["responses"]
    assert report["clamps"] == want.clamp_flags, \
        f"clamp flags {report['clamps']:#x}, the twin's {want.clamp_flags:#x}"
    assert report["cleared"] == 0 and regs["CLAMP_FLAGS"] == 0
    assert regs["STATUS"] & 0xC0 == 0, f"STATUS {regs['STATUS']:#x}: a spike or tick lost"
    return {"spikes": n, "clamp_flags": want.clamp_flags}

