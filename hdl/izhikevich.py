"""Pipelined, time-multiplexed, fixed-point Izhikevich core and its bit-exact NumPy twin.

The arithmetic is forward Euler (the golden model's ``scheme="euler"``), rewritten so that each
multiplier sees two operands of at most ``operand_width`` (18) bits and every constant keeps as
many significant bits as an operand can carry. Per parameter set ``s``::

    w   = v + B_s/(2 A_s)                       (62.5 mV for the standard equation)
    v'  = v + (A_s dt) w^2 + dt (C_s - A_s woff_s^2) + dt I - dt u
    u'  = u + (a_s dt) (b_s v - lambda_s u - b_s v_u,s)
    if v' >= v_th:  v' <- c_s,  u' <- u' + d_s

Completing the square (``A v^2 + B v = A w^2 - B^2/(4A)``) makes the one squared operand small
near rest, where the neuron spends its time, so its rounding costs least there. When ``dt`` is a
power of two (16 kHz: dt = 1/16 ms) ``dt I`` and ``dt u`` are exact shifts and the core uses four
multipliers: ``(A dt) w``, ``((A dt) w) w``, ``b v`` and ``(a dt) y``. Otherwise a fifth
multiplies ``I - u`` by ``dt``. ``a dt`` is stored per parameter set as a normalized mantissa
with its own shift; ``b`` and ``A dt`` share one exponent across the sets. Per-set offsets and
constants are multiplexed by the neuron's set index only when the sets differ.

Formats, clamp levels and constants come from :class:`~cuneate.hdl.izhikevich_config
.IzhikevichConfig`, sized to the state range proven for the accepted currents; every clamp that
can act is flagged (``v_low``, ``u_high``, ``u_low``, ``current``, ``y``: see
:data:`CLAMP_KINDS`). All arithmetic comes from :mod:`cuneate.hdl.fixed`; the four datapath
steps below are written once and used both by the RTL (with a pipeline register after each
stage) and by the twin (composed directly).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from amaranth import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..golden import izhikevich as golden
from .fixed import (check_int64, clamp_flagged, is_hdl, narrow, round_shift, round_shift_add,
                    select, tally_clamps)
from .izhikevich_config import (CLAMP_KINDS, PIPELINE_DEPTH, SATURATION, ConfigError,
                                IzhikevichConfig)
from .tick import tick_strobe

__all__ = ["ConfigError", "IzhikevichConfig", "IzhikevichTwin", "IzhikevichCore",
           "PIPELINE_DEPTH", "CLAMP_KINDS", "SATURATION", "operands", "multiply1",
           "multiply2", "update_state"]


def _lookup(table: Sequence[int], sel, width: int | None = None):
    """``table[sel]``: a constant when every entry is equal, else a mux of constants in RTL
    and fancy indexing in the twin."""
    if len(set(table)) == 1:
        return table[0]
    if is_hdl(sel):
        out = Const(table[-1], range(min(table), max(table) + 1) if width is None else width)
        for i in range(len(table) - 2, -1, -1):
            out = Mux(sel == i, table[i], out)
        return out
    return np.asarray(table, dtype=np.int64)[np.asarray(sel)]


def _select_by(sel, options):
    """``options[sel]`` (a mux in RTL, per-element choice in the twin)."""
    if is_hdl(sel):
        out = options[-1]
        for i in range(len(options) - 2, -1, -1):
            out = Mux(sel == i, options[i], out)
        return out
    return np.choose(np.asarray(sel), [np.broadcast_to(o, np.shape(sel)) for o in options])


def _const_like(like, c: int):
    return Const(c) if is_hdl(like) else np.full(np.shape(like), c, dtype=np.int64)


def _false(like):
    return Const(0, 1) if is_hdl(like) else np.zeros(np.shape(like), dtype=bool)


# ----------------------------------------------------------------------------------------------
# The datapath as four steps (operands and multiply1 share pipeline stage 3, multiply2 is
# stage 4, update_state stage 5). Each works on NumPy int64 arrays (twin) and on Amaranth
# values (RTL) alike.

def operands(cfg: IzhikevichConfig, v, u, I, sel):
    """Operands: the accepted current (clamped and flagged when the host wrote one outside
    ``current_range``), ``w = v + B/(2A)`` and ``v`` rounded to multiplier width, and the
    ``I - u`` operand when dt is not a power of two."""
    r = cfg.rounding
    if cfg.current_clamp:
        I, i_low, i_high = clamp_flagged(I, cfg.i_lo_raw, cfg.i_hi_raw, cfg.I)
        i_flag = i_low | i_high
    else:
        i_flag = _false(v)
    sv = cfg.V.frac_bits - cfg.W.frac_bits
    woff = [w.raw for w in cfg.woff]
    if len(set(woff)) == 1:
        wq_full = round_shift_add(v, woff[0], sv, r)
    else:
        wq_full = round_shift(v + _lookup(woff, sel), sv, r)
    wq = narrow(wq_full, cfg.W, cfg.bounds_wq, "w operand")
    vq = narrow(round_shift(v, cfg.V.frac_bits - cfg.VQ.frac_bits, r), cfg.VQ, cfg.bounds_vq,
                "v operand")
    if cfg.dt_shift is not None:
        x = I
    else:
        x_full = round_shift(I, cfg.I.frac_bits - cfg.U.frac_bits, r) - u
        x = narrow(round_shift(x_full, cfg.U.frac_bits - cfg.X.frac_bits, r), cfg.X,
                   cfg.bounds_x, "I - u operand")
    return {"wq": wq, "vq": vq, "x": x, "i": I, "i_flag": i_flag}


def multiply1(cfg: IzhikevichConfig, wq, vq, x, u, sel):
    """Multipliers 1 and 3 (and 5, ``dt (I - u)``, when dt is not a power of two; when it is,
    ``dt I - dt u`` by shifts, the rounding of ``dt u`` folded into the subtraction)."""
    out = {"q": wq * _lookup([k.raw for k in cfg.KA], sel),
           "bvp": vq * _lookup([b.raw for b in cfg.beta], sel)}
    # y = round((b v - lambda u - b v_u) / 2**shift_y) is computed in stage 4 as
    # (bvp - uy) >> shift_y with uy = (lambda u + E) << shift_b, minus half an LSB of y when
    # rounding to nearest (exact, one adder)
    half_y = (1 << (cfg.shift_y - 1)) if cfg.rounding == "nearest" else 0
    e_sh = [(e.raw << cfg.shift_b) - half_y for e in cfg.E]
    if all(cfg.u_leak):
        uy = (u << cfg.shift_b) + _lookup(e_sh, sel)
    else:
        uy = _select_by(sel, [((u << cfg.shift_b) + es) if lam else _const_like(u, es)
                              for lam, es in zip(cfg.u_leak, e_sh)])
    out["uy"] = uy
    if cfg.dt_shift is not None:
        s, r = cfg.dt_shift, cfg.rounding
        dti = round_shift(x, cfg.I.frac_bits + s - cfg.V.frac_bits, r)
        su = cfg.U.frac_bits + s - cfg.V.frac_bits
        if su > 0 and r == "nearest":
            # dti - ((u >> su) + bit) == dti + ~(u >> su) + ~bit   (two's complement)
            bit_n = ~u[su - 1] if is_hdl(u) else 1 - ((u >> (su - 1)) & 1)
            out["x"] = dti + ~(u >> su) + bit_n
        else:
            out["x"] = dti - round_shift(u, su, r)
    else:
        out["x"] = x * cfg.KDT.raw
    return out


def multiply2(cfg: IzhikevichConfig, q, bvp, uy, wq, v, u, x, sel):
    """Multipliers 2 and 4: (A dt w) w and (a dt) y. Meanwhile the addends of stage 5 are
    prepared, pre-shifted to the products' scale with the rounding half folded in, so that
    each sum of stage 5 is a single adder: ``v + dt (I - u) + K0`` for ``v'``, ``u`` and
    ``u + d`` for ``u'``."""
    r = cfg.rounding
    qq = narrow(round_shift(q, cfg.shift_q, r), cfg.Q, cfg.bounds_qq, "q operand")
    y_full = (bvp - uy) >> cfg.shift_y
    y, y_low, y_high = clamp_flagged(y_full, cfg.Y.min_raw, cfg.Y.max_raw, cfg.Y,
                                     cfg.bounds_y)
    if cfg.dt_shift is not None:
        dx = x
    else:
        dx = round_shift(x, cfg.X.frac_bits + cfg.KDT.frac_bits - cfg.V.frac_bits, r)
    near = r == "nearest"
    vb = v + dx + _lookup([k.raw for k in cfg.K0], sel)
    vb_sh = (vb << cfg.shift_p) + ((1 << (cfg.shift_p - 1)) if near else 0)
    # threshold and lower clamp of v' become sign tests of sums formed in stage 5:
    # v' >= v_th  <=>  vb_sh - (v_th << shift_p) + p >= 0   (likewise for v_floor)
    vb_th = vb_sh - (cfg.VTH.raw << cfg.shift_p)
    vb_lo = vb_sh - (cfg.v_floor_raw << cfg.shift_p)
    shifts = cfg.shift_a
    halves = [(1 << (sa - 1)) if near else 0 for sa in shifts]
    ud = u + _lookup([d.raw for d in cfg.d], sel)
    if len(set(shifts)) == 1:
        u_sh = (u << shifts[0]) + halves[0]
        ud_sh = (ud << shifts[0]) + halves[0]
    else:
        u_sh = _select_by(sel, [(u << sa) + h for sa, h in zip(shifts, halves)])
        ud_sh = _select_by(sel, [(ud << sa) + h for sa, h in zip(shifts, halves)])
    return {"p": qq * wq, "m": y * _lookup([a.raw for a in cfg.alpha], sel),
            "vb_sh": vb_sh, "vb_th": vb_th, "vb_lo": vb_lo, "u_sh": u_sh, "ud_sh": ud_sh,
            "y_flag": y_low | y_high}


