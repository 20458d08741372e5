"""Pipelined, time-multiplexed, fixed-point LIF core and its bit-exact NumPy twin.

One neuron update per clock; state (``v`` and the refractory counter) in block RAM; a host-written
current and a parameter-set index per neuron; weighted input spikes summed per tick from a weight
memory. Both forms of the brief (section 6), written as one subtraction of a product (see
:mod:`cuneate.hdl.lif_config`)::

    D   = clamp(I) + sum_i w_i x_i                    (total input of this tick)
    continuous:  v_pre = v - k (v - v_rest - D)       k = 1 - exp(-dt/tau_m)
    discrete:    v_pre = v - k v + D                  k = 1 - alpha
    refractory (r > 0):  v' = v_reset, r' = r - 1, no spike
    else if v_pre >= v_th (continuous) / v_pre > u_th (discrete):  spike, v' = v_reset, r' = n_ref
    else:  v' = v_pre (flagged clamp at the state floor when the format is narrower than proven)

Formats (from :class:`LifConfig`): state ``V`` (signed, ``v_frac_bits`` fraction bits, integer
bits from the proven range), host current ``I`` (default sQ8.8), weights ``W`` (``weight_bits``,
e.g. 8 or 4), accumulator ``acc_bits = weight_bits + ceil(log2 fan_in)`` (cannot overflow), the
leak operand ``X`` (``operand_width`` bits, multiply mode) and ``k`` (``operand_width`` bits,
one shared exponent) or a per-set shift ``s`` (shift mode, no multiplier). All arithmetic comes
from :mod:`cuneate.hdl.fixed`; the three datapath steps below are used by the RTL (a pipeline
register after each stage) and by the twin (composed directly).

With ``synapses=True`` the weighted input spikes drive four per-neuron AMPA/GABA traces instead
(:mod:`cuneate.hdl.lif_synapses`): ``D = clamp(I) + I_syn``, the traces in their own block RAM,
their decays (one multiplier each) in stage 4 and their write-back in stage 5.

Every clamp that can act is flagged and counted (:data:`CLAMP_KINDS`): ``current`` (host wrote
outside ``current_range``), ``input`` (the total input left ``input_limit``; only built with
``saturation="flag"``) and ``v_low`` (state below a format narrower than proven).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..golden.izhikevich import group_spikes
from .fixed import (QFormat, check_int64, clamp_flagged, is_hdl, narrow, round_shift, round_shift_select,
                    select, tally_clamps)
from .lif_synapses import TRACE_NAMES, trace_inputs, trace_products, trace_update
from .lif_config import (CLAMP_KINDS, DECAYS, FORMS, PIPELINE_DEPTH, ConfigError, LifConfig,
                         LifSet)
from .tick import tick_strobe

__all__ = ["ConfigError", "LifConfig", "LifSet", "LifTwin", "LifCore", "PIPELINE_DEPTH",
           "CLAMP_KINDS", "FORMS", "DECAYS", "gather_input", "leak_operand", "leak_product",
           "update_state", "lif_verilog", "generate_lif"]


def _lookup(table: Sequence[int], sel):
    """``table[sel]``: a constant when all entries are equal, else a mux (RTL) or indexing."""
    if len(set(table)) == 1:
        return table[0]
    if is_hdl(sel):
        out = Const(table[-1], range(min(table), max(table) + 1))
        for i in range(len(table) - 2, -1, -1):
            out = Mux(sel == i, table[i], out)
        return out
    return np.asarray(table, dtype=np.int64)[np.asarray(sel)]


def _false(like):
    return Const(0, 1) if is_hdl(like) else np.zeros(np.shape(like), dtype=bool)


# ----------------------------------------------------------------------------------------------
# The datapath: stage 3 (gather_input, leak_operand), stage 4 (leak_product), stage 5
# (update_state). NumPy int64 arrays (twin) and Amaranth values (RTL) alike.

def gather_input(cfg: LifConfig, I, x: Sequence, w: Sequence, traces=None):
    """Total input ``D = clamp(I) + sum_i (x_i ? w_i : 0)`` in state fraction bits, or, with
    synaptic traces, ``D = clamp(I) + I_syn`` (see :mod:`cuneate.hdl.lif_synapses`).

    ``x`` and ``w`` are per-source lists (spike bit and raw weight of the neuron for source
    ``i``). The sum cannot overflow its accumulator (width derived from the fan-in). Returns
    ``D``, the accumulator, the trace inputs ``ys`` and the ``current``/``input`` clamp flags."""
    fv = cfg.V.frac_bits
    if cfg.current_clamp:
        I, lo, hi = clamp_flagged(I, cfg.i_lo_raw, cfg.i_hi_raw, cfg.I)
        f_cur = lo | hi
    else:
        f_cur = _false(I)
    ys = []
    if cfg.synapses:
        i_syn, ys, acc = trace_inputs(cfg, traces, x, w)
        D = (I << (fv - cfg.I.frac_bits)) + i_syn
    else:
        acc = 0
        for xi, wi in zip(x, w):
            acc = acc + select(xi, wi, 0)
        if not cfg.n_inputs:
            acc = Const(0, 1) if is_hdl(I) else np.zeros(np.shape(I), dtype=np.int64)
        D = (I << (fv - cfg.I.frac_bits)) + (acc << (fv - cfg.W.frac_bits))
    if cfg.input_clamp:
        width = max(abs(cfg.d_lo_raw), abs(cfg.d_hi_raw)).bit_length() + 1
        D, lo, hi = clamp_flagged(D, cfg.d_lo_raw, cfg.d_hi_raw, QFormat(width, 0))
        f_in = lo | hi
    else:
        f_in = _false(I)
    return {"d": D, "acc": acc, "ys": ys, "current": f_cur, "input": f_in}


def leak_operand(cfg: LifConfig, v, D, sel):
    """The operand of the leak: ``v - v_rest - D`` (continuous) or ``v`` (discrete), rounded
    to the multiplier's operand format ``X`` (proven to fit: no clamp) in multiply mode."""
    if cfg.form == "continuous":
        x = v - _lookup([c.raw for c in cfg.REST], sel) - D
    else:
        x = v
    if cfg.X is None:
        return x
    return narrow(round_shift(x, cfg.V.frac_bits - cfg.X.frac_bits, cfg.rounding), cfg.X,
                  cfg.x_bounds_raw, "leak operand")


