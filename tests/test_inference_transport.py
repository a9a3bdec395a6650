"""The triangular transport map: one to one with the right Jacobian, it straightens a
bent ridge that normal scores leave bent, and an independence move through it is an
exact move; ``Adaptation(transport=True)`` fits it and keeps the block move in the
normal scores alone."""

import emcee
import numpy as np
import pytest
from scipy import stats

from bayes_inerter.inference.sampling.adaptation import Adaptation
from bayes_inerter.inference.sampling.marginals import NormalScores
from bayes_inerter.inference.sampling.moves import BlockMove, IndependenceMove
from bayes_inerter.inference.sampling.transport import TriangularScores, quadratic_features

BEND = 0.8  # y = BEND x^2 + noise: a ridge a linear fit cannot follow
NOISE = 0.15


def _banana(n, rng):
    x = rng.normal(size=n)
    return np.column_stack([x, BEND * x ** 2 + NOISE * rng.normal(size=n), rng.normal(size=n)])


def _log_banana(p):
    p = np.atleast_2d(p)
    return (stats.norm.logpdf(p[:, 0]) + stats.norm.logpdf(p[:, 1], BEND * p[:, 0] ** 2, NOISE)
            + stats.norm.logpdf(p[:, 2]))


def test_quadratic_features_are_the_constant_columns_and_products():
    z = np.arange(6.0).reshape(2, 3)
    f = quadratic_features(z)
    assert f.shape == (2, 1 + 3 + 6)
    assert np.array_equal(f[1], [1, 3, 4, 5, 9, 12, 15, 16, 20, 25])
    assert quadratic_features(z[:, :0]).shape == (2, 1)


def test_far_proposals_map_to_finite_points():
    # a 12-coordinate chain with bends between neighbours: w far in the tails (the wide
    # t's draws) must come back finite, which quadratics of quadratics do not
    rng = np.random.default_rng(10)
    base = rng.normal(size=(5000, 12))
    x = base.copy()
    x[:, 1:] += 0.7 * base[:, :-1] ** 2
    tmap = TriangularScores.fit(x, 100)
    w = rng.normal(size=(2000, 12)) * 12.0
    back = tmap.inverse(w)
    assert np.all(np.isfinite(back))
    assert np.max(np.abs(tmap.forward(back)[0] - w)) < 1e-6 * np.max(np.abs(w))


def test_the_map_is_one_to_one_with_its_jacobian():
    draws = _banana(4000, np.random.default_rng(1))
    tmap = TriangularScores.fit(draws, 100)
    assert tmap.ndim == 3 and sorted(tmap.order) == [0, 1, 2]
    x = _banana(50, np.random.default_rng(2))
    w, log_jac = tmap.forward(x)
    assert np.max(np.abs(tmap.inverse(w) - x)) < 1e-9
    eps = 1e-6
    for k in range(10):
        jac = np.empty((3, 3))
        for i in range(3):
            e = np.zeros(3)
            e[i] = eps
            jac[:, i] = (tmap.forward(x[k] + e)[0][0] - tmap.forward(x[k] - e)[0][0]) / (2 * eps)
        assert log_jac[k] == pytest.approx(np.linalg.slogdet(jac)[1], abs=1e-5)