def update_state(cfg: IzhikevichConfig, vb_sh, vb_th, vb_lo, u_sh, ud_sh, p, m, sel):
    """Sum, threshold, reset and the flagged state clamps:
    ``v' = (vb_sh + p) >> shift_p`` and ``u' = (u_sh + m) >> shift_a`` (or ``ud_sh`` on a
    spike, i.e. ``u' = u + d + (a dt) y``) clamped once into ``[u_lo, u_hi]``. The threshold
    test and the floor of ``v'`` are signs of ``vb_th + p`` and ``vb_lo + p``; ``v'`` needs no
    upper clamp: above threshold it is replaced by ``c``. Returns the new state, the spike and
    the clamp flags of this update (``v_low``, ``u_high``, ``u_low``)."""
    v_pre = (vb_sh + p) >> cfg.shift_p
    spike = (vb_th + p) >= 0
    under = (vb_lo + p) < 0
    shifts = cfg.shift_a
    u_sum = select(spike, ud_sh, u_sh) + m
    if len(set(shifts)) == 1:
        u_pre = u_sum >> shifts[0]
    else:
        u_pre = _select_by(sel, [u_sum >> sa for sa in shifts])
    u_out, u_low, u_high = clamp_flagged(u_pre, cfg.u_lo_raw, cfg.u_hi_raw, cfg.U)
    v_keep = select(under, cfg.v_floor_raw,
                    narrow(v_pre, cfg.V, (cfg.v_floor_raw, cfg.VTH.raw), "v below threshold"))
    v_out = select(spike, _lookup([c.raw for c in cfg.c], sel), v_keep)
    v_low = under & ~spike
    return {"v": v_out, "u": u_out, "spike": spike, "v_pre": v_pre, "v_low": v_low,
            "u_high": u_high, "u_low": u_low}