def leak_product(cfg: LifConfig, x, sel):
    """``k x`` rounded to state fraction bits: one multiply by the set's ``k`` (shared
    exponent) or a shift by the set's ``s``."""
    if cfg.k_shift is not None:
        return round_shift_select(x, cfg.k_shift, sel, cfg.rounding) if len(
            set(cfg.k_shift)) > 1 else round_shift(x, cfg.k_shift[0], cfg.rounding)
    return round_shift(x * _lookup([c.raw for c in cfg.K], sel), cfg.product_shift,
                       cfg.rounding)


def update_state(cfg: LifConfig, v, d, D, ref, sel):
    """``v_pre = v - d (+ D)``, refractory hold, threshold, reset, state floor clamp (flagged).
    Returns the new ``v`` and ``ref``, the spike, ``v_pre`` and the ``v_low`` flag."""
    v_pre = v - d + D if cfg.form == "discrete" else v - d
    frozen = (ref != 0) if cfg.ref_bits else _false(v)
    spike = (v_pre >= _lookup(cfg.th_cmp_raw, sel)) & ~frozen
    reset = _lookup([c.raw for c in cfg.RESET], sel)
    fv = cfg.V.frac_bits
    pb = (int(np.floor(cfg.v_lo_proven * 2.0 ** fv)), int(np.ceil(cfg.v_hi_proven * 2.0 ** fv)))
    if cfg.v_clamp:
        # above the format's top v_pre is above threshold (the format holds v_th): it spikes
        kept, below, _ = clamp_flagged(v_pre, cfg.V.min_raw, cfg.V.max_raw, cfg.V)
        v_low = below & ~spike & ~frozen
    else:
        kept = narrow(v_pre, cfg.V, pb, "v")
        v_low = _false(v)
    v_out = select(frozen | spike, reset, kept)
    if cfg.ref_bits:
        n_ref = _lookup(cfg.n_ref, sel)
        ref_out = select(frozen, ref - 1, select(spike, n_ref, 0))
    else:
        ref_out = ref
    return {"v": v_out, "ref": ref_out, "spike": spike, "v_pre": v_pre, "v_low": v_low}


def clamp_bits(flags: dict):
    """Pack per-update clamp flags in the bit order of :data:`CLAMP_KINDS` (twin)."""
    return sum((np.asarray(flags[k], dtype=np.int64) << i) for i, k in enumerate(CLAMP_KINDS))


