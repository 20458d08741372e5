"""Afferent scenes with the channel fan-out (``hardware.fanout = true``): the channels the host
streams and the table the chip holds give every afferent the current the host-side front end
gives it, within the fan-out's derived bound; the fixed and board engines run it spike for
spike alike; what cannot run it is refused in one line; the whole-hand example's link carries
channels."""

import numpy as np
import pytest

from cuneate.golden.fanout import fanout_currents
from cuneate.hdl.fanout import FanoutTwin
from cuneate.sim import cli
from cuneate.sim.fanout.scene import channel_plan
from cuneate.sim.host.uart import link_budget
from cuneate.sim.scenes import afferent, example_path, load_scene, parse_scene

SLIDE = example_path("slide_texture.toml").read_text()


def _scene(duration_ms=120, trials=1, engines='["golden", "fixed"]'):
    text = (SLIDE.replace("[hardware]", "[hardware]\nfanout = true")
            .replace("duration_ms = 500", f"duration_ms = {duration_ms}")
            .replace("trials = 8", f"trials = {trials}")
            .replace('engines = ["golden", "fixed"]', f"engines = {engines}"))
    return parse_scene(text, "slide_fanout.toml")


def _plan(scene):
    _, _, traces, infos, _ = afferent.synthesize(scene)
    nn = afferent.build_neurons(scene, len(traces))
    cfg = afferent.core_config(scene)
    drv, currents, _ = afferent.front_end(scene, nn, traces, infos, cfg)
    return channel_plan(scene, nn, traces, infos, cfg, drv), nn, currents


def test_the_channels_and_the_table_give_the_front_ends_currents():
    scene = _scene(trials=2)
    plan, nn, currents = _plan(scene)
    fc = plan.config
    # one shift and one band-passed channel per grating and trial; every afferent listens
    assert [k for _, _, k in plan.channels].count("band") == 2 * 3 * 2
    assert fc.n_channels == 2 * 3 * 2 * 2 and fc.n_neurons == len(nn) == currents.shape[1]
    twin = FanoutTwin(fc)
    got = np.empty_like(currents)
    for j, row in enumerate(plan.raw):
        twin.samples[:] = row
        got[j] = fc.I.to_float(twin.run()[0])
    assert sum(twin.clamp_counts.values()) == 0
    # against the host front end's float currents, away from the SA gates' thresholds
    x = plan.samples
    near = np.zeros_like(got, dtype=bool)
    for i, (c, th) in enumerate(zip(fc.channels_, fc.thresholds_)):
        if th is not None:
            near[:, i] = np.abs(x[:, c] - th) <= fc.S.lsb
    err = np.abs(got - currents)
    assert np.all(err[~near] <= fc.sample_bound(x)[~near])
    assert np.count_nonzero(currents) > currents.size // 4
    # and against the fan-out's own golden model on the same float samples
    th = [np.nan if t is None else t for t in fc.thresholds_]
    gold = fanout_currents(x, fc.channels_, fc.gain, ["none" if t is not None else "abs"
                                                       for t in fc.thresholds_], th)
    assert np.allclose(gold, currents, rtol=1e-9, atol=1e-9)


@pytest.mark.long
def test_fixed_and_board_run_the_fanout_spike_for_spike():
    run = afferent.run(_scene(duration_ms=150, engines='["fixed", "board"]'))
    a, b = run.spikes["fixed"], run.spikes["board"]
    assert sum(map(len, a)) > 20
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    fan = [blk for blk in run.ran["blocks"] if blk["block"] == "channel_fanout"]
    # 3 textures x 2 gratings, a shift and a band-passed channel each; an SA and an FA
    # afferent a grating
    assert fan and fan[0]["n_channels"] == 12 and fan[0]["n_neurons"] == 12
    c = run.counters["board"]
    assert c["frames_lost"] == 0 and c["line_framing_errors"] == 0
    assert run.counters["fixed"]["fanout_current_high"] == 0
    # the budget counts channels of the sample format, not afferent currents
    assert c["link_budget"]["worst_case"]["words_per_sample"] == 12


