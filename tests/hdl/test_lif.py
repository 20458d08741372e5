"""LIF core: refusals, twin against the float golden models, RTL against the twin (Amaranth
simulator, every update of every sweep)."""

import math

import numpy as np
import pytest

from cuneate.golden import lif as golden
from cuneate.hdl.lif import (CLAMP_KINDS, PIPELINE_DEPTH, ConfigError, LifConfig, LifCore,
                             LifTwin)
from cuneate.sim.engines.amaranth import simulate, spikes_then_tick, write_currents


# ---------------------------------------------------------------------------------- refusals
@pytest.mark.parametrize("kw, match", [
    ({"decay": "shift"}, "relative error"),                     # tau 20 ms: 2**-8 is 25 % off
    ({"form": "discrete", "param_sets": [{"alpha": 1.0}]}, "rounds to alpha = 1"),
    ({"form": "discrete", "param_sets": [{"alpha": 0.0}]}, "rounds to alpha = 0"),
    ({"param_sets": [{}, {"tau_m_ms": 1e9}]}, "rounds to alpha = 1"),
    ({"weights": np.full((8, 4), 3.0), "weight_frac_bits": 6}, "outside the weight format"),
    ({"weights": np.full((8, 16), 1.0), "acc_bits": 8}, "fan-in sum would overflow"),
    ({"weights": np.full((8, 16), 1.0), "input_limit": (-128, 130)}, "outside input_limit"),
    ({"v_int_bits": 6}, "narrower than the proven state range"),
    ({"v_int_bits": 4, "saturation": "flag"}, "cannot hold the thresholds"),
    ({"param_sets": [{"v_reset": 20.0}]}, "below the threshold"),
    ({"n_neurons": 4}, "n_neurons"),
    ({"current_range": (-200.0, 10.0)}, "inside"),
    ({"weights": np.ones((7, 2))}, "shape"),
])
def test_refusals(kw, match):
    with pytest.raises(ConfigError, match=match):
        LifConfig(**kw)


def test_shift_decay_accepted_when_power_of_two_is_close():
    cfg = LifConfig(decay="shift", param_sets=[{"tau_m_ms": 16.0}])   # dt/tau = 2**-8
    assert cfg.k_shift == [8] and cfg.X is None
    assert abs(cfg.k_q[0] - cfg.k_exact[0]) / cfg.k_exact[0] < 1e-2
    assert cfg.to_dict()["multipliers"] == 0


# ------------------------------------------------------------------------- twin vs golden
def test_twin_matches_golden_spike_trains_continuous():
    """Constant currents: every spike of the exact-integration golden model, at the same
    update (quantization error stays far below one step of v near threshold)."""
    cfg = LifConfig(n_neurons=8)
    cur = np.linspace(20, 120, 8)
    steps = 8000
    got = LifTwin(cfg).run(cur, steps)
    ref = golden.simulate_lif(np.tile(cur, (steps, 1)), cfg.dt_ms, n_neurons=8, record=False)
    for a, b in zip(got, ref.spikes_ms):
        assert len(a) == len(b) and len(a) > 0
        assert np.max(np.abs(a - b)) <= cfg.dt_ms + 1e-12