def clamp_bits(flags: dict):
    """Pack the per-update clamp flags into the bit order of :data:`CLAMP_KINDS`
    (twin: an int64 array)."""
    return sum((np.asarray(flags[k], dtype=np.int64) << i) for i, k in enumerate(CLAMP_KINDS))


# ----------------------------------------------------------------------------------------------
class IzhikevichTwin:
    """Bit-exact NumPy (int64) model of :class:`IzhikevichCore`, vectorized over neurons.

    State is held as raw integers in the core's formats; :meth:`sweep` performs one update of
    every neuron exactly as the RTL does. :meth:`update` computes updates from any given state
    (used by benches to check the DUT from its own previous state).

    Saturation is visible as in the RTL: :meth:`update` returns each update's clamp flags;
    :attr:`clamp_sticky` (bit mask of :data:`CLAMP_KINDS`), :attr:`clamp_counts` (updates per
    kind since construction) and :attr:`last_sweep_clamps` (per kind, the last sweep) follow
    every :meth:`sweep`.

    Two implementations compute the same bits:

    ``kernel="stages"``
        The stage functions composed over NumPy arrays (the reference; with ``check=True``
        every wide intermediate is also tested against the int64 range, which the
        configuration has already proven once from the formats).
    ``kernel="numba"``
        The compiled per-neuron loop of :mod:`cuneate.hdl.izhikevich_kernel` (in place, no
        temporaries), proven bit-exact against the stage functions by property tests and
        long runs. The default whenever numba is available and ``check`` is off.

    ``threads`` (compiled kernel, :meth:`run` with constant currents) splits the population
    over threads; default: all cores from 2000 neurons on, else one.
    """

    KERNELS = ("stages", "numba")

    def __init__(self, config: IzhikevichConfig | None = None, check: bool = False,
                 kernel: str | None = None, threads: int | None = None, **kwargs):
        from . import izhikevich_kernel as _k
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        self.check = check
        if kernel is None:
            kernel = "numba" if (_k.available() and not check) else "stages"
        if kernel not in self.KERNELS:
            raise ValueError(f"unknown twin kernel {kernel!r}; known: {', '.join(self.KERNELS)}")
        if kernel == "numba" and not _k.available():
            raise ValueError("twin kernel 'numba' needs numba installed")
        self.kernel = kernel
        self.threads = threads
        self._k = _k
        self._consts = _k.gather_constants(cfg)
        self.sel = np.asarray(cfg.neuron_sets, dtype=np.int64)
        self.v = np.array(cfg.v_init_raw, dtype=np.int64)
        self.u = np.array(cfg.u_init_raw, dtype=np.int64)
        self.I = np.zeros(cfg.n_neurons, dtype=np.int64)
        self._spike = np.zeros(cfg.n_neurons, dtype=bool)
        self._counts = np.zeros(len(CLAMP_KINDS), dtype=np.int64)
        self.sweeps = 0
        self.clamp_sticky = 0
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}
        self.last_sweep_clamps = {k: 0 for k in CLAMP_KINDS}

    def set_currents(self, values_mv_per_ms, index=None) -> np.ndarray:
        """Quantize currents (mV/ms) like the host driver does and store them; returns raw.
        Values outside the current format saturate to it; values outside the accepted
        ``current_range`` are clamped (and flagged) by the datapath."""
        raw = self.cfg.I.to_raw(values_mv_per_ms)
        if index is None:
            self.I[:] = raw
        else:
            self.I[index] = raw
        return raw

    def update(self, v, u, I, sel):
        """One update of the given neurons (raw int64 arrays); returns the stage-5 dict with
        the clamp flags of every kind and their packed bits (``"clamp"``)."""
        if self.kernel == "numba":
            arrs = np.broadcast_arrays(*(np.asarray(x, dtype=np.int64) for x in (v, u, I, sel)))
            if arrs[0].ndim == 1:
                v, u, I, sel = (np.ascontiguousarray(a) for a in arrs)
                self._check_sel(sel)
                vo, uo, spk, clamp, v_pre = self._k.update_arrays(self._consts, v, u, I, sel)
                out = {"v": vo, "u": uo, "spike": spk, "v_pre": v_pre, "clamp": clamp}
                for b, k in enumerate(CLAMP_KINDS):
                    out[k] = ((clamp >> b) & 1).astype(bool)
                return out
        return self.update_stages(v, u, I, sel)

    def _check_sel(self, sel):
        if sel.size and (sel.min() < 0 or sel.max() >= len(self.cfg.params)):
            raise ValueError(f"parameter-set index out of range 0..{len(self.cfg.params) - 1}")

    def update_stages(self, v, u, I, sel):
        """:meth:`update` by the stage functions (the reference implementation)."""
        cfg = self.cfg
        v, u, I, sel = (np.asarray(x, dtype=np.int64) for x in (v, u, I, sel))
        s2 = operands(cfg, v, u, I, sel)
        s3 = multiply1(cfg, s2["wq"], s2["vq"], s2["x"], u, sel)
        s4 = multiply2(cfg, s3["q"], s3["bvp"], s3["uy"], s2["wq"], v, u, s3["x"], sel)
        if self.check:
            for k in ("q", "bvp", "x", "uy"):
                check_int64(k, s3[k])
            for k in ("p", "m", "vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh"):
                check_int64(k, s4[k])
        out = update_state(cfg, *(s4[k] for k in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh",
                                                  "p", "m")), sel)
        out["current"] = np.broadcast_to(s2["i_flag"], v.shape)
        out["y"] = np.broadcast_to(s4["y_flag"], v.shape)
        out["clamp"] = clamp_bits(out)
        return out

    def _account(self, counts):
        tally_clamps(self, CLAMP_KINDS, counts)
        for i, k in enumerate(CLAMP_KINDS):
            self.last_sweep_clamps[k] = int(counts[i])

    def sweep(self):
        """Update every neuron once (one tick); returns the boolean spike vector."""
        if self.kernel == "numba":
            self._k.sweep_inplace(self._consts, self.v, self.u, self.I, self.sel, self._spike,
                                  self._counts)
            self.sweeps += 1
            self._account(self._counts)
            return self._spike.copy()
        out = self.update_stages(self.v, self.u, self.I, self.sel)
        self.v, self.u = out["v"].astype(np.int64), out["u"].astype(np.int64)
        self.sweeps += 1
        self._account([np.count_nonzero(out[k]) for k in CLAMP_KINDS])
        return np.asarray(out["spike"], dtype=bool)

    def run(self, currents, n_sweeps: int, progress=None) -> list[np.ndarray]:
        """Run ``n_sweeps`` ticks with currents given as a number, a (n_neurons,) array, or a
        callable ``f(t_ms) -> array``, read at the start of each update. Returns spike times (ms)
        per neuron with the golden convention (update k -> (k+1) dt). ``progress``, if given,
        is called with the number of sweeps done every 1000 sweeps."""
        hits_k, hits_n = [], []
        const = None if callable(currents) else np.broadcast_to(currents, (self.cfg.n_neurons,))
        if const is not None:
            self.set_currents(const)
        if const is not None and self.kernel == "numba":
            done = 0
            block = 1000 if progress is not None else max(n_sweeps, 1)
            last = None
            while done < n_sweeps:
                todo = min(block, n_sweeps - done)
                ks, ns, totals, last = self._k.run_sweeps(self._consts, self.v, self.u, self.I,
                                                          self.sel, todo, k0=done,
                                                          threads=self.threads)
                hits_k.append(ks)
                hits_n.append(ns)
                tally_clamps(self, CLAMP_KINDS, totals)
                done += todo
                self.sweeps += todo
                if progress is not None and done % 1000 == 0:
                    progress(done)
            if last is not None:
                self.last_sweep_clamps = {k: int(last[i]) for i, k in enumerate(CLAMP_KINDS)}
        else:
            for k in range(n_sweeps):
                if const is None:
                    self.set_currents(np.broadcast_to(currents(k * self.cfg.dt_ms),
                                                      (self.cfg.n_neurons,)))
                spk = self.sweep()
                if spk.any():
                    idx = np.flatnonzero(spk)
                    hits_n.append(idx)
                    hits_k.append(np.full(idx.size, k, dtype=np.int64))
                if progress is not None and (k + 1) % 1000 == 0:
                    progress(k + 1)
        steps = golden.group_spikes(hits_k, hits_n, self.cfg.n_neurons)
        return [(s + 1) * self.cfg.dt_ms for s in steps]

    def clamp_report(self) -> dict:
        """Sticky flags and counts per clamp kind (for reports and ``simulate --json``)."""
        return {"sticky": {k: bool(self.clamp_sticky >> i & 1)
                           for i, k in enumerate(CLAMP_KINDS)},
                "counts": dict(self.clamp_counts)}

    def v_mv(self):
        return self.cfg.V.to_float(self.v)

    def u_mv(self):
        return self.cfg.U.to_float(self.u)