def test_engines_that_do_not_run_the_fanout_are_refused(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(SLIDE.replace("[hardware]", "[hardware]\nfanout = true")
                 .replace('engines = ["golden", "fixed"]', 'engines = ["fixed", "icarus"]'))
    assert cli.main(["run", str(p), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "run.engines[1]: engine 'icarus' does not run the channel" in err[0]
    # the same engine asked for on the command line
    p.write_text(SLIDE.replace("[hardware]", "[hardware]\nfanout = true"))
    assert cli.main(["run", str(p), "--engines", "fixed,verilator", "-q",
                     "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"cuneate run: {p}: hardware.fanout: engine 'verilator' does not run the "
                   f"channel fan-out (engines that do: golden, fixed, board, axi)"]


def test_the_whole_hand_streams_channels_not_afferents():
    scene = load_scene(example_path("whole_hand.toml"))
    assert scene["hardware"]["fanout"] and scene["sensor"]["channels"] == 24
    plan, nn, _ = _plan(scene)
    fc = plan.config
    assert (fc.n_channels, fc.n_neurons) == (12 * 48, 12 * 192) == (576, 2304)
    # each SA population gated at its own threshold (pm), the FA afferents ungated
    gates: dict = {}
    for pop, th in zip(nn.population, fc.to_kwargs()["threshold"]):
        gates.setdefault(pop, set()).add(th)
    assert gates == {"sa_low": {0.25}, "sa_mid": {0.5}, "sa_high": {1.0}, "sa_top": {2.0},
                     "fa_low": {None}, "fa_mid": {None}, "fa_high": {None}, "fa_top": {None}}
    # one hand (a trial: 48 channels, 192 afferents) at the scene's rates: its channels of 16
    # bits fit a 3 Mbaud line, every afferent's 18-bit current does not
    ch = link_budget(192, fc.S.width, 1000.0, 16000.0, 0.0, words_per_sample=48)
    cur = link_budget(192, fc.I.width, 1000.0, 16000.0, 0.0)
    assert ch["in_bytes_per_s"] * 3 < cur["in_bytes_per_s"]
    fits = {r["baud"]: r["real_time"] for r in ch["rows"]}
    assert fits == {115_200: False, 3_000_000: True}
    assert not {r["baud"]: r["real_time"] for r in cur["rows"]}[3_000_000]


def whole_hand_slice():
    """The whole hand's board slice: one grasp per material and the six fingertip gratings
    (0-5) of every population, 192 afferents from 48 channels, and three cuneate neurons a
    hand over them (the full scene's bursts pass the link's 79 spikes a batch: see
    docs/boards.md)."""
    text = example_path("whole_hand.toml").read_text().replace("trials = 3", "trials = 1")
    text = text.replace("size = 6", "size = 3\ngratings = [0, 1, 2, 3, 4, 5]")
    for enc in ('encoding = "SA"', 'encoding = "FA"'):
        text = text.replace(enc, enc + "\ngratings = [0, 1, 2, 3, 4, 5]")
    return parse_scene(text.replace('engines = ["golden", "fixed"]',
                                    'engines = ["fixed", "board"]'), "whole_hand_slice.toml")


# the release lane: the fan-out on board equals fixed spike for spike in CI
# (test_fixed_and_board_run_the_fanout_spike_for_spike); this is the whole hand's size
@pytest.mark.release
def test_the_whole_hand_slice_on_board_equals_fixed():
    run = afferent.run(whole_hand_slice())
    a, b = run.spikes["fixed"], run.spikes["board"]
    assert len(a) == 192 and sum(map(len, a)) > 1000
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    # the cuneate layer ran on chip behind the fan-out: its trains equal the fixed twin's
    la, lb = run.layer["spikes"]["fixed"], run.layer["spikes"]["board"]
    assert len(la) == 12 and sum(map(len, la)) > 20
    assert all(np.array_equal(x, y) for x, y in zip(la, lb))
    fan = next(blk for blk in run.ran["blocks"] if blk["block"] == "channel_fanout")
    assert (fan["n_channels"], fan["n_neurons"]) == (48, 192)
    c = run.counters["board"]
    assert c["frames_lost"] == 0 and c["spikes_counted"] == c["spikes"]
    rows = {r["baud"]: r for r in c["link_budget"]["measured"]["rows"]}
    assert rows[3_000_000]["real_time"] and not rows[115_200]["real_time"]
