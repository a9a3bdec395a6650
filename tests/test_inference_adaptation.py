"""Tests of the fitted moves' settings and schedule (bayes_inerter.inference.sampling.adaptation)."""

import numpy as np
import pytest

from bayes_inerter.inference.sampling import adaptation as adaptation_module
from bayes_inerter.inference.sampling.adaptation import FIT_MAX_STEPS, STRETCH, Adaptation, Schedule
from bayes_inerter.inference.sampling.moves import BlockMove


def test_adaptation_fits_after_the_transient_only():
    rng = np.random.default_rng(1)
    chain = rng.normal(size=(300, 20, 3))
    still = rng.normal(0.0, 1.0, size=(300, 20))
    adapt = Adaptation(every=400)
    move, block = adapt.fit(chain, still)  # 300 steps in equilibrium: at least every // 2
    assert move is not None and isinstance(block, BlockMove)
    np.testing.assert_allclose(move.mean, 0.0, atol=0.05)
    climbing = still - np.r_[np.linspace(500.0, 0.0, 150), np.zeros(150)][:, None]
    assert adapt.fit(chain, climbing) == (None, None)  # about 150 steps after the climb: fewer
    moves = adapt.moves([("a", 0.6), ("b", 0.4)], move)
    assert [w for _, w in moves] == pytest.approx([0.3, 0.2, 0.5])
    assert adapt.moves([("a", 1.0)], None) == [("a", 1.0)]
    for bad in (dict(weight=1.0), dict(weight=0.0), dict(every=1), dict(every=2.5), dict(dof=0.0), dict(wide=1.0),
                dict(knots=3), dict(blocks=1.0)):
        with pytest.raises(ValueError, match="adaptation"):
            Adaptation(**bad)


def test_a_long_chain_is_fitted_from_its_steps_thinned_to_the_most_a_fit_takes(monkeypatch):
    rng = np.random.default_rng(2)
    chain = rng.normal(size=(900, 10, 3)) * np.linspace(1.0, 3.0, 900)[:, None, None]  # the spread grows
    still = rng.normal(0.0, 1.0, size=(900, 10))
    adapt = Adaptation(every=200, knots=None, blocks=0.0)
    whole = adapt.fit(chain, still)[0]
    every_third = adapt.fit(chain[::3], still[::3])[0]  # 300 steps: fitted from each
    monkeypatch.setattr(adaptation_module, "FIT_MAX_STEPS", 300)
    thinned = adapt.fit(chain, still)[0]
    np.testing.assert_array_equal(thinned.chol, every_third.chol)
    np.testing.assert_array_equal(thinned.mean, every_third.mean)
    assert not np.allclose(thinned.chol, whole.chol, rtol=1e-6)
    assert FIT_MAX_STEPS >= 1000  # a chain of a few thousand steps is thinned a few times at most


def test_adaptation_describes_one_t_in_the_sampler_coordinates_as_before():
    # the fitted runs' moves in fit.json name the kernel: one t in the sampler's
    # coordinates (the default until 2026-11-25) is described as it always was
    assert Adaptation(knots=None, blocks=0.0).describe().startswith("IndependenceMove 0.5 (t, dof 10,")


def test_adaptation_in_normal_scores_with_block_moves_shares_its_weight_and_says_so():
    rng = np.random.default_rng(3)
    chain = rng.lognormal(size=(300, 20, 3))
    still = rng.normal(0.0, 1.0, size=(300, 20))
    adapt = Adaptation(every=400, knots=100, blocks=0.4)
    move, block = adapt.fit(chain, still)
    assert move.scores is not None and isinstance(block, BlockMove)
    assert block.scores is move.scores  # one map, fitted once
    moves = adapt.moves([("a", 0.6), ("b", 0.4)], move, block)
    assert [w for _, w in moves] == pytest.approx([0.3, 0.2, 0.3, 0.2])
    assert moves[2][0] is move and moves[3][0] is block
    assert Adaptation(every=400, knots=100, blocks=0.0).fit(chain, still)[1] is None  # none asked for
    assert "normal scores (100 knots); 0.4 of its share to block moves" in adapt.describe()
    assert Adaptation().knots == 200 and Adaptation().blocks == 0.5  # the defaults
    for bad in (dict(knots=None), dict(knots=100, blocks=1.0), dict(knots=3)):
        with pytest.raises(ValueError, match="adaptation"):
            Adaptation(**bad)