@pytest.mark.parametrize("rounding", ["nearest", "truncate"])
@pytest.mark.parametrize("form, decay, sets", [
    ("continuous", "multiply", [{"tau_m_ms": 20.0, "t_ref_ms": 2.0},
                                {"tau_m_ms": 10.0, "t_ref_ms": 1.0, "v_rest": -2.0}]),
    ("continuous", "shift", [{"tau_m_ms": 16.0}, {"tau_m_ms": 8.0, "t_ref_ms": 0.5}]),
    ("discrete", "multiply", [{"alpha": 0.389, "u_th": 0.65},
                              {"alpha": 0.9, "u_th": 1.0, "refractory_steps": 2}]),
])
def test_one_step_bound_holds(form, decay, sets, rounding):
    """One fixed update from random states and inputs stays within the derived bound of the
    float golden update, for every update whose spike decision agrees."""
    rng = np.random.default_rng(3)
    n = 4000
    cur_fmt = (8, 8) if form == "continuous" else (4, 12)
    cfg = LifConfig(n_neurons=n, clock_hz=16e3 * n, form=form, decay=decay, param_sets=sets,
                    neuron_sets=list(rng.integers(0, 2, n)), current_format=cur_fmt,
                    rounding=rounding)
    twin = LifTwin(cfg)
    v = rng.integers(cfg.v_floor_raw, max(c.raw for c in cfg.TH), n)
    ref = rng.integers(0, max(cfg.n_ref) + 1, n) * (rng.random(n) < 0.2)
    I = rng.integers(cfg.I.min_raw, cfg.I.max_raw + 1, n)
    sel = np.asarray(cfg.neuron_sets)
    out = twin.update(v, ref, I, None, sel)
    vf, Df = cfg.V.to_float(v), cfg.I.to_float(I)
    gv, gspk, gpre = cfg.golden_step(vf, Df, ref, sel)
    bound = cfg.one_step_bound(vf, Df, sel)
    agree = gspk == out["spike"]
    err = np.abs(cfg.V.to_float(out["v"]) - gv)[agree]
    assert np.all(err <= bound[agree]), float((err / bound[agree]).max())
    th = np.array([s.v_th for s in cfg.sets])[sel]
    assert np.all(np.abs(gpre - th)[~agree] <= bound[~agree] + cfg.V.lsb)
    assert agree.mean() > 0.99 and out["spike"].any() and not out["clamp"].any()


def test_discrete_twin_matches_golden_with_quantized_weights():
    """Weights exactly representable in 8 bits: the twin's spikes equal golden's."""
    rng = np.random.default_rng(5)
    w = rng.integers(-64, 128, (8, 10)) / 128.0
    cfg = LifConfig(form="discrete", weights=w, weight_bits=8, current_format=(4, 12))
    x = rng.random((200, 10)) < 0.3
    got = LifTwin(cfg).run(0.0, 200, x)
    ref = golden.simulate_discrete_lif(x.astype(float), w.T)
    for n in range(8):
        gk = np.flatnonzero(ref.spikes[:, n])
        assert np.array_equal(np.round(got[n] / cfg.dt_ms - 1).astype(int), gk)
    assert ref.spikes.sum() > 50


# --------------------------------------------------------------------------- RTL vs twin
def _run_rtl(cfg: LifConfig, currents, n_sweeps, inputs=None, sel_writes=None, period=None):
    """Simulate the core with external ticks; return per-sweep (v, ref, i, acc, spike, clamp)
    arrays as the ``upd_*`` probe reported them and the spike stream."""
    dut = LifCore(cfg)
    N, F = cfg.n_neurons, cfg.n_inputs
    period = period or N
    rec = {k: np.zeros((n_sweeps, N), dtype=np.int64)
           for k in ("v", "ref", "i", "acc", "spike", "clamp")}
    rec["tr"] = np.zeros((n_sweeps, len(cfg.traces), N), dtype=np.int64)
    stream, done = [], []

    async def bench(ctx):
        ctx.set(dut.spike_ready, 1)
        await write_currents(ctx, dut, cfg.I.to_raw(currents)[:N])
        sweep = -1
        total = n_sweeps * period + PIPELINE_DEPTH + 4
        for c in range(total):
            k = c // period
            ctx.set(dut.tick, int(c % period == 0 and k < n_sweeps))
            if F:
                # spikes for sweep k + 1 arrive during tick k (mid-sweep)
                src = None
                if inputs is not None and c % period == 2 and k + 1 < n_sweeps:
                    srcs = np.flatnonzero(inputs[k + 1])
                    src = srcs
                ctx.set(dut.in_valid, 0)
            if sel_writes and c in sel_writes:
                n, s = sel_writes[c]
                ctx.set(dut.sel_wr_en, 1)
                ctx.set(dut.sel_wr_addr, n)
                ctx.set(dut.sel_wr_data, s)
            else:
                ctx.set(dut.sel_wr_en, 0)
            await ctx.tick()
            rec_sample(ctx)
            if F and inputs is not None and c % period == 2 and k + 1 < n_sweeps:
                ctx.set(dut.tick, 0)
                for s_ in src:
                    ctx.set(dut.in_valid, 1)
                    ctx.set(dut.in_source, int(s_))
                    await ctx.tick()
                    rec_sample(ctx)
                ctx.set(dut.in_valid, 0)

    def rec_sample(ctx):
        if ctx.get(dut.spike_valid):
            stream.append((ctx.get(dut.spike_index), ctx.get(dut.spike_sweep)))
        if ctx.get(dut.sweep_done):
            done.append(ctx.get(dut.sweep_count))
        if ctx.get(dut.upd_valid):
            n = ctx.get(dut.upd_index)
            s = state["sweep"] + (n == 0)
            state["sweep"] = s
            if s < n_sweeps:
                for key, sig in (("v", dut.upd_v), ("ref", dut.upd_ref),
                                 ("i", dut.upd_current), ("acc", dut.upd_acc),
                                 ("spike", dut.upd_spike), ("clamp", dut.upd_clamp)):
                    rec[key][s, n] = ctx.get(sig)
                for j, t in enumerate(cfg.traces):
                    rec["tr"][s, j, n] = ctx.get(getattr(dut, f"upd_{t.name}"))

    state = {"sweep": -1}
    simulate(dut, bench)
    return rec, stream, done


