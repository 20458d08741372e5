"""What the k-induction tests of the time-multiplexed blocks share: the verdict a mutant's
shallow bounded run must give, and a block whose update stage is off by one LSB."""


def assert_fails_first_at(r, check, step):
    """``r`` (a ``ProofResult``) failed in the base case at ``step``, naming ``check``."""
    assert r.status == "fail" and r.phase == "basecase" and r.step == step, r
    assert check in r.failed, r


def v_one_high(block):
    """``block`` (a component class with a static ``update_state`` stage) whose update stage
    gives ``v + 1``; the proof's reference keeps the true stage function."""
    class VOneHigh(block):
        @staticmethod
        def update_state(cfg, *args):
            out = dict(block.update_state(cfg, *args))
            out["v"] = out["v"] + 1
            return out
    return VOneHigh