def test_adaptation_with_correlated_blocks_fits_them_and_keeps_older_checkpoints_identity():
    from bayes_inerter.inference.sampling.identity import _adaptation

    rng = np.random.default_rng(5)
    chain = rng.lognormal(size=(300, 20, 3))
    still = rng.normal(0.0, 1.0, size=(300, 20))
    adapt = Adaptation(every=400, knots=100, block_partners="correlated")
    assert adapt.fit(chain, still)[1].partners == "correlated"
    earlier = Adaptation(every=400, knots=100)
    assert earlier.fit(chain, still)[1].partners == "random"  # the default
    assert "its most correlated partners" in adapt.describe() and "partners" not in earlier.describe()
    # checkpoints written before the setting existed hold random blocks, the default:
    # their identity stays as it was
    assert "block_partners" not in _adaptation(Adaptation())
    assert _adaptation(adapt)["block_partners"] == "correlated"
    with pytest.raises(ValueError, match="block partners"):
        Adaptation(block_partners="nearest")


def test_the_command_lines_block_partners_are_the_packages():
    from bayes_inerter.cli import BLOCK_PARTNERS, DEFAULT_BLOCK_PARTNERS
    from bayes_inerter.inference.sampling.moves.block import PARTNERS

    assert BLOCK_PARTNERS == PARTNERS and DEFAULT_BLOCK_PARTNERS == Adaptation().block_partners


def test_a_checkpoint_of_other_block_moves_is_refused_by_name_and_one_without_blocks_kept():
    from bayes_inerter.inference.sampling.identity import _adaptation, mismatch

    def identity(adaptation):
        return {"format": 2, "adaptation": _adaptation(adaptation)}

    # an identity written before the setting existed (random blocks, no entry)
    before = {"format": 2, "adaptation": {"weight": 0.5, "every": 250, "dof": 10.0, "scale": 1.1, "wide": 0.2,
                                          "wide_scale": 3.0, "knots": 200, "blocks": 0.5}}
    assert mismatch(before, identity(Adaptation())) is None
    got = mismatch(before, identity(Adaptation(block_partners="correlated")))
    assert got is not None and "'random' then, 'correlated' now" in got.what and "--block-partners" in got.fix
    # without block moves the choice is no part of the kernel: earlier checkpoints match
    unblocked = {"format": 2, "adaptation": {**before["adaptation"], "knots": None, "blocks": 0.0}}
    assert "block_partners" not in _adaptation(Adaptation(knots=None, blocks=0.0))
    assert mismatch(unblocked, identity(Adaptation(knots=None, blocks=0.0))) is None


class _Chain:
    """A stand-in back end: the chain so far (steps, walkers, ndim) and its log posterior."""

    def __init__(self, chain, log_prob):
        self.chain, self.lp = chain, log_prob
        self.reads = 0

    def get_chain(self):
        self.reads += 1
        return self.chain

    def get_log_prob(self):
        return self.lp


def test_schedule_refits_once_per_period_from_the_chain_up_to_it():
    rng = np.random.default_rng(5)
    backend = _Chain(rng.normal(size=(600, 10, 2)), rng.normal(size=(600, 10)))
    base = [("a", 0.6), ("b", 0.4)]
    adapt = Adaptation(every=200, blocks=0.0)
    schedule = Schedule(base, adapt)
    assert schedule.moves_at(0, backend) == base  # nothing fitted before the first period
    assert schedule.used() == ("str 0.6", "str 0.4")
    assert schedule.end_of_stretch(0) == 200 and schedule.end_of_stretch(399) == 400
    first = schedule.moves_at(200, backend)
    again = schedule.moves_at(250, backend)  # the same stretch: the same fitted moves, not refitted
    assert backend.reads == 1 and [m for m, _ in first] == [m for m, _ in again]
    assert [w for _, w in first] == pytest.approx([0.3, 0.2, 0.5])
    assert schedule.used()[-1] == adapt.describe()
    later = schedule.moves_at(400, backend)
    assert backend.reads == 2 and later[2][0] is not first[2][0]


def test_schedule_without_adaptation_keeps_its_moves_in_fixed_stretches():
    schedule = Schedule([("a", 1.0)], None)
    assert schedule.moves_at(1234, None) == [("a", 1.0)]
    assert schedule.end_of_stretch(1234) == (1234 // STRETCH + 1) * STRETCH
    assert schedule.used() == ("str 1",)