# ----------------------------------------------------------------------------------------------
class IzhikevichCore(wiring.Component):
    """Time-multiplexed Izhikevich core: one neuron update per clock, 5-stage pipeline.

    Pipeline (a neuron's index enters at cycle t; its result is on ``upd_*`` at t+5):

    1. **Fetch** - the sweep counter addresses the state (v, u), current and set-select RAMs
       (synchronous read).
    2. **Read** - the RAM outputs are registered (no logic after the block RAM).
    3. **Operands, multiply 1** - ``w = v + 62.5`` and ``v`` rounded to multiplier width, then
       ``(A dt) w`` and ``b v``; ``dt I - dt u`` by shifts (or ``I - u`` rounded and
       multiplied by ``dt`` when dt is not a power of two).
    4. **Multiply 2** - ``((A dt) w) w`` and ``(a dt)(b v - u)``; meanwhile
       ``v + dt (I - u) + dt (C - B^2/4A)`` is summed.
    5. **Update** - add the products into ``v'`` and ``u'`` (rounding as a carry-in),
       threshold, reset, saturate; write back to the state RAM and register the outputs.

    Sweeps start on a tick (internal divider of ``clock_hz / update_hz`` cycles, or the ``tick``
    input with ``tick_source="external"``). A tick that arrives while a sweep is still being
    issued is ignored and sets the sticky ``overrun`` flag.

    Ports
    -----
    ``i_wr_en/i_wr_addr/i_wr_data``
        Host write of a neuron's input current (format ``config.I``). It lands in the current RAM
        only, which the pipeline never writes, so it cannot corrupt an update in flight; a write
        in the same cycle as that neuron's fetch is seen from the next sweep on.
    ``sel_wr_en/sel_wr_addr/sel_wr_data``
        Host write of a neuron's parameter-set index (same rules).
    ``spike_valid/spike_ready/spike_index/spike_sweep``
        Spike stream (FIFO of ``spike_fifo_depth``); when full, further spikes are dropped and
        the sticky ``spike_overflow`` flag is set - nothing is lost silently.
    ``upd_valid/upd_index/upd_v/upd_u/upd_current/upd_spike/upd_clamp``
        Every update as it leaves the pipeline (for scoreboards and probes); ``upd_current`` is
        the current as the host wrote it, ``upd_clamp`` the clamps that acted in this update
        (one bit per kind of :data:`CLAMP_KINDS`, bit 0 = ``v_low``).
    ``sweep_done/sweep_count/sweep_number``
        Pulse in the cycle after the last update of a sweep is on ``upd_*``, with the number of
        spikes in that sweep and its number.
    ``sweep_clamps_<kind>``
        With ``sweep_done``: how many updates of that sweep clamped, per kind.
    ``clamp_flags/clamp_clear``
        Sticky clamp flags (bit per kind), set by any clamp since reset; ``clamp_clear`` clears
        them (a clamp in the same cycle keeps its flag set: nothing is lost).
    """

    def __init__(self, config: IzhikevichConfig | None = None, **kwargs):
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        N = cfg.n_neurons
        sig = {
            "i_wr_en": In(1), "i_wr_addr": In(range(N)), "i_wr_data": In(cfg.I.shape()),
            "sel_wr_en": In(1), "sel_wr_addr": In(range(N)), "sel_wr_data": In(cfg.sel_bits),
            "spike_valid": Out(1), "spike_ready": In(1), "spike_index": Out(range(N)),
            "spike_sweep": Out(cfg.sweep_number_width), "spike_overflow": Out(1),
            "upd_valid": Out(1), "upd_index": Out(range(N)), "upd_v": Out(cfg.V.shape()),
            "upd_u": Out(cfg.U.shape()), "upd_current": Out(cfg.I.shape()),
            "upd_spike": Out(1), "upd_clamp": Out(len(CLAMP_KINDS)),
            "clamp_flags": Out(len(CLAMP_KINDS)), "clamp_clear": In(1),
            "sweep_done": Out(1), "sweep_count": Out(range(N + 1)),
            "sweep_number": Out(cfg.sweep_number_width), "overrun": Out(1), "busy": Out(1),
        }
        for k in CLAMP_KINDS:
            sig[f"sweep_clamps_{k}"] = Out(range(N + 1))
        if cfg.tick_source == "external":
            sig["tick"] = In(1)
        super().__init__(sig)

    def elaborate(self, platform):
        cfg = self.cfg
        N = cfg.n_neurons
        m = Module()
        V, U = cfg.V, cfg.U

        def pack(v, u):
            return (v & ((1 << V.width) - 1)) | ((u & ((1 << U.width) - 1)) << V.width)

        init_state = [pack(int(v), int(u)) for v, u in zip(cfg.v_init_raw, cfg.u_init_raw)]
        m.submodules.state_mem = state_mem = Memory(shape=V.width + U.width, depth=N,
                                                    init=init_state)
        m.submodules.cur_mem = cur_mem = Memory(shape=cfg.I.shape(), depth=N, init=[])
        m.submodules.sel_mem = sel_mem = Memory(shape=cfg.sel_bits, depth=N,
                                                init=cfg.neuron_sets)
        st_rd, st_wr = state_mem.read_port(), state_mem.write_port()
        cur_rd, cur_wr = cur_mem.read_port(), cur_mem.write_port()
        sel_rd, sel_wr = sel_mem.read_port(), sel_mem.write_port()
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
        start = tick & (~issuing | last_issue)   # a tick in the last issuing cycle is on time
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

        for port in (st_rd, cur_rd, sel_rd):
            m.d.comb += [port.addr.eq(addr), port.en.eq(1)]

        # --- pipeline valid/index/sweep tags -----------------------------------------------
        def tag(n):
            return (Signal(name=f"valid{n}"), Signal(range(N), name=f"idx{n}"),
                    Signal(cfg.sweep_number_width, name=f"swp{n}"))
        t2, t3, t4, t5 = tag(2), tag(3), tag(4), tag(5)
        m.d.sync += [t2[0].eq(issuing), t2[1].eq(addr), t2[2].eq(sweep_no)]
        for a, b in ((t2, t3), (t3, t4), (t4, t5)):
            m.d.sync += [b[0].eq(a[0]), b[1].eq(a[1]), b[2].eq(a[2])]

        # --- stage 2: the RAM outputs go straight into registers -------------------------
        def reg(name, value, stage):
            sig_ = Signal(value.shape(), name=f"{name}{stage}")
            m.d.sync += sig_.eq(value)
            return sig_

        v3 = reg("v", st_rd.data[:V.width].as_signed(), 3)
        u3 = reg("u", st_rd.data[V.width:].as_signed(), 3)
        i3, sel3 = reg("i", cur_rd.data, 3), reg("sel", sel_rd.data, 3)
        # what an update starts from, for the formal harness (hdl/formal_core.py)
        self.probes = {"valid": t3[0], "index": t3[1], "v": v3, "u": u3, "i": i3, "sel": sel3}
        # --- stage 3: operands and the first multipliers ----------------------------------
        s2 = operands(cfg, v3, u3, i3, sel3)
        wq3, vq3, x3 = s2["wq"], s2["vq"], s2["x"]
        s3 = multiply1(cfg, wq3, vq3, x3, u3, sel3)
        v4, u4, i4, sel4, wq4 = (reg(n, x, 4) for n, x in
                                 (("v", v3), ("u", u3), ("i", i3), ("sel", sel3), ("wq", wq3)))
        q4, bvp4, x4 = reg("q", s3["q"], 4), reg("bvp", s3["bvp"], 4), reg("x", s3["x"], 4)
        uy4 = reg("uy", s3["uy"], 4)
        fi4 = reg("flag_current", s2["i_flag"], 4)
        # --- stage 4 ----------------------------------------------------------------------
        s4 = multiply2(cfg, q4, bvp4, uy4, wq4, v4, u4, x4, sel4)
        i5, sel5 = reg("i", i4, 5), reg("sel", sel4, 5)
        p5, m5 = reg("p", s4["p"], 5), reg("m", s4["m"], 5)
        sums5 = [reg(n, s4[n], 5) for n in ("vb_sh", "vb_th", "vb_lo", "u_sh", "ud_sh")]
        fi5, fy5 = reg("flag_current", fi4, 5), reg("flag_y", s4["y_flag"], 5)
        # --- stage 5 ----------------------------------------------------------------------
        s5 = update_state(cfg, *sums5, p5, m5, sel5)
        v_out = Signal(V.shape())
        u_out = Signal(U.shape())
        spike = Signal()
        clamp = Signal(len(CLAMP_KINDS))
        flags = {"v_low": s5["v_low"], "u_high": s5["u_high"], "u_low": s5["u_low"],
                 "current": fi5, "y": fy5}
        m.d.comb += [v_out.eq(s5["v"]), u_out.eq(s5["u"]), spike.eq(s5["spike"] & t5[0]),
                     clamp.eq(Mux(t5[0], Cat(*(flags[k] for k in CLAMP_KINDS)), 0))]
        m.d.comb += [st_wr.addr.eq(t5[1]), st_wr.data.eq(Cat(v_out, u_out)),
                     st_wr.en.eq(t5[0])]
        m.d.sync += [self.upd_valid.eq(t5[0]), self.upd_index.eq(t5[1]), self.upd_v.eq(v_out),
                     self.upd_u.eq(u_out), self.upd_current.eq(i5), self.upd_spike.eq(spike),
                     self.upd_clamp.eq(clamp)]

        # --- bookkeeping from the registered outputs (off the datapath's critical path) -----
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
        # clamp bookkeeping: per-sweep counters and sticky flags
        for i, k in enumerate(CLAMP_KINDS):
            cnt = Signal(range(N + 1), name=f"clamp_count_{k}")
            with m.If(last):
                m.d.sync += [getattr(self, f"sweep_clamps_{k}").eq(cnt + self.upd_clamp[i]),
                             cnt.eq(0)]
            with m.Elif(self.upd_valid):
                m.d.sync += cnt.eq(cnt + self.upd_clamp[i])
        m.d.sync += self.clamp_flags.eq(Mux(self.clamp_clear, 0, self.clamp_flags)
                                        | self.upd_clamp)

        # --- spike stream -----------------------------------------------------------------
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