def test_the_map_straightens_a_bend_that_normal_scores_keep():
    draws = _banana(6000, np.random.default_rng(3))
    z = NormalScores.fit(draws, 100).forward(draws)[0]
    w = TriangularScores.fit(draws, 100).forward(draws)[0]
    # the bend: the ridge coordinate's mean given the other is quadratic in it
    bend_z = abs(np.corrcoef(z[:, 0] ** 2, z[:, 1])[0, 1])
    bend_w = max(abs(np.corrcoef(w[:, i] ** 2, w[:, j])[0, 1]) for i in range(3) for j in range(3) if i != j)
    assert bend_z > 0.5 and bend_w < 0.1
    # and an independence t fitted after the map is accepted far more often at equilibrium
    rng = np.random.default_rng(4)
    stationary = _banana(2000, rng)
    rates = []
    for move in (IndependenceMove.fit(draws, knots=100), Adaptation(knots=100, transport=True)._transported(
            draws, {"dof": 10.0, "scale": 1.1, "wide": 0.2, "wide_scale": 3.0})):
        y = move.draw(2000, np.random.RandomState(5))
        w_y = _log_banana(y) - move.log_density(y)
        w_x = _log_banana(stationary) - move.log_density(stationary)
        rates.append(float(np.mean(np.minimum(1.0, np.exp(np.clip(w_y - w_x, -700, 50))))))
    assert rates[1] > 1.5 * rates[0], rates


def _run_banana(move, steps=30, n=4000):
    sampler = emcee.EnsembleSampler(n, 3, _log_banana, moves=[move], vectorize=True)
    sampler.random_state = np.random.RandomState(6).get_state()
    sampler.run_mcmc(_banana(n, np.random.default_rng(7)), steps)  # exact draws: an exact move keeps them so
    x = sampler.get_last_sample().coords
    p = [stats.kstest(x[:, 0], stats.norm.cdf).pvalue, stats.kstest(x[:, 2], stats.norm.cdf).pvalue,
         stats.kstest((x[:, 1] - BEND * x[:, 0] ** 2) / NOISE, stats.norm.cdf).pvalue]
    return sampler, min(p)


class _WithoutMapJacobian(IndependenceMove):
    def log_density(self, x):
        return self._log_density(self.scores.forward(x)[0])


def test_an_independence_move_through_the_map_leaves_the_target_invariant():
    # fitted to other draws and made off centre, so the Hastings factor has work to do
    tmap = TriangularScores.fit(_banana(3000, np.random.default_rng(8)), 60)
    move = IndependenceMove(np.array([0.3, -0.2, 0.0]), np.diag([1.5, 0.7, 1.0]), scores=tmap)
    sampler, p = _run_banana(move)
    assert 0.05 < np.mean(sampler.acceptance_fraction) < 0.95
    assert p > 0.001  # three KS p-values of exact draws
    bad = _WithoutMapJacobian(np.array([0.3, -0.2, 0.0]), np.diag([1.5, 0.7, 1.0]), scores=tmap)
    assert _run_banana(bad)[1] < 1e-6


def test_adaptation_with_transport_fits_the_map_for_its_t_and_normal_scores_for_blocks():
    rng = np.random.default_rng(9)
    chain = _banana(300 * 20, rng).reshape(300, 20, 3)
    still = rng.normal(size=(300, 20))
    adapt = Adaptation(every=400, knots=100, transport=True)
    move, block = adapt.fit(chain, still)
    assert isinstance(move.scores, TriangularScores) and isinstance(block, BlockMove)
    assert block.scores is move.scores.scores  # the block move keeps each coordinate's own map
    assert "after a triangular quadratic map" in adapt.describe()
    assert not Adaptation().transport and "triangular" not in Adaptation().describe()
    with pytest.raises(ValueError, match="transport"):
        Adaptation(knots=None, blocks=0.0, transport=True)
    # too few draws for the map: the t without it (in normal scores where they allow)
    few = chain[:10, :1]  # 10 draws: the largest regression has 6 terms
    with pytest.raises(ValueError, match="too few"):
        TriangularScores.fit(few[:, 0], 4)
    move_few, _ = Adaptation(every=4, knots=4, transport=True, blocks=0.0).fit(few, still[:10, :1])
    assert move_few is not None and not isinstance(move_few.scores, TriangularScores)


def test_checkpoints_without_transport_keep_their_identity():
    from bayes_inerter.inference.sampling.identity import _adaptation

    assert "transport" not in _adaptation(Adaptation())
    assert _adaptation(Adaptation(transport=True))["transport"] is True