# ----------------------------------------------------------------------------------------------
class LifTwin:
    """Bit-exact NumPy (int64) model of :class:`LifCore`, vectorized over neurons.

    :meth:`sweep` performs one tick (every neuron once) with the input spikes ``x`` of that
    tick; :meth:`run` a whole program; :meth:`update` computes updates from any given state
    (used by scoreboards, always by the stage functions). Clamp flags, sticky bits and counters
    follow the RTL's (:meth:`clamp_report`).

    Two implementations of :meth:`sweep` and :meth:`run` compute the same bits: ``kernel=
    "stages"`` (the stage functions over NumPy arrays; with ``check=True`` the leak product is
    also tested against the int64 range) and ``kernel="numba"`` (the compiled loop of
    :mod:`cuneate.hdl.lif_kernel`, proven bit-exact against the stages by property tests and
    long runs; the default whenever numba is available, ``check`` is off and the configuration
    is covered). ``threads`` (compiled kernel, :meth:`run_raw` / :meth:`run`) splits the
    population over threads; default: all cores from 2000 neurons on, else one.
    """

    KERNELS = ("stages", "numba")

    def __init__(self, config: LifConfig | None = None, check: bool = False,
                 kernel: str | None = None, threads: int | None = None, **kwargs):
        from . import lif_kernel as _k
        self.cfg = cfg = config or LifConfig(**kwargs)
        self.check = check
        self.threads = threads
        if kernel is not None and kernel not in self.KERNELS:
            raise ValueError(f"unknown twin kernel {kernel!r}; known: {', '.join(self.KERNELS)}")
        self._consts = None
        if kernel != "stages" and _k.available() and not (check and kernel is None):
            try:
                self._consts = _k.gather_constants(cfg)
            except ValueError:
                if kernel == "numba":
                    raise
        elif kernel == "numba":
            raise ValueError("twin kernel 'numba' needs numba installed")
        self.kernel = "numba" if self._consts is not None else "stages"
        self._k = _k
        self.sel = np.asarray(cfg.neuron_sets, dtype=np.int64)
        self.v = cfg.v_init_raw.copy()
        self.ref = np.zeros(cfg.n_neurons, dtype=np.int64)
        self.I = np.zeros(cfg.n_neurons, dtype=np.int64)
        self.traces = np.zeros((len(cfg.traces), cfg.n_neurons), dtype=np.int64)
        self.W = cfg.weights_raw.copy()
        self.sweeps = 0
        self.clamp_sticky = 0
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}

    def set_currents(self, values, index=None) -> np.ndarray:
        """Quantize currents like the host does (saturating to the current format)."""
        raw = self.cfg.I.to_raw(values)
        if index is None:
            self.I[:] = raw
        else:
            self.I[index] = raw
        return raw

    def set_weights(self, neuron: int, raw_row) -> None:
        """Host write of a neuron's weight row (raw values of ``config.W``), as ``w_wr_*``;
        only with ``weights_writable``."""
        if not self.cfg.weights_writable:
            raise ValueError("the core was generated with fixed weights (weights_writable)")
        row = np.asarray(raw_row, dtype=np.int64)
        W = self.cfg.W
        if row.shape != (self.cfg.n_inputs,) or np.any(row < W.min_raw) or \
                np.any(row > W.max_raw):
            raise ValueError(f"a weight row is {self.cfg.n_inputs} raw values of {W}")
        self.W[neuron] = row

    @staticmethod
    def pack_weights(cfg, raw_row) -> int:
        """The ``w_wr_data`` word of a raw weight row (source 0 in the low bits)."""
        wb = cfg.W.width
        return sum((int(w) & ((1 << wb) - 1)) << (wb * i) for i, w in enumerate(raw_row))

    def update(self, v, ref, I, x, sel, traces=None):
        """One update of every neuron given (raw arrays); ``x`` is the (n_inputs,) spike
        vector of the tick, ``traces`` the (4, n) synaptic traces (with ``synapses``).
        Returns the new state (``traces`` too), spike, ``d``/``acc`` and clamp flags."""
        cfg = self.cfg
        v, ref, I, sel = (np.asarray(a, dtype=np.int64) for a in (v, ref, I, sel))
        xs = np.zeros(cfg.n_inputs, dtype=bool) if x is None else np.asarray(x, dtype=bool)
        if xs.shape != (cfg.n_inputs,):
            raise ValueError(f"input spike vector must have {cfg.n_inputs} entries")
        W = self.W
        tr = None
        if cfg.synapses:
            tr = [np.asarray(t, dtype=np.int64) for t in (self.traces if traces is None
                                                          else traces)]
        g = gather_input(cfg, I, [bool(b) for b in xs], [W[:, i] for i in range(cfg.n_inputs)],
                         tr)
        xop = leak_operand(cfg, v, g["d"], sel)
        d = leak_product(cfg, xop, sel)
        if self.check:
            check_int64("leak product", d)
        out = update_state(cfg, v, d, g["d"], ref, sel)
        if cfg.synapses:
            out["traces"] = np.array(trace_update(cfg, g["ys"], trace_products(cfg, g["ys"])),
                                     dtype=np.int64)
            out["ys"] = np.array(g["ys"], dtype=np.int64)
        out["acc"] = np.broadcast_to(np.asarray(g["acc"], dtype=np.int64), v.shape)
        out["d"] = g["d"]
        out["current"] = np.broadcast_to(g["current"], v.shape)
        out["input"] = np.broadcast_to(g["input"], v.shape)
        out["clamp"] = clamp_bits(out)
        return out

    def _run_kernel(self, I, n_sweeps: int, inputs, threads):
        """``n_sweeps`` ticks by the compiled kernel (state, traces and clamp accounting kept);
        returns the spikes as ``(sweeps, neurons)``."""
        syn = self.cfg.synapses
        tr = self.traces if syn else np.zeros((1, self.cfg.n_neurons), dtype=np.int64)
        ks, ns, totals, _ = self._k.run_program(self._consts, self.v, self.ref, tr, I, self.sel,
                                                self.W, inputs, n_sweeps, threads)
        if syn:
            self.traces = tr
        self.sweeps += n_sweeps
        tally_clamps(self, CLAMP_KINDS, totals)
        return ks, ns

    def run_raw(self, currents_raw, n_sweeps: int, inputs=None):
        """``n_sweeps`` ticks from raw currents, (n,) for the whole run or (n_sweeps, n) per
        tick (already in the current format), and optional (n_sweeps, n_inputs) input spikes.
        Returns every spike as ``(sweep indices, neuron indices)``, sweeps counted from 0 at
        this call; the final state, clamp counts and sticky flags are kept."""
        cfg = self.cfg
        I = np.ascontiguousarray(currents_raw, dtype=np.int64)
        if I.shape not in ((cfg.n_neurons,), (n_sweeps, cfg.n_neurons)):
            raise ValueError(f"currents must have shape ({cfg.n_neurons},) or ({n_sweeps}, "
                             f"{cfg.n_neurons})")
        if inputs is not None:
            inputs = np.ascontiguousarray(inputs, dtype=bool)
            if inputs.shape != (n_sweeps, cfg.n_inputs):
                raise ValueError(f"input spikes must have shape ({n_sweeps}, {cfg.n_inputs})")
        if self.kernel == "numba":
            ks, ns = self._run_kernel(I, n_sweeps, inputs, self.threads)
            if n_sweeps:
                self.I[:] = I if I.ndim == 1 else I[-1]
            return ks, ns
        hits_k, hits_n = [], []
        for k in range(n_sweeps):
            self.I[:] = I if I.ndim == 1 else I[k]
            idx = np.flatnonzero(self.sweep(None if inputs is None else inputs[k]))
            hits_k.append(np.full(idx.size, k, dtype=np.int64))
            hits_n.append(idx)
        if not hits_k:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return np.concatenate(hits_k), np.concatenate(hits_n)

    def sweep(self, x=None) -> np.ndarray:
        """One tick with input spike vector ``x``; returns the boolean spike vector."""
        if self.kernel == "numba":
            xs = None if x is None else np.asarray(x, dtype=bool).reshape(1, -1)
            if xs is not None and xs.shape[1] != self.cfg.n_inputs:
                raise ValueError(f"input spike vector must have {self.cfg.n_inputs} entries")
            _, ns = self._run_kernel(self.I, 1, xs, threads=1)
            spk = np.zeros(self.cfg.n_neurons, dtype=bool)
            spk[ns] = True
            return spk
        out = self.update(self.v, self.ref, self.I, x, self.sel)
        self.v = np.asarray(out["v"], dtype=np.int64)
        self.ref = np.asarray(out["ref"], dtype=np.int64)
        if self.cfg.synapses:
            self.traces = out["traces"]
        self.sweeps += 1
        tally_clamps(self, CLAMP_KINDS, [np.count_nonzero(out[k]) for k in CLAMP_KINDS])
        return np.asarray(out["spike"], dtype=bool)

    def run(self, currents, n_sweeps: int, inputs=None) -> list[np.ndarray]:
        """``n_sweeps`` ticks; ``currents`` a number, (n,) array or callable ``f(t_ms)``;
        ``inputs`` an optional (n_sweeps, n_inputs) spike array. Returns spike times (ms)
        per neuron, update k -> (k+1) dt."""
        hits: list[list[int]] = [[] for _ in range(self.cfg.n_neurons)]
        if not callable(currents):
            raw = self.set_currents(np.broadcast_to(currents, (self.cfg.n_neurons,)))
            ks, ns = self.run_raw(np.asarray(raw, dtype=np.int64), n_sweeps, inputs)
            steps = group_spikes([ks], [ns], self.cfg.n_neurons)
            return [(np.asarray(s, dtype=np.float64) + 1) * self.cfg.dt_ms for s in steps]
        for k in range(n_sweeps):
            if callable(currents):
                self.set_currents(np.broadcast_to(currents(k * self.cfg.dt_ms),
                                                  (self.cfg.n_neurons,)))
            spk = self.sweep(None if inputs is None else inputs[k])
            for n in np.flatnonzero(spk):
                hits[n].append(k)
        return [(np.asarray(h, dtype=np.float64) + 1) * self.cfg.dt_ms for h in hits]

    def clamp_report(self) -> dict:
        return {"sticky": {k: bool(self.clamp_sticky >> i & 1)
                           for i, k in enumerate(CLAMP_KINDS)},
                "counts": dict(self.clamp_counts)}

    def v_float(self):
        return self.cfg.V.to_float(self.v)


