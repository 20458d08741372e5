"""The bit-exact integer twin of the Izhikevich core: the datapath's stage functions (or their
compiled restatement, :mod:`cuneate.hdl.izhikevich.kernel`) over NumPy int64 arrays, one element
per neuron, one :meth:`IzhikevichTwin.sweep` per tick."""

from __future__ import annotations

import numpy as np

from ...golden import izhikevich as golden
from ..lib.fixed import check_int64, clamp_report, store_raw, tally_clamps
from ..lib.kernel import choose_kernel
from .config import CLAMP_KINDS, IzhikevichConfig
from .datapath import clamp_bits, one_update

__all__ = ["IzhikevichTwin", "IzhikevichArrayTwin", "SPECIALIZE_MIN_UPDATES"]

#: A run with constant currents of at least this many updates (neurons x sweeps) takes the
#: loop compiled for its configuration (the first such run of a configuration compiles it).
SPECIALIZE_MIN_UPDATES = 10_000_000


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
        The compiled per-neuron loop of :mod:`cuneate.hdl.izhikevich.kernel` (in place, no
        temporaries), proven bit-exact against the stage functions by property tests and
        long runs. The default whenever numba is available and ``check`` is off.

    ``threads`` (compiled kernel, :meth:`run` with constant currents) splits the population
    over threads; default: two cores from 512 neurons and 2e6 updates on (a block each),
    else one. ``specialize``: such a
    run's loop compiled for this configuration (its constants folded in:
    :func:`~cuneate.hdl.izhikevich.kernel.specialized`, about 2x; compiled once per
    configuration, cached on disk); default from :data:`SPECIALIZE_MIN_UPDATES` updates on.
    """

    KERNELS = ("stages", "numba")

    def __init__(self, config: IzhikevichConfig | None = None, check: bool = False,
                 kernel: str | None = None, threads: int | None = None,
                 specialize: bool | None = None, **kwargs):
        from . import kernel as _k
        self.cfg = cfg = config or IzhikevichConfig(**kwargs)
        self.check = check
        self.kernel = kernel = choose_kernel(kernel, self.KERNELS, numba_default=not check)
        self.threads = threads
        self.specialize = specialize
        self._k = _k
        self._consts = _k.gather_constants(cfg)
        self.sel = np.asarray(cfg.neuron_sets, dtype=np.int64)
        self.v = np.array(cfg.v_init_raw, dtype=np.int64)
        self.u = np.array(cfg.u_init_raw, dtype=np.int64)
        self.I = np.zeros(cfg.n_neurons, dtype=np.int64)
        self._spike = np.zeros(cfg.n_neurons, dtype=bool)
        self._counts = np.zeros(len(CLAMP_KINDS), dtype=np.int64)
        self._scratch = None
        self.sweeps = 0
        self.clamp_sticky = 0
        self.clamp_counts = {k: 0 for k in CLAMP_KINDS}
        self.last_sweep_clamps = {k: 0 for k in CLAMP_KINDS}

    def set_currents(self, values_mv_per_ms, index=None) -> np.ndarray:
        """Quantize currents (mV/ms) like the host driver does and store them; returns raw.
        Values outside the current format saturate to it; values outside the accepted
        ``current_range`` are clamped (and flagged) by the datapath."""
        return store_raw(self.I, self.cfg.I, values_mv_per_ms, index)

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
        """:meth:`update` by the pipelined steps of the core (the reference implementation:
        :func:`~cuneate.hdl.izhikevich.datapath.one_update`)."""
        cfg = self.cfg
        v, u, I, sel = (np.asarray(x, dtype=np.int64) for x in (v, u, I, sel))
        vals = one_update(cfg, v, u, I, sel)
        if self.check:
            for k, x in vals.items():
                if isinstance(x, np.ndarray) and x.dtype.kind == "i":
                    check_int64(k, x)
        out = {k: vals[k] for k in ("v", "u", "spike", "v_pre", "v_low", "u_high", "u_low")}
        out["current"] = np.broadcast_to(vals["i_flag"], v.shape)
        out["y"] = np.broadcast_to(vals["y_flag"], v.shape)
        out["clamp"] = clamp_bits(out)
        return out

    def _account(self, counts):
        tally_clamps(self, CLAMP_KINDS, counts)
        for i, k in enumerate(CLAMP_KINDS):
            self.last_sweep_clamps[k] = int(counts[i])

    def sweep(self):
        """Update every neuron once (one tick); returns the boolean spike vector."""
        if self.kernel == "numba":
            if self._scratch is None:
                self._scratch = self._k.sweep_scratch(self.cfg.n_neurons)
            self._k.sweep_inplace(self._consts, self.v, self.u, self.I, self.sel, self._spike,
                                  self._counts, self._scratch)
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
            special = self.specialize if self.specialize is not None else \
                self.cfg.n_neurons * n_sweeps >= SPECIALIZE_MIN_UPDATES
            done = 0
            block = 1000 if progress is not None else max(n_sweeps, 1)
            last = None
            while done < n_sweeps:
                todo = min(block, n_sweeps - done)
                ks, ns, totals, last = self._k.run_sweeps(self._consts, self.v, self.u, self.I,
                                                          self.sel, todo, k0=done,
                                                          threads=self.threads,
                                                          special=special)
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
        return golden.group_spikes(hits_k, hits_n, self.cfg.n_neurons, self.cfg.dt_ms)[1]

    def clamp_report(self) -> dict:
        """Sticky flags and counts per clamp kind (for reports and ``simulate --json``)."""
        return clamp_report(self, CLAMP_KINDS)

    def v_mv(self):
        return self.cfg.V.to_float(self.v)

    def u_mv(self):
        return self.cfg.U.to_float(self.u)


class IzhikevichArrayTwin:
    """The bit-exact model of :class:`~cuneate.hdl.izhikevich.array.IzhikevichArray`: one
    :class:`IzhikevichTwin` per core (``twins[k]`` holds the global ids ``k * n_neurons ..
    (k + 1) * n_neurons - 1``), all swept by the one tick; ``neuron_sets`` as the array's
    (:func:`~cuneate.hdl.izhikevich.array.core_configs`)."""

    def __init__(self, config: IzhikevichConfig, n_cores: int, neuron_sets=None, **kwargs):
        from .array import core_configs
        self.cfg, self.n_cores = config, n_cores
        self.twins = [IzhikevichTwin(c, **kwargs)
                      for c in core_configs(config, n_cores, neuron_sets)]

    def set_current_raw(self, neuron: int, raw: int) -> None:
        """Store the raw current of global neuron ``neuron`` (a host write)."""
        core, local = divmod(int(neuron), self.cfg.n_neurons)
        self.twins[core].I[local] = raw

    def sweep(self) -> np.ndarray:
        """One tick of every core; returns the spike vector over the global ids."""
        return np.concatenate([t.sweep() for t in self.twins])
