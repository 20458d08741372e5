"""What the iCEBreaker's reduced core costs in accuracy, measured like the core's yardstick:
the four presets x 15 currents (3.5..100 mV/ms), 1 s at 16 kHz, spike trains against float64
Euler, beside float32 Euler and the default 18-bit-operand core."""

from wide_battery import wide_battery

from cuneate.boards.sizing import size_core
from cuneate.boards.targets import TARGETS
from cuneate.golden.metrics import compare_populations
from cuneate.hdl.izhikevich import IzhikevichTwin


def test_icebreaker_core_accuracy_against_float64_and_float32():
    board_core = size_core(TARGETS["icebreaker"])["link"].core
    b = wide_battery()
    g64 = b.g64
    res = {"float32": compare_populations(g64.spikes_ms, b.g32.spikes_ms, 0.0625, 0.005)}
    for label, ow in (("18-bit core", 18), ("iCEBreaker core", board_core.operand_width)):
        cfg = b.config(operand_width=ow)
        res[label] = compare_populations(g64.spikes_ms, IzhikevichTwin(cfg).run(b.cur, 16000),
                                         cfg.dt_ms, 0.005)
    print()
    for k, c in res.items():
        print(f"{k:16s} spikes {c['total_b']:6d} of {c['total_a']}, within +-1 tick "
              f"{c['fraction_within_tick']:.4f}, mean VP {c['mean_vp_distance']:.4f}")
    ice, full = res["iCEBreaker core"], res["18-bit core"]
    assert board_core.operand_width == 16
    # measured: 11315 of 11317 spikes, 0.937 within a tick, mean VP 0.077 (18-bit: 0.972,
    # 0.013; float32: 0.974, 0.012) - the price of 16-bit operands, bounded here
    assert abs(ice["total_b"] - ice["total_a"]) <= 0.001 * ice["total_a"]
    assert ice["fraction_within_tick"] >= 0.92
    assert ice["mean_vp_distance"] <= 0.1
    assert full["fraction_within_tick"] > ice["fraction_within_tick"]
