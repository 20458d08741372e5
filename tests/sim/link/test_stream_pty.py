"""The host side of a real board, without the board: the board top in Verilator served on a
pseudo-terminal (``PtyBoard``) and reached through pyserial by the device path, as a USB serial
adapter is. ``FbgDriver.stream`` over ``UartTransport(path)`` equals the bit-exact twin with
every counter of the transport contract checked; ``cuneate stream ulx3s --port PATH SCENE``
runs a scene end to end and agrees with the fixed engine; a harness that dies is reported on
both sides at once (nothing hangs); missing ports, unknown boards and scenes a board cannot
run are refused in one line."""

import json
import time

import pytest

from cuneate.hdl.izhikevich import IzhikevichConfig
from cuneate.sim.cli import main
from cuneate.sim.host.transport import TransportError
from cuneate.sim.host.uart import UartTransport
from cuneate.sim.link.pty import PtyBoard, PtyBoardError, scene_link
from cuneate.sim.scenes.scene import DEFAULT_SCENE_TOML, load_scene
from host_stream import assert_contract, held_levels as trace, sa_driver, twin_reference

# a small, fast core: 8 neurons, 16 cycles per sweep at 4 kHz (samples at 1 kHz held 4 ticks)
CORE = IzhikevichConfig(n_neurons=8, clock_hz=4e3 * 16, update_hz=4e3, spike_fifo_depth=16)

# the default scene cut to two grasps (one per material) of 200 ms, two gratings each: 4 FA
# neurons, 3200 sweeps
TINY_SCENE = (DEFAULT_SCENE_TOML.replace('name = "four-material grasp"',
                                         'name = "two short grasps"')
              .replace("duration_ms = 700", "duration_ms = 200")
              .replace("trials = 10", "trials = 1")
              .replace('["dragon_skin", "vytaflex", "abs", "aluminium"]',
                       '["dragon_skin", "aluminium"]')
              .replace('kind = "tree"', 'kind = "none"'))


def driver():
    return sa_driver(CORE, 2)


def reference(x):
    return twin_reference(CORE, 2, x)


def test_pyserial_through_the_pty_board_equals_the_twin_with_every_counter_checked():
    x = trace(60)
    ref = reference(x)
    board = PtyBoard(CORE)
    try:
        host = UartTransport(board.path, timeout_s=30.0)
        host.open(CORE)
        got = driver().stream(host, x)
        host.close()
    finally:
        board.close()
    assert not board.serving
    c = assert_contract(got, ref)
    assert c["frames_received"] > 10
    assert all(c[k] == 0 for k in c if k.startswith("rx_"))
    # every byte crossed the pty, both ways, and the simulated line carried exactly those
    t = board.totals
    assert t["bytes_to_device"] == host.bytes_sent > 0
    assert t["bytes_to_host"] == host.bytes_received > 0
    assert t["line"]["bytes_to_device"] == t["bytes_to_device"]
    assert t["line"]["bytes_from_device"] == t["bytes_to_host"]
    assert t["line"]["framing_errors"] == 0 and t["cycles"] > 10_000


def test_a_dead_harness_fails_the_host_at_once_and_is_reported_by_the_board():
    board = PtyBoard(CORE)
    host = UartTransport(board.path, timeout_s=30.0)
    try:
        host.open(CORE)
        host.run(32)
        assert len(host.collect()) == 0            # no current written: no spike, but an answer
        board.serial.kill()
        t0 = time.monotonic()
        with pytest.raises(TransportError, match=f"uart: the line to {board.path} failed"):
            host.run(32)
            host.collect()
        assert time.monotonic() - t0 < 5.0         # the hangup, not the 30 s timeout
    finally:
        host.close()
        with pytest.raises(PtyBoardError, match="the board harness ended"):
            board.close()
    assert not board.serving


@pytest.mark.parametrize("fanout", [False, True], ids=["currents", "channels"])
def test_cuneate_stream_through_the_pty_board_agrees_with_the_fixed_engine(tmp_path, capsys,
                                                                          fanout):
    """The scene's currents to its core, or (``hardware.fanout``) its channels to the board
    top with the fan-out in front of the core."""
    path = tmp_path / "tiny.toml"
    path.write_text(TINY_SCENE.replace("[hardware]", "[hardware]\nfanout = true").replace(
        '"golden", "fixed", "verilator"', '"golden", "fixed"') if fanout else TINY_SCENE)
    out = tmp_path / "out"
    link = scene_link(load_scene(path))
    # 4 channels to 4 afferents, or 4 currents to a core of 8 (its fewest neurons)
    assert (link.fanout is not None) == fanout and link.n_written == (4 if fanout else 8)
    if fanout:      # the core's idle neurons get idle afferents: gain 0 on channel 0
        assert link.fanout.n_neurons == link.core.n_neurons == 8
        assert list(link.fanout.gain[4:]) == [0.0] * 4
    board = PtyBoard(link)
    try:
        # the port named between the board and the scene, as the usage line gives them
        rc = main(["-q", "stream", "ulx3s", "--port", board.path, str(path), "--out", str(out)])
    finally:
        board.close()
    printed = capsys.readouterr().out
    assert rc == 0, printed
    run = json.loads((out / "run.json").read_text())
    agree = run["agreement"]["board vs fixed"]
    assert agree["neurons"] == 4 and agree["spikes_a"] == agree["spikes_b"] > 10
    assert agree["identical_trains"] == 4
    c = run["counters"]["board"]
    assert {k: c[k] for k in ("frames_lost", "overflow", "overrun", "late_writes")} == \
        dict.fromkeys(("frames_lost", "overflow", "overrun", "late_writes"), 0)
    assert c["writes"] == run["counters"]["fixed"]["writes"] > 10
    assert c["spikes"] == c["spikes_counted"] == agree["spikes_a"]
    assert c["line_port"] == board.path
    assert c["line_bytes_to_device"] == board.bytes_to_device > 0
    assert c["line_bytes_from_device"] == board.bytes_to_host > 0
    assert c["line_frames_to_device"] == c["frames_sent"]
    assert (out / "spikes_board.npz").is_file() and (out / "index.html").is_file()
    assert f"board ulx3s on {board.path} (3000000 baud): {agree['spikes_a']} spikes" in printed
    assert "board vs fixed: 4/4 identical trains" in printed


