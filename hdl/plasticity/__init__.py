"""The plasticity block: a cuneate layer that learns its afferent synapses on chip with
activity-intensity-dependent plasticity (AIDP, :mod:`cuneate.golden.aidp`).

``config``       :class:`PlasticityConfig`
``datapath``     the stage functions (synapse calcium, learning drive, step; interneuron, drive)
``stage``        :class:`SynapseStage`, the learning stage: the synapse memory and its pipeline
``twin``         :class:`PlasticityTwin`, the bit-exact integer model
``kernel``       the twin's compiled (numba) loop
``core``         :class:`LearningLayer` (Amaranth) and its Verilog
``formal_core``  the k-induction of the learning stage against its one-operation specification
"""

from .config import (CLAMP_KINDS, CN_CLAMP_KINDS, OPS, STAGE_LATENCY, SYNAPSE_CLAMP_KINDS,
                     ConfigError, PlasticityConfig)

__all__ = ["PlasticityConfig", "ConfigError", "CLAMP_KINDS", "CN_CLAMP_KINDS",
           "SYNAPSE_CLAMP_KINDS", "OPS", "STAGE_LATENCY"]
