"""The JSON description of an Izhikevich configuration, written beside its Verilog: timing,
pipeline, formats, constants, proven range, clamps and worst cases
(:meth:`IzhikevichConfig.to_dict <cuneate.hdl.izhikevich.config.IzhikevichConfig.to_dict>`).
The configuration is passed in (this module does not import it: the configuration's methods
call here)."""

from __future__ import annotations

import numpy as np


__all__ = ["describe", "clamps_dict"]


def clamps_dict(self, kinds) -> dict:
    """The clamps of configuration ``self`` (an ``IzhikevichConfig``; ``kinds``: its
    ``CLAMP_KINDS``), their levels and whether each can act for accepted inputs."""
    return {
        "kinds": list(kinds),
        "v_low": {"level_mV": self.v_floor, "raw": self.v_floor_raw,
                  "can_act_for_accepted_inputs": self.clamp_can_act["v_low"]},
        "u_high": {"level": self.u_hi, "raw": self.u_hi_raw,
                   "can_act_for_accepted_inputs": self.clamp_can_act["u_high"]},
        "u_low": {"level": self.u_lo, "raw": self.u_lo_raw,
                  "can_act_for_accepted_inputs": self.clamp_can_act["u_low"]},
        "current": {"range": [self.i_lo, self.i_hi], "raw": [self.i_lo_raw, self.i_hi_raw],
                    "built": self.current_clamp,
                    "can_act_for_accepted_inputs": False},
        "y": {"format": str(self.Y), "built": self.y_int_bits is not None,
              "can_act_for_accepted_inputs": self.clamp_can_act["y"]},
    }

def describe(self, kinds) -> dict:
    """Everything a user of the generated Verilog needs (written beside it as JSON)."""
    consts = [self.VTH, self.V0] + ([self.KDT] if self.KDT else []) + self.KA + \
        self.woff + self.K0 + self.alpha + self.beta + self.c + self.d + self.E + self.u0
    bv, bu = self.one_step_bound(np.array([self.v_floor / 2, -65.0, self.v_th]),
                                 np.array([0.0, -13.0, 0.0]), np.zeros(3))
    return {
        "block": "IzhikevichCore", "scheme": "euler", "n_neurons": self.n_neurons,
        "clock_hz": self.clock_hz, "update_hz": self.update_hz, "dt_ms": self.dt_ms,
        "cycles_per_tick": self.cycles_per_tick, "pipeline_depth": self.pipeline_stages,
        "latency_cycles": self.pipeline_stages, "throughput": "one neuron update per cycle",
        "pipeline_cuts": list(self.cuts),
        "rounding": self.rounding, "tick_source": self.tick_source,
        "saturation": self.saturation,
        "dt_is_shift": self.dt_shift is not None,
        "multipliers": 4 if self.dt_shift is not None else 5,
        "multiplier_operands": {"(A dt) w": [self.operand_width, self.W.width],
                                "q w": [self.Q.width, self.W.width],
                                "b v": [self.operand_width, self.VQ.width],
                                "(a dt) y": [max(a.width for a in self.alpha),
                                             self.Y.width]}
        | ({"dt (I - u)": [self.KDT.width, self.X.width]} if self.X else {}),
        "accepted_current_range": [self.i_lo, self.i_hi],
        "formats": {k: getattr(self, k).to_dict() for k in ("V", "U", "I", "W", "VQ", "Q",
                                                             "Y")}
        | ({"X": self.X.to_dict()} if self.X else {}),
        "param_sets": [p.to_dict() for p in self.params],
        "constants": {c.name: c.to_dict() for c in consts},
        "proven_range": {
            "method": "u: worst-case stimulus search (float64 forward Euler at the core's "
                      "dt, cuneate.hdl.izhikevich.range); v: proven lower bound from u's "
                      "bound; margins as documented there",
            "v": list(self.proven["v"]), "u": list(self.proven["u"]),
            "per_set": [r.to_dict() for r in self.ranges],
            "v_int_bits_needed": self.v_int_bits_derived,
            "u_int_bits_needed": self.u_int_bits_derived},
        "clamps": clamps_dict(self, kinds),
        "worst_case": {"v_pre_max_mV": self.v_pre_max,
                       "v_range": [self.v_floor, self.v_th],
                       "u_range": [self.u_lo, self.u_hi],
                       "y_range": list(self.y_range),
                       "one_step_bound_v_mV_at_rest": float(bv[1]),
                       "one_step_bound_u_at_rest": float(bu[1]),
                       "one_step_bound_v_mV_at_threshold": float(bv[2])},
        "state_word_bits": self.V.width + self.U.width,
    }
