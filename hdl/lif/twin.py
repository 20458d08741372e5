"""The bit-exact integer twin of the LIF core: the datapath's stage functions (or their compiled
restatement, :mod:`cuneate.hdl.lif.kernel`) over NumPy int64 arrays, one :meth:`LifTwin.sweep`
per tick."""

from __future__ import annotations

import numpy as np

from ...golden.izhikevich import group_spikes, spike_times
from ..lib.fixed import check_int64, clamp_report, store_raw, tally_clamps
from ..lib.synapses import trace_products, trace_update
from .config import CLAMP_KINDS, LifConfig
from .datapath import clamp_bits, gather_input, leak_operand, leak_product, update_state

__all__ = ["LifTwin"]


class LifTwin:
    """Bit-exact NumPy (int64) model of :class:`LifCore`, vectorized over neurons.

    :meth:`sweep` performs one tick (every neuron once) with the input spikes ``x`` of that
    tick; :meth:`run` a whole program; :meth:`update` computes updates from any given state
    (used by scoreboards, always by the stage functions). Clamp flags, sticky bits and counters
    follow the RTL's (:meth:`clamp_report`).

    Two implementations of :meth:`sweep` and :meth:`run` compute the same bits: ``kernel=
    "stages"`` (the stage functions over NumPy arrays; with ``check=True`` the leak product is
    also tested against the int64 range) and ``kernel="numba"`` (the compiled loop of
    :mod:`cuneate.hdl.lif.kernel`, proven bit-exact against the stages by property tests and
    long runs; the default whenever numba is available, ``check`` is off and the configuration
    is covered). ``threads`` (compiled kernel, :meth:`run_raw` / :meth:`run`) splits the
    population over threads; default: all cores from 2000 neurons on, else one.
    """

    KERNELS = ("stages", "numba")

    def __init__(self, config: LifConfig | None = None, check: bool = False,
                 kernel: str | None = None, threads: int | None = None, **kwargs):
        from . import kernel as _k
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
        self.history = np.zeros((cfg.max_input_delay, cfg.n_inputs), dtype=bool)
        self.sweeps = 0
        self.clamp_sticky = 0
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}

    def delay_inputs(self, x):
        """The input vector the sweep of this tick uses, given the spikes ``x`` received before
        its tick: source ``i`` delayed by ``input_delays[i]`` ticks (the core's input history,
        advanced by one tick). Without delays ``x`` itself."""
        if not self.cfg.max_input_delay:
            return x
        xs = np.zeros(self.cfg.n_inputs, dtype=bool) if x is None else np.asarray(x, dtype=bool)
        d = np.asarray(self.cfg.input_delays)
        hist = np.vstack([xs[None, :], self.history])
        out = hist[d, np.arange(d.size)]
        self.history = hist[:-1].copy()
        return out

    def set_currents(self, values, index=None) -> np.ndarray:
        """Quantize currents like the host does (saturating to the current format)."""
        return store_raw(self.I, self.cfg.I, values, index)

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
        if cfg.traces:
            tr = [np.asarray(t, dtype=np.int64) for t in (self.traces if traces is None
                                                          else traces)]
        g = gather_input(cfg, I, [bool(b) for b in xs], [W[:, i] for i in range(cfg.n_inputs)],
                         tr)
        xop = leak_operand(cfg, v, g["d"], sel)
        d = leak_product(cfg, xop, sel)
        if self.check:
            check_int64("leak product", d)
        out = update_state(cfg, v, d, g["d"], ref, sel)
        if cfg.traces:
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
        out = self.update(self.v, self.ref, self.I, self.delay_inputs(x), self.sel)
        self.v = np.asarray(out["v"], dtype=np.int64)
        self.ref = np.asarray(out["ref"], dtype=np.int64)
        if self.cfg.traces:
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
            return [spike_times(s, self.cfg.dt_ms) for s in steps]
        for k in range(n_sweeps):
            if callable(currents):
                self.set_currents(np.broadcast_to(currents(k * self.cfg.dt_ms),
                                                  (self.cfg.n_neurons,)))
            spk = self.sweep(None if inputs is None else inputs[k])
            for n in np.flatnonzero(spk):
                hits[n].append(k)
        return [spike_times(h, self.cfg.dt_ms) for h in hits]

    def clamp_report(self) -> dict:
        """Sticky flags and counts per clamp kind (for reports and ``simulate --json``)."""
        return clamp_report(self, CLAMP_KINDS)

    def v_float(self):
        return self.cfg.V.to_float(self.v)


# ----------------------------------------------------------------------------------------------
