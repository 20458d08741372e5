"""The stimulus of an afferent scene (grasp, slide, pulses or a recorded trace): every trial's
FBG traces with the sensor effects the scene names, and nothing else."""

from __future__ import annotations

import numpy as np

from ...golden.tactile import (MATERIALS, GraspSpec, Material, Pad, PulseSpec, SlideSpec,
                              apply_effects, sensor_effects, synthesize_grasp, synthesize_pulse,
                              synthesize_slide)
from .scene import Scene

__all__ = ["synthesize", "merge_counts"]


def _material(m) -> Material:
    if isinstance(m, str):
        return MATERIALS[m]
    return Material(m["name"], m["young_MPa"] * 1e6, m["poisson"], m["diameter_mm"] * 1e-3,
                    m["height_mm"] * 1e-3)


def merge_counts(agg: dict, counts: dict) -> None:
    """Add one trial's effect counts into ``agg`` (integers summed, floats their maximum)."""
    for e, cnt in counts.items():
        a = agg.setdefault(e, {})
        for k, v in cnt.items():
            if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
                a[k] = a.get(k, 0) + int(v)
            elif isinstance(v, float):
                a[k] = max(a.get(k, v), v)


def synthesize(scene: Scene):
    """Traces for every trial: ``(classes, trial_class, traces, info, effect_counts)``."""
    st, sen, sc = scene["stimulus"], scene["sensor"], scene["scene"]
    rng = np.random.default_rng(sc["seed"])
    fs = sen["sample_rate_hz"]
    classes = scene.classes()
    trial_class, traces, infos = [], [], []
    effect_params = {e: sen[e] for e in sen["effects"] if e != "strain"}
    counts_all: dict = {}
    if st["kind"] == "recorded":
        from ..host.traces import TraceError, load_trace
        tr = load_trace(st["file"], time_key=st["time_key"], data_key=st["data_key"],
                        struct=st["struct"] or None, time_unit=st["time_unit"],
                        shift_unit=st["shift_unit"], expect_fs_hz=fs,
                        channels=sen["channels"])
        x = tr.d_lambda_nm
        big = np.abs(x) >= sen["lambda_B_nm"]
        if big.any():
            r, c = (int(v) for v in np.argwhere(big)[0])
            raise TraceError(f"{st['file']}: row {r}, grating {c}: a shift of {x[r, c]:.3g} nm is "
                             f"not a Bragg shift of a {sen['lambda_B_nm']:g} nm grating (check "
                             f"stimulus.shift_unit)")
        # the sensor effects the scene lists act on the recorded shifts too
        x, counts = sensor_effects(x, sen["effects"], effect_params, rng, fs,
                                   sen["lambda_B_nm"])
        return classes, [classes[0]], [x], [tr.info], counts
    for c, cls in enumerate(classes):
        for t in range(sc["trials"]):
            if st["kind"] == "grasp":
                spec = GraspSpec(
                    velocity_m_per_s=st["velocity_mm_per_s"] * 1e-3,
                    pad=Pad(st["pad_young_MPa"] * 1e6, st["pad_area_mm2"] * 1e-6,
                            st["pad_thickness_mm"] * 1e-3, st["contact_length_mm"] * 1e-3),
                    coupling_microstrain_per_N=tuple(st["coupling_microstrain_per_N"]),
                    stop_nm=st["stop_nm"], contact_ms=st["contact_ms"],
                    duration_ms=sc["duration_ms"], fs_hz=fs,
                    spread_velocity=st["spread_velocity"], spread_pad=st["spread_pad"],
                    spread_young=st["spread_young"], spread_coupling=st["spread_coupling"])
                strain, info = synthesize_grasp(_material(st["materials"][c]), spec, rng,
                                                sen["lambda_B_nm"])
            elif st["kind"] == "pulses":
                spec = PulseSpec(start_ms=st["pulse_start_ms"], width_ms=st["pulse_width_ms"],
                                 edge_ms=st["pulse_edge_ms"],
                                 coupling_microstrain_per_N=tuple(
                                     st["coupling_microstrain_per_N"]),
                                 duration_ms=sc["duration_ms"], fs_hz=fs,
                                 spread_force=st["spread_force"])
                strain, info = synthesize_pulse(spec, rng, st["pulse_amplitudes_N"][c])
            else:
                spec = SlideSpec(speed_m_per_s=st["speed_mm_per_s"] * 1e-3,
                                 depth_microstrain=st["depth_microstrain"],
                                 normal_force_N=st["normal_force_N"], ramp_ms=st["ramp_ms"],
                                 coupling_microstrain_per_N=st["slide_coupling_microstrain_per_N"],
                                 spacing_m=st["spacing_mm"] * 1e-3, n_gratings=sen["channels"],
                                 duration_ms=sc["duration_ms"], fs_hz=fs,
                                 spread_speed=st["spread_speed"],
                                 spread_force=st["spread_force"])
                strain, info = synthesize_slide(spec, rng, st["periods_mm"][c] * 1e-3)
            tr = apply_effects(strain, sen["effects"], effect_params, rng, fs,
                               sen["lambda_B_nm"])
            merge_counts(counts_all, tr.effect_counts)
            trial_class.append(cls)
            traces.append(tr.d_lambda_nm)
            infos.append(info)
    return classes, trial_class, traces, infos, counts_all
