"""Channels in, fanned out on chip into the afferent -> cuneate network: the board top
:class:`~cuneate.hdl.link.LinkedTop` of the fan-out in front of the network compiled by Verilator behind the simulated serial
line, driven by the host's transport with raw channel samples. The spikes of both populations
equal a reference built from the twins alone (the fan-out twin's currents into the network's
twin, each sample in effect from its sweep), the link carried channels, not afferents; a tick
due during a frame's writes or the fan-out's run waits for the last current; the pty board
serves the top; and it elaborates in a board's platform with its PLL, UART and LEDs."""

import numpy as np
import pytest

from cuneate.hdl.fanout import FanoutConfig, FanoutTwin
from cuneate.hdl.lib.fixed import QFormat
from cuneate.hdl.lib.config import ConfigError
from cuneate.hdl.lib.payload import payload_spec
from cuneate.hdl.link import LinkConfig, LinkedTop
from cuneate.hdl.link.codec import MSG_WRITE, FrameDecoder, write_message
from cuneate.hdl.network import NetworkConfig, NetworkTwin, REPORT_SETTLE
from cuneate.sim.link.engines import BoardTransport, board_link
from cuneate.sim.link.faults import Recorder
from host_stream import stream_samples

# 20 afferents on 4 channels; afferents 2 .. 17 drive 3 cuneate neurons at 4 kHz
N, C, M, S, F = 20, 4, 3, 16, 2
_rng = np.random.default_rng(5)
FAN = FanoutConfig(n_channels=C, channel=[i % C for i in range(N)],
                   gain=[float(g) for g in np.round(_rng.uniform(6, 30, N), 2)],
                   rectify=["positive", "abs", "none", "positive"] * (N // 4),
                   threshold=[0.5 if i % 5 == 0 else None for i in range(N)],
                   sample_max=4.0, sample_width=12)
NETWORK = NetworkConfig(n_afferents=N, first_source=F,
                        detector=dict(n_sources=S, n_targets=M,
                                      delays_ticks=_rng.integers(0, 6, (M, S)).tolist(),
                                      weights=np.round(_rng.uniform(4, 10, (M, S)), 2).tolist(),
                                      max_delay_ticks=8),
                        clock_hz=4e3 * 200, update_hz=4e3, tick_source="external")
EVERY = 4                                          # sweeps a sample
N_SAMPLES = 80


def samples(n: int, seed: int = 2) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return FAN.S.to_raw(rng.uniform(-1.5, 3.0, (n, C)))


def reference(raw: np.ndarray, n_ticks: int):
    """(tick, spike id) of every spike of both populations, afferent ``i`` as ``i`` and
    cuneate ``j`` as ``N + j``: the fan-out twin's currents into the network's twin from each
    sample's sweep (the tick the twin returns a spike at is the sweep the link reports)."""
    fan, net = FanoutTwin(FAN), NetworkTwin(NETWORK)
    out = []
    for t in range(n_ticks):
        if t % EVERY == 0 and t // EVERY < len(raw):
            fan.samples[:] = raw[t // EVERY]
            net.core.I[:] = fan.run()[0]
        aff, cun = net.tick()
        out += [(t, int(i)) for i in np.flatnonzero(aff)]
        out += [(t, N + int(j)) for j in np.flatnonzero(cun)]
    return sorted(out), fan.clamp_counts


@pytest.mark.parametrize("ahead", [True, False], ids=["writes-ahead", "lockstep"])
def test_the_board_with_the_fanout_network_equals_the_twins(ahead):
    raw = samples(N_SAMPLES)
    n_ticks = len(raw) * EVERY
    want, clamps = reference(raw, n_ticks)
    rec = Recorder()
    tr = BoardTransport(fanout=FAN, ahead=ahead, corrupt_host=rec)
    got, counters, figures = stream_samples(tr, NETWORK, raw, EVERY)
    print(f"\n{'ahead' if ahead else 'lockstep'}: {figures}; "
          f"{sum(1 for _, i in want if i < N)} afferent and "
          f"{sum(1 for _, i in want if i >= N)} cuneate spikes")
    # both populations fire (the cuneate neurons too), the board's spikes are the twins'
    assert sum(1 for _, i in want if i < N) > 50
    assert sorted({i - N for _, i in want if i >= N}) == list(range(M))
    assert sorted(zip(got.tick.tolist(), got.neuron.tolist())) == want
    assert tr.spike_ids == N + M and tr.lcfg.n_written == C
    # the link carried the channels: one frame of C samples a sample, nothing lost
    assert counters["currents_sent"] == C * len(raw) and counters["write_frames_sent"] == len(raw)
    assert counters["device_frames_ok"] == counters["frames_sent"] - 2
    assert counters["device_late_writes"] == 0 and figures["framing_errors"] == 0
    assert counters["spikes"] == len(want)
    writes = [m for m in FrameDecoder().feed(bytes(rec.data)) if m.type == MSG_WRITE]
    assert [(m.tick, m.payload) for m in writes] == [
        (k * EVERY, write_message(0, k * EVERY, 0, row, FAN.S.width).payload)
        for k, row in enumerate(raw)]
    assert figures["bytes_to_device"] == len(rec.data)
    assert sum(clamps.values()) == 0


def test_the_board_sizes_a_tick_for_the_writes_the_run_and_the_network():
    lc = board_link(NETWORK, fanout=FAN)
    net = lc.payload.config
    assert lc.fanout.to_kwargs() | {"clock_hz": 0} == FAN.to_kwargs() | {"clock_hz": 0}
    assert lc.n_written == C and lc.current_width == FAN.S.width
    assert lc.n_neurons == N and lc.n_spike_ids == N + M and lc.batch_sweeps == 4
    work = net.cycles_needed + REPORT_SETTLE + N + M + C + FAN.cycles_per_run + 16
    assert net.cycles_per_tick >= work
    same = {"clock_hz": 0}
    assert net.to_kwargs() | same == NETWORK.to_kwargs() | same
    # a fan-out of fewer afferents is padded with idle ones to the network's
    short = FanoutConfig(n_channels=C, channel=[0, 1, 2, 3] * 4, gain=[8.0] * 16,
                         sample_max=4.0, sample_width=12)
    lc = board_link(NETWORK, fanout=short)
    assert lc.fanout.n_neurons == N and lc.fanout.gain[16:] == [0.0] * 4


def test_a_fanout_network_refuses_what_it_cannot_join():
    lc = board_link(NETWORK, fanout=FAN)
    net = lc.payload.config
    internal = NetworkConfig(**(net.to_kwargs() | {"tick_source": "internal"}))
    with pytest.raises(ConfigError, match="needs tick_source='external'"):
        LinkConfig(internal, fanout=FAN)
    # a fan-out of more afferents than the network's, or of another current format
    many = FanoutConfig(n_channels=C, channel=[i % C for i in range(24)], gain=[8.0] * 24,
                        sample_max=4.0, sample_width=12)
    with pytest.raises(ConfigError, match="the fan-out feeds 24 afferents in .*; the block "
                                          "behind it takes 20"):
        payload_spec(net, fanout=many)
    wide = FanoutConfig(n_channels=C, channel=[0] * 4, gain=[8.0] * 4, sample_max=4.0,
                        sample_width=12, current_format=QFormat(12, 8))
    with pytest.raises(ConfigError, match="the fan-out feeds 4 afferents in"):
        payload_spec(net, fanout=wide)
    # a fan-out does not feed a fan-out, and an array option is refused for a network
    with pytest.raises(ConfigError, match="a fan-out feeds a block, not another fan-out"):
        payload_spec(payload_spec(net, fanout=FAN), fanout=FAN)
    with pytest.raises(ConfigError, match="a NetworkConfig behind a face takes no n_cores"):
        payload_spec(net, n_cores=2)
    # every message is one line
    with pytest.raises(ConfigError) as err:
        LinkConfig(internal, fanout=FAN)
    assert "\n" not in str(err.value)


def test_the_fanout_network_top_elaborates_for_the_ulx3s():
    """In the ULX3S platform (amaranth's build files, no tools): the PLL, the UART and three
    LEDs, running, overflow and the fan-out's clamp."""
    from cuneate.boards.targets import TARGETS
    from cuneate.boards.top import BoardTop
    t = TARGETS["ulx3s"]
    lc = board_link(NETWORK, fanout=FAN)
    net = lc.payload.config
    plan = t["platform"]().prepare(BoardTop(lc, t["pll"], True), name="top")
    il, lpf = (plan.files[f"top.{x}"] for x in ("il", "lpf"))
    il, lpf = (f.decode() if isinstance(f, bytes) else f for f in (il, lpf))
    assert "EHXPLLL" in il and "uart_0__rx" in lpf and "uart_0__tx" in lpf
    assert [f"led_{i}__io" in lpf for i in range(4)] == [True, True, True, False]


def test_a_tick_due_during_the_writes_or_the_run_waits_for_the_last_current():
    """The link's hold, in the Amaranth simulator over the UART pins: frames whose writes land
    late in a sweep (their ends swept across the last 45 cycles of a 200-cycle sweep, the
    network free-running) have their tick held until the fan-out's last current write (no
    tick from a frame's first channel write to the last current write; the held ones fire in
    that cycle), and the spikes of both populations are still the twins', each sample in
    effect from its sweep. (Without the hold the ticks of the late frames fall inside their
    runs.)"""
    from amaranth.sim import Simulator
    from cuneate.hdl.link.codec import OP_START, control_message, encode_frame
    P, cpb = 200, 4
    net = NetworkConfig(**(NETWORK.to_kwargs() | {"clock_hz": NETWORK.update_hz * P}))
    net = NetworkConfig(**(net.to_kwargs() | {"tick_source": "external"}))
    lc = LinkConfig(net, clocks_per_bit=cpb, batch_sweeps=16, fanout=FAN)
    dut = LinkedTop(lc)
    raw = samples(8, seed=7)
    ticks, runs, spikes, applied = [], [], [], {}
    cyc, first = 0, None

    async def tb(ctx):
        nonlocal cyc, first
        fan, link, nw = dut.payload.fanout, dut.link.payload, dut.payload.inner.network

        async def step(n=1):
            nonlocal cyc, first
            for _ in range(n):
                if ctx.get(link.tick):
                    ticks.append(cyc)
                if ctx.get(link.write.valid) and first is None:
                    first = cyc
                if ctx.get(fan.i_wr_en) and ctx.get(fan.i_wr_addr) == N - 1:
                    runs.append((first, cyc))
                    first = None
                if ctx.get(nw.out_valid) and ctx.get(nw.out_ready):
                    spikes.append((ctx.get(nw.out_tick),
                                   N * ctx.get(nw.out_population) + ctx.get(nw.out_index)))
                await ctx.tick()
                cyc += 1

        async def send(msg):
            for b in encode_frame(msg):
                for bit in [0] + [(b >> i) & 1 for i in range(8)] + [1]:
                    ctx.set(dut.rx, bit)
                    await step(cpb)

        ctx.set(dut.rx, 1)
        await step(20)
        await send(control_message(0, OP_START))
        while not ticks:
            await step()
        g0 = ticks[0]
        for j, row in enumerate(raw):
            msg = write_message(j + 1, 0, 0, row, FAN.S.width)
            dur = len(encode_frame(msg)) * 10 * cpb
            n = (cyc + dur - g0) // P + 1
            at = g0 + n * P + P - 45 + 5 * j          # the frame's end: late in sweep n
            await step(at - dur - cyc)
            applied[n + 1] = row                      # in effect from the next sweep
            await send(write_message(j + 1, n + 1, 0, row, FAN.S.width))
        await step(3 * P)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(tb)
    sim.run()
    assert len(runs) == len(raw)                      # no write refused as late
    t = np.array(ticks)
    assert all(not np.any((t >= a) & (t < b)) for a, b in runs)
    # the held ticks: off the divider's grid, in the cycle of the last current write
    held = [b for a, b in runs if b in ticks and (b - ticks[0]) % P != 0]
    assert len(held) >= 4
    # the twins, each sample from its sweep, over the sweeps whose report is complete
    fan, tw, want = FanoutTwin(FAN), NetworkTwin(net), []
    for k in range(len(ticks) - 1):
        if k in applied:
            fan.samples[:] = applied[k]
            tw.core.I[:] = fan.run()[0]
        aff, cun = tw.tick()
        want += [(k, int(i)) for i in np.flatnonzero(aff)]
        want += [(k, N + int(j)) for j in np.flatnonzero(cun)]
    assert sorted(s for s in spikes if s[0] < len(ticks) - 1) == sorted(want)
    print(f"\n{len(ticks)} ticks, {len(held)} of {len(runs)} held to the last current write, "
          f"{sum(1 for _, i in want if i < N)} afferent and "
          f"{sum(1 for _, i in want if i >= N)} cuneate spikes")
    assert sum(1 for _, i in want if i < N) > 20


def test_the_pty_board_serves_the_fanout_network():
    """The same board top served on a pseudo-terminal (``PtyBoard`` given the network and its
    link) and reached through pyserial by the device path: the twins' spikes of both
    populations."""
    from cuneate.sim.host.uart import UartTransport
    from cuneate.sim.link.pty import PtyBoard
    lc = board_link(NETWORK, fanout=FAN)
    net = lc.payload.config
    raw = samples(30, seed=4)
    n_ticks = len(raw) * EVERY
    want, _ = reference(raw, n_ticks)
    board = PtyBoard(lc)
    try:
        host = UartTransport(board.path, timeout_s=60.0, batch_sweeps=lc.batch_sweeps,
                             spike_ids=lc.n_spike_ids)
        host.open(lc.info.writes())
        for k, row in enumerate(raw):
            host.write_currents(k * EVERY, 0, row)
        host.run(n_ticks)
        got = host.collect()
        host.check()
        host.close()
    finally:
        board.close()
    assert any(i >= N for _, i in want)
    assert sorted(zip(got.tick.tolist(), got.neuron.tolist())) == want
    assert board.totals["bytes_to_device"] == host.bytes_sent