# ----------------------------------------------------------------------------------------------
class LifCore(wiring.Component):
    """Time-multiplexed LIF core: one neuron update per clock, 5-stage pipeline.

    Latency: a neuron's index is issued at cycle t; its update is on ``upd_*`` at t + 5.

    1. **Fetch** - the sweep counter addresses the state (``v``, refractory counter), current,
       set-select and weight RAMs (synchronous read); the tick's input spike vector is tagged
       onto the neuron.
    2. **Read** - the RAM outputs are registered.
    3. **Input, operand** - ``D = clamp(I) + sum w x`` (adder tree over the fan-in, width from
       the fan-in) and the leak operand ``v - v_rest - D`` (or ``v``), rounded to ``X``.
    4. **Leak** - ``k x`` (one multiplier) or ``x >> s`` (no multiplier).
    5. **Update** - subtract, refractory hold, threshold, reset, flagged floor clamp; write
       back; outputs registered.

    Input spikes: ``in_valid``/``in_source`` set a source's bit in the pending vector; each
    tick moves the pending vector into the active one (used by every neuron of that sweep)
    and clears it, so a spike arriving during tick t acts on the sweep of tick t + 1. Several
    spikes of one source in one tick count once and set the sticky ``in_merged`` flag. Other ports are those of
    :class:`cuneate.hdl.izhikevich.IzhikevichCore` (``i_wr_*``, ``sel_wr_*``, spike stream,
    ``upd_*`` probe with ``upd_ref``, ``upd_acc``, sweep counters, sticky clamp flags). With
    ``weights_writable``, ``w_wr_en/w_wr_addr/w_wr_data`` write a neuron's whole weight row
    (same rules as the current writes; the accepted input range is then proven for any weights
    of the format).
    """

    def __init__(self, config: LifConfig | None = None, **kwargs):
        self.cfg = cfg = config or LifConfig(**kwargs)
        N, F = cfg.n_neurons, cfg.n_inputs
        sig = {
            "i_wr_en": In(1), "i_wr_addr": In(range(N)), "i_wr_data": In(cfg.I.shape()),
            "sel_wr_en": In(1), "sel_wr_addr": In(range(N)), "sel_wr_data": In(cfg.sel_bits),
            "spike_valid": Out(1), "spike_ready": In(1), "spike_index": Out(range(N)),
            "spike_sweep": Out(cfg.sweep_number_width), "spike_overflow": Out(1),
            "upd_valid": Out(1), "upd_index": Out(range(N)), "upd_v": Out(cfg.V.shape()),
            "upd_ref": Out(max(1, cfg.ref_bits)), "upd_current": Out(cfg.I.shape()),
            "upd_acc": Out(signed(cfg.acc_bits)), "upd_spike": Out(1),
            "upd_clamp": Out(len(CLAMP_KINDS)),
            "clamp_flags": Out(len(CLAMP_KINDS)), "clamp_clear": In(1),
            "sweep_done": Out(1), "sweep_count": Out(range(N + 1)),
            "sweep_number": Out(cfg.sweep_number_width), "overrun": Out(1), "busy": Out(1),
        }
        for t in cfg.traces:
            sig[f"upd_{t.name}"] = Out(t.T.shape())
        if F:
            sig["in_valid"] = In(1)
            sig["in_source"] = In(range(F))
            sig["in_merged"] = Out(1)
            if cfg.weights_writable:
                sig["w_wr_en"] = In(1)
                sig["w_wr_addr"] = In(range(N))
                sig["w_wr_data"] = In(F * cfg.W.width)
        for k in CLAMP_KINDS:
            sig[f"sweep_clamps_{k}"] = Out(range(N + 1))
        if cfg.tick_source == "external":
            sig["tick"] = In(1)
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        N, F, V, R = cfg.n_neurons, cfg.n_inputs, cfg.V, cfg.ref_bits
        m = Module()
        init_state = [int(v) & ((1 << V.width) - 1) for v in cfg.v_init_raw]
        m.submodules.state_mem = state_mem = Memory(shape=V.width + R, depth=N,
                                                    init=init_state)
        m.submodules.cur_mem = cur_mem = Memory(shape=cfg.I.shape(), depth=N, init=[])
        m.submodules.sel_mem = sel_mem = Memory(shape=cfg.sel_bits, depth=N,
                                                init=cfg.neuron_sets)
        st_rd, st_wr = state_mem.read_port(), state_mem.write_port()
        cur_rd, cur_wr = cur_mem.read_port(), cur_mem.write_port()
        sel_rd, sel_wr = sel_mem.read_port(), sel_mem.write_port()
        rd_ports = [st_rd, cur_rd, sel_rd]
        wb = cfg.W.width
        if F:
            rows = [LifTwin.pack_weights(cfg, row) for row in cfg.weights_raw]
            m.submodules.weight_mem = w_mem = Memory(shape=wb * F, depth=N, init=rows)
            w_rd = w_mem.read_port()
            rd_ports.append(w_rd)
            if cfg.weights_writable:
                w_wr = w_mem.write_port()
                m.d.comb += [w_wr.addr.eq(self.w_wr_addr), w_wr.data.eq(self.w_wr_data),
                             w_wr.en.eq(self.w_wr_en)]
        TW = [t.T.width for t in cfg.traces]
        if cfg.traces:
            m.submodules.trace_mem = tr_mem = Memory(shape=sum(TW), depth=N, init=[])
            tr_rd, tr_wr = tr_mem.read_port(), tr_mem.write_port()
            rd_ports.append(tr_rd)
        m.d.comb += [
            cur_wr.addr.eq(self.i_wr_addr), cur_wr.data.eq(self.i_wr_data),
            cur_wr.en.eq(self.i_wr_en),
            sel_wr.addr.eq(self.sel_wr_addr), sel_wr.data.eq(self.sel_wr_data),
            sel_wr.en.eq(self.sel_wr_en),
        ]

        # --- sweep control ------------------------------------------------------------------
        tick = tick_strobe(m, cfg, getattr(self, "tick", None))
        issuing = Signal()
        addr = Signal(range(N))
        sweep_no = Signal(cfg.sweep_number_width)
        started = Signal()
        last_issue = issuing & (addr == N - 1)
        start = tick & (~issuing | last_issue)
        with m.If(tick & ~start):
            m.d.sync += self.overrun.eq(1)
        with m.If(start):
            m.d.sync += [issuing.eq(1), addr.eq(0), started.eq(1),
                         sweep_no.eq(Mux(started, sweep_no + 1, 0))]
        with m.Elif(issuing):
            m.d.sync += addr.eq(addr + 1)
            with m.If(last_issue):
                m.d.sync += issuing.eq(0)
        m.d.comb += self.busy.eq(issuing)
        for port in rd_ports:
            m.d.comb += [port.addr.eq(addr), port.en.eq(1)]

        # --- input spikes: pending -> active on each sweep start ------------------------------
        active = Signal(max(1, F))
        if F:
            pending = Signal(F)
            event = Mux(self.in_valid, Const(1, F) << self.in_source, 0)
            with m.If(start):
                m.d.sync += [active.eq(pending), pending.eq(event)]
            with m.Else():
                m.d.sync += pending.eq(pending | event)
                # a second spike of a source within one tick merges with the first: flagged
                with m.If(self.in_valid & pending.bit_select(self.in_source, 1)):
                    m.d.sync += self.in_merged.eq(1)

        # --- pipeline tags --------------------------------------------------------------------
        def tag(n):
            return (Signal(name=f"valid{n}"), Signal(range(N), name=f"idx{n}"),
                    Signal(cfg.sweep_number_width, name=f"swp{n}"))
        t2, t3, t4, t5 = tag(2), tag(3), tag(4), tag(5)
        m.d.sync += [t2[0].eq(issuing), t2[1].eq(addr), t2[2].eq(sweep_no)]
        for a, b in ((t2, t3), (t3, t4), (t4, t5)):
            m.d.sync += [b[0].eq(a[0]), b[1].eq(a[1]), b[2].eq(a[2])]

        def reg(name, value, stage):
            s = Signal(value.shape(), name=f"{name}{stage}")
            m.d.sync += s.eq(value)
            return s

        x2 = reg("x", active, 2)
        # --- stage 2: RAM outputs registered -------------------------------------------------
        v3 = reg("v", st_rd.data[:V.width].as_signed(), 3)
        ref3 = reg("ref", st_rd.data[V.width:] if R else Const(0, 1), 3)
        i3, sel3, x3 = reg("i", cur_rd.data, 3), reg("sel", sel_rd.data, 3), reg("x", x2, 3)
        w3 = reg("w", w_rd.data, 3) if F else None
        # --- stage 3: total input and leak operand -------------------------------------------
        ws = [w3[wb * i: wb * (i + 1)].as_signed() for i in range(F)]
        tr3 = None
        if cfg.traces:
            offs = np.cumsum([0] + TW)
            tr3 = [reg(f"tr_{t.name}", tr_rd.data[offs[j]:offs[j + 1]].as_signed(), 3)
                   for j, t in enumerate(cfg.traces)]
        g = gather_input(cfg, i3, [x3[i] for i in range(F)], ws, tr3)
        xop = leak_operand(cfg, v3, g["d"], sel3)
        v4, ref4, sel4, i4 = (reg(n, s, 4) for n, s in
                              (("v", v3), ("ref", ref3), ("sel", sel3), ("i", i3)))
        d4, acc4, x4 = reg("d", g["d"], 4), reg("acc", g["acc"], 4), reg("xop", xop, 4)
        fcur4, fin4 = reg("flag_current", g["current"], 4), reg("flag_input", g["input"], 4)
        # --- stage 4: the leak product --------------------------------------------------------
        p = leak_product(cfg, x4, sel4)
        v5, ref5, sel5, i5, d5, acc5 = (reg(n, s, 5) for n, s in
                                        (("v", v4), ("ref", ref4), ("sel", sel4), ("i", i4),
                                         ("d", d4), ("acc", acc4)))
        p5 = reg("p", p, 5)
        ys4 = [reg(f"y_{t.name}", y, 4) for t, y in zip(cfg.traces, g["ys"])]
        # the trace products are formed in stage 4 from the registered ys
        if cfg.traces:
            tp5 = [reg(f"tp_{t.name}", q, 5) for t, q in zip(cfg.traces,
                                                             trace_products(cfg, ys4))]
            ys5 = [reg(f"y_{t.name}", y, 5) for t, y in zip(cfg.traces, ys4)]
            tr_new = trace_update(cfg, ys5, tp5)
            tr_out = [Signal(t.T.shape(), name=f"{t.name}_out") for t in cfg.traces]
            m.d.comb += [o.eq(v) for o, v in zip(tr_out, tr_new)]
            m.d.comb += [tr_wr.addr.eq(t5[1]), tr_wr.data.eq(Cat(*tr_out)),
                         tr_wr.en.eq(t5[0])]
            m.d.sync += [getattr(self, f"upd_{t.name}").eq(o)
                         for t, o in zip(cfg.traces, tr_out)]
        fcur5, fin5 = reg("flag_current", fcur4, 5), reg("flag_input", fin4, 5)
        # --- stage 5: update, write back ------------------------------------------------------
        s5 = update_state(cfg, v5, p5, d5, ref5, sel5)
        v_out = Signal(V.shape())
        ref_out = Signal(max(1, R))
        spike = Signal()
        clamp = Signal(len(CLAMP_KINDS))
        flags = {"current": fcur5, "input": fin5, "v_low": s5["v_low"]}
        m.d.comb += [v_out.eq(s5["v"]), ref_out.eq(s5["ref"]), spike.eq(s5["spike"] & t5[0]),
                     clamp.eq(Mux(t5[0], Cat(*(flags[k] for k in CLAMP_KINDS)), 0))]
        m.d.comb += [st_wr.addr.eq(t5[1]),
                     st_wr.data.eq(Cat(v_out, ref_out[:R]) if R else v_out),
                     st_wr.en.eq(t5[0])]
        m.d.sync += [self.upd_valid.eq(t5[0]), self.upd_index.eq(t5[1]), self.upd_v.eq(v_out),
                     self.upd_ref.eq(ref_out), self.upd_current.eq(i5),
                     self.upd_acc.eq(acc5), self.upd_spike.eq(spike), self.upd_clamp.eq(clamp)]

        # --- bookkeeping ------------------------------------------------------------------------
        upd_sweep = Signal(cfg.sweep_number_width)
        m.d.sync += upd_sweep.eq(t5[2])
        count = Signal(range(N + 1))
        last = self.upd_valid & (self.upd_index == N - 1)
        m.d.sync += self.sweep_done.eq(last)
        with m.If(last):
            m.d.sync += [self.sweep_count.eq(count + self.upd_spike),
                         self.sweep_number.eq(upd_sweep), count.eq(0)]
        with m.Elif(self.upd_valid):
            m.d.sync += count.eq(count + self.upd_spike)
        for i, k in enumerate(CLAMP_KINDS):
            cnt = Signal(range(N + 1), name=f"clamp_count_{k}")
            with m.If(last):
                m.d.sync += [getattr(self, f"sweep_clamps_{k}").eq(cnt + self.upd_clamp[i]),
                             cnt.eq(0)]
            with m.Elif(self.upd_valid):
                m.d.sync += cnt.eq(cnt + self.upd_clamp[i])
        m.d.sync += self.clamp_flags.eq(Mux(self.clamp_clear, 0, self.clamp_flags)
                                        | self.upd_clamp)

        # --- spike stream ---------------------------------------------------------------------
        iw = (N - 1).bit_length() or 1
        m.submodules.spike_fifo = fifo = SyncFIFOBuffered(
            width=iw + cfg.sweep_number_width, depth=cfg.spike_fifo_depth)
        push = self.upd_valid & self.upd_spike
        m.d.comb += [fifo.w_data.eq(Cat(self.upd_index[:iw], upd_sweep)), fifo.w_en.eq(push),
                     self.spike_valid.eq(fifo.r_rdy), fifo.r_en.eq(self.spike_ready),
                     self.spike_index.eq(fifo.r_data[:iw]),
                     self.spike_sweep.eq(fifo.r_data[iw:])]
        with m.If(push & ~fifo.w_rdy):
            m.d.sync += self.spike_overflow.eq(1)
        return m


# ----------------------------------------------------------------------------------------------
def lif_verilog(config: LifConfig, name: str = "lif_core") -> str:
    """Verilog text of the core (no source locations: the same config gives the same bytes)."""
    from amaranth.back import verilog
    return verilog.convert(LifCore(config), name=name, emit_src=False)


def generate_lif(out, config: LifConfig, name: str = "lif_core") -> list:
    """Write ``out/<name>.v`` and ``out/<name>.json`` (formats, constants and their errors,
    latency, ports, resources hint); returns the paths."""
    import json
    from pathlib import Path
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    core = LifCore(config)
    from amaranth.back import verilog
    text = verilog.convert(core, name=name, emit_src=False)
    desc = config.to_dict() | {"module": name}
    desc["ports"] = {pname: {"direction": "in" if member.flow == In else "out",
                             "width": len(getattr(core, pname)),
                             "signed": bool(getattr(member.shape, "signed", False))}
                     for pname, member in core.signature.members.items()}
    vpath, jpath = out / f"{name}.v", out / f"{name}.json"
    vpath.write_text(text)
    jpath.write_text(json.dumps(desc, indent=2, sort_keys=True, default=float) + "\n")
    return [vpath, jpath]