@pytest.mark.parametrize("argv,message", [
    (["stream", "ulx3s", "--port", "/dev/does-not-exist"],
     "cuneate stream: cannot open /dev/does-not-exist: "),
    (["stream", "ulx3s"], "cuneate stream: name the board's serial port: --port PORT"),
    (["stream", "nosuchboard", "--port", "/dev/ttyUSB0"],
     "cuneate stream: unknown board 'nosuchboard'; known: ulx3s, "),
    (["stream", "ulx3s", "--port", "/dev/ttyUSB0", "skin_3x3"],
     "is a skin scene; a board streams afferent scenes"),
], ids=["missing-port", "no-port", "unknown-board", "not-afferent"])
def test_stream_refuses_in_one_line(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err


def test_stream_refuses_a_scene_the_board_cannot_hold(tmp_path, capsys):
    path = tmp_path / "big.toml"
    path.write_text(TINY_SCENE.replace("trials = 1", "trials = 200"))   # 800 neurons
    assert main(["stream", "icebreaker", "--port", "/dev/ttyUSB0", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert "its core of 800 neurons at 16000 Hz does not fit the board: icebreaker:" in err


LAYER_TOML = """
[[population]]
name = "cn"
model = "cuneate"
size = 1
inputs = ["fa"]

[[projection]]
source = "fa"
target = "cn"
weight = 12.0

[hardware]"""


def stream_layered(tmp_path, capsys, text: str):
    """Stream the scene ``text`` (a cuneate layer on board) to the pty board its link gives;
    ``(network, link, printed output, run.json)``, after checking both populations equal
    fixed and every spike arrived."""
    path = tmp_path / "scene.toml"
    path.write_text(text)
    link = scene_link(load_scene(path))
    net = link.payload.inner.config if link.fanout is not None else link.payload.config
    out = tmp_path / "out"
    board = PtyBoard(link)
    try:
        rc = main(["-q", "stream", "ulx3s", "--port", board.path, str(path), "--out",
                   str(out)])
    finally:
        board.close()
    printed = capsys.readouterr()
    assert rc == 0, printed
    run = json.loads((out / "run.json").read_text())
    aff, cn = run["agreement"]["board vs fixed"], run["agreement"]["cn: board vs fixed"]
    assert aff["identical_trains"] == aff["neurons"] == 4 and aff["spikes_a"] > 10
    assert cn["identical_trains"] == cn["neurons"] == 2 and cn["spikes_a"] > 0
    c = run["counters"]["board"]
    assert c["frames_lost"] == 0 and c["spikes"] == aff["spikes_a"] + cn["spikes_a"]
    return net, link, printed.out, run


@pytest.mark.long
def test_cuneate_stream_of_a_scene_with_a_cuneate_layer_agrees_for_both_populations(tmp_path,
                                                                                    capsys):
    """A cuneate layer on the board (the network: currents in, afferent and cuneate
    spikes out in one id space) streamed through the pty: both populations equal fixed."""
    net, link, _, _ = stream_layered(
        tmp_path, capsys, TINY_SCENE.replace("\n[hardware]", LAYER_TOML, 1)
        .replace('"golden", "fixed", "verilator"', '"golden", "fixed"'))
    # two trials of two afferents on a core of 8, a cuneate neuron a trial after them
    assert (net.n_afferents, net.n_targets, link.n_spike_ids) == (8, 2, 10)


@pytest.mark.long
def test_cuneate_stream_plays_the_trials_of_a_one_hand_board_in_turn(tmp_path, capsys):
    """A board built for one of the scene's two grasps (``board_trials = 1``; channels fanned
    out on chip, a cuneate layer: the fan-out in front of the network) streamed in turn through the pty:
    the board's core holds one grasp, the host plays the grasps one after another, and both
    populations equal the fixed engine played the same way."""
    net, link, printed, run = stream_layered(
        tmp_path, capsys, TINY_SCENE.replace("\n[hardware]", LAYER_TOML, 1)
        .replace("[hardware]", "[hardware]\nfanout = true\nboard_trials = 1")
        .replace('"golden", "fixed", "verilator"', '"golden", "fixed"'))
    # one grasp's two FA afferents from its two band-passed channels on a core of 8, and its
    # cuneate neuron
    assert (net.n_afferents, net.n_targets, link.n_written) == (8, 1, 2)
    assert "trials in turn: 1 at a time on the board's core, 2 groups" in printed
    assert run["ran"]["in_turn"]["groups"] == 2