def _twin_replay(cfg, rec, inputs):
    """Advance the twin from the DUT's own previous state with the current it reports."""
    twin = LifTwin(cfg)
    v, ref = cfg.v_init_raw.copy(), np.zeros(cfg.n_neurons, dtype=np.int64)
    tr = np.zeros((len(cfg.traces), cfg.n_neurons), dtype=np.int64)
    mism = 0
    for k in range(rec["v"].shape[0]):
        out = twin.update(v, ref, rec["i"][k], None if inputs is None else inputs[k],
                          twin.sel, tr)
        if cfg.traces:
            mism += int(np.sum(out["traces"] != rec["tr"][k]))
            tr = rec["tr"][k]
        mism += int(np.sum((out["v"] != rec["v"][k]) | (out["ref"] != rec["ref"][k])
                           | (out["spike"] != rec["spike"][k].astype(bool))
                           | (out["clamp"] != rec["clamp"][k])
                           | (out["acc"] != rec["acc"][k])))
        v, ref = rec["v"][k], rec["ref"][k]
    return mism


@pytest.mark.parametrize("case", ["continuous_multiply", "continuous_shift", "discrete_weights",
                                  "discrete_truncate", "clamps", "synapses"])
def test_rtl_equals_twin_every_update(case):
    rng = np.random.default_rng(7)
    N = 12
    base = {"n_neurons": N, "tick_source": "external", "spike_fifo_depth": 32}
    inputs = None
    if case == "continuous_multiply":
        kw = {"param_sets": [{"tau_m_ms": 2.0, "t_ref_ms": 0.25},
                             {"tau_m_ms": 1.0, "v_rest": -1.0}],
              "neuron_sets": [i % 2 for i in range(N)]}
        cur = np.linspace(5, 100, N)
    elif case == "continuous_shift":
        kw = {"decay": "shift", "param_sets": [{"tau_m_ms": 8.0, "t_ref_ms": 0.125},
                                               {"tau_m_ms": 16.0}],
              "neuron_sets": [i % 2 for i in range(N)]}
        cur = np.linspace(60, 127, N)
    elif case in ("discrete_weights", "discrete_truncate"):
        w = rng.integers(-8, 8, (N, 6)) / 8.0
        kw = {"form": "discrete", "weights": w, "weight_bits": 4, "current_format": (4, 12),
              "param_sets": [{"alpha": 0.389, "u_th": 0.65, "refractory_steps": 1}],
              "rounding": "nearest" if case == "discrete_weights" else "truncate"}
        cur = np.zeros(N)
        inputs = rng.random((60, 6)) < 0.4
    elif case == "synapses":
        w = rng.uniform(0, 20, (N, 4))
        kw = {"synapses": True, "weights": w, "input_types": ["exc", "exc", "inh", "exc"],
              "update_hz": 2000.0, "param_sets": [{"tau_m_ms": 5.0, "t_ref_ms": 1.0}]}
        cur = np.linspace(0, 15, N)
        inputs = rng.random((60, 4)) < 0.3
    else:
        # narrow state format and input limit: every clamp kind acts, flagged
        w = np.full((N, 2), 100.0)
        w[:N // 2] = 0.0
        kw = {"weights": w, "input_limit": (-50.0, 150.0), "saturation": "flag",
              "current_range": (-60.0, 100.0), "v_int_bits": 6,
              "param_sets": [{"tau_m_ms": 0.5, "v_reset": -20.0}]}
        cur = np.concatenate([np.full(N // 2, -128.0), np.full(N - N // 2, 120.0)])
        inputs = np.zeros((60, 2), dtype=bool)
        inputs[5::3, 0] = True
    cfg = LifConfig(**base, **kw)
    n_sweeps = 60
    if inputs is not None:
        inputs[0] = False          # the first sweep starts before any spike can arrive
    rec, stream, done = _run_rtl(cfg, cur, n_sweeps, inputs, period=N + 6)
    mism = _twin_replay(cfg, rec, inputs)
    assert mism == 0
    assert rec["spike"].sum() > 0
    # spike stream and per-sweep counts agree with the updates
    exp_stream = [(int(n), k) for k in range(n_sweeps) for n in np.flatnonzero(rec["spike"][k])]
    assert stream[:len(exp_stream)] == exp_stream
    assert done[:n_sweeps] == [int(x) for x in rec["spike"].sum(axis=1)]
    if case == "synapses":
        assert (rec["tr"] > 0).any(axis=(0, 2)).all()      # every trace carried input
    if case == "clamps":
        for b, k in enumerate(CLAMP_KINDS):
            assert ((rec["clamp"] >> b) & 1).sum() > 0, k
    else:
        assert not rec["clamp"].any()


def test_synaptic_traces_follow_the_golden_kernel():
    """Input spikes through AMPA and GABA traces: the twin's I_syn equals the golden
    difference-of-exponentials sum (with the stored weights) within the traces' rounding
    margin, and it drives the membrane like golden's current does."""
    rng = np.random.default_rng(2)
    n_in, steps = 3, 3000
    w = np.tile([[12.0, 9.0, 6.0]], (8, 1))
    cfg = LifConfig(synapses=True, weights=w, input_types=["exc", "exc", "inh"])
    x = rng.random((steps, n_in)) < 0.01
    twin = LifTwin(cfg)
    twin.set_currents(16.0)
    isyn, spikes = np.zeros(steps), []
    for k in range(steps):
        tr = twin.traces[:, 0]
        isyn[k] = cfg.V.to_float((tr[0] - tr[1]) - (tr[2] - tr[3]))
        if twin.sweep(x[k])[0]:
            spikes.append(k)
    t = np.arange(steps) * cfg.dt_ms
    from cuneate.golden import synapses as gs
    w_eff = cfg.W.to_float(cfg.weights_raw[0]) * np.array(
        [gs.norm_factor(*cfg.ampa, "peak")] * 2 + [gs.norm_factor(*cfg.gaba, "peak")])
    pre = [np.flatnonzero(x[:, i]) * cfg.dt_ms for i in range(n_in)]
    ref = (golden.synaptic_current(pre[:2], t, *cfg.ampa, latency_ms=0.0, weight=w_eff[:2])
           - golden.synaptic_current(pre[2:], t, *cfg.gaba, latency_ms=0.0, weight=w_eff[2:]))
    margin = sum((s.Y.lsb + 2 * cfg.V.lsb) / s.K.quantized for s in cfg.traces)
    assert np.max(np.abs(isyn - ref)) <= margin
    assert isyn.max() > 5 and isyn.min() < -3
    g = golden.simulate_lif(16.0 + ref[:, None], cfg.dt_ms, n_neurons=1, record=False)
    assert abs(len(g.spikes_ms[0]) - len(spikes)) <= 1 and len(spikes) > 3


@pytest.mark.parametrize("kw, match", [
    ({"synapses": True}, "needs weights"),
    ({"synapses": True, "weights": -np.ones((8, 2))}, "must be >= 0"),
    ({"synapses": True, "weights": np.ones((8, 2)), "input_types": ["exc"]}, "input_types"),
    ({"synapses": True, "weights": np.ones((8, 2)), "form": "discrete"}, "continuous form"),
    ({"synapses": True, "weights": np.ones((8, 2)), "ampa": (2.0, 0.4)}, "tau_rise"),
    ({"synapses": True, "weights": np.ones((8, 2)), "weights_writable": True}, "host-writable"),
    ({"weights_writable": True}, "weights_writable needs weights"),
    ({"weights": np.ones((8, 2)), "input_types": ["exc", "inh"]}, "only apply with synapses"),
])
def test_synapse_refusals(kw, match):
    with pytest.raises(ConfigError, match=match):
        LifConfig(**kw)


def test_second_spike_of_a_source_in_one_tick_is_flagged():
    cfg = LifConfig(weights=np.full((8, 3), 0.5), tick_source="external")
    dut = LifCore(cfg)
    seen = []

    async def bench(ctx):
        async def spike(src):
            ctx.set(dut.in_valid, 1)
            ctx.set(dut.in_source, src)
            await ctx.tick()
            ctx.set(dut.in_valid, 0)
        await spike(0)
        await spike(1)                 # other sources in the same tick: no merge
        await spike(2)
        seen.append(ctx.get(dut.in_merged))
        ctx.set(dut.tick, 1)
        await ctx.tick()
        ctx.set(dut.tick, 0)
        await spike(0)                 # the next tick: source 0 again is a new spike
        seen.append(ctx.get(dut.in_merged))
        await spike(0)                 # twice within one tick: merged, flagged
        seen.append(ctx.get(dut.in_merged))

    simulate(dut, bench)
    assert seen == [0, 0, 1]


def test_host_weight_writes():
    """Weight rows written by the host between ticks: the RTL follows the twin given the same
    writes, and the input range is proven for any weights of the format."""
    rng = np.random.default_rng(8)
    N, F, n_sweeps = 8, 3, 40
    cfg = LifConfig(form="discrete", weights=np.full((N, F), 0.25), weights_writable=True,
                    weight_bits=4, current_format=(4, 12), tick_source="external")
    assert cfg.d_lo == cfg.i_lo + F * cfg.W.min_value
    assert cfg.d_hi == cfg.i_hi + F * cfg.W.max_value
    with pytest.raises(ValueError, match="raw values"):
        LifTwin(cfg).set_weights(0, [100, 0, 0])
    writes = {k: (int(rng.integers(N)), rng.integers(cfg.W.min_raw, cfg.W.max_raw + 1, F))
              for k in range(0, n_sweeps, 3)}
    x = rng.random((n_sweeps, F)) < 0.5
    dut = LifCore(cfg)
    got = np.zeros((n_sweeps, N), dtype=np.int64)

    async def bench(ctx):
        k = -1
        for sweep in range(n_sweeps):
            while ctx.get(dut.busy):
                await ctx.tick()
            if sweep in writes:
                n, row = writes[sweep]
                ctx.set(dut.w_wr_en, 1)
                ctx.set(dut.w_wr_addr, n)
                ctx.set(dut.w_wr_data, LifTwin.pack_weights(cfg, row))
                await ctx.tick()
                ctx.set(dut.w_wr_en, 0)
            await spikes_then_tick(ctx, dut, np.flatnonzero(x[sweep]), ctx.tick, True)
            for _ in range(N + 6):
                if ctx.get(dut.upd_valid):
                    i = ctx.get(dut.upd_index)
                    k += i == 0
                    got[k, i] = ctx.get(dut.upd_acc)
                await ctx.tick()

    simulate(dut, bench)
    twin = LifTwin(cfg)
    for k in range(n_sweeps):
        if k in writes:
            twin.set_weights(*writes[k])
        out = twin.update(twin.v, twin.ref, twin.I, x[k], twin.sel)
        twin.sweep(x[k])
        assert np.array_equal(out["acc"], got[k]), k
    assert np.any(got < 0) and len(writes) > 5
