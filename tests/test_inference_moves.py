"""The moves of ``inference.sampling.moves``. The nut-ridge move: it must leave the target
invariant (its Jacobian matters), keep 1 / b - k_n / c_n^2 where it is, and be used only
where a model has the ridge. The independence move: invariant whatever proposal it is
given (its Hastings factor matters, and in normal scores the map's Jacobian), and fitted
only where draws define a proposal. The block move: invariant too, and it changes only
its block, from the block's conditional law."""

import emcee
import numpy as np
import pytest
from scipy import stats
from scipy.special import ndtri

from bayes_inerter.inference.sampling.marginals import NormalScores
from bayes_inerter.inference.sampling.moves import BlockMove, IndependenceMove, NutRidgeMove, ridge_indices
from bayes_inerter.inference.sampling.sampler import DEFAULT_MOVES, default_moves

# A target in (log b, log k_n, log c_n) where the Jacobian b'/b is far from 1: c_n near
# 1 and k_n spread over e^-2..e^2, so k_n / c_n^2 is as large as 1 / b.
SD = np.array([0.5, 1.0, 1.0])


def _log_target(x):
    return np.sum(stats.norm.logpdf(x, 0.0, SD), axis=1)


def _run(move, steps=30, n=4000):
    rng = np.random.default_rng(1)
    x0 = rng.normal(0.0, SD, size=(n, 3))  # exact draws: an invariant move keeps them so
    sampler = emcee.EnsembleSampler(n, 3, _log_target, moves=[move], vectorize=True)
    sampler.random_state = np.random.RandomState(2).get_state()
    sampler.run_mcmc(x0, steps)
    return sampler


class _WithoutJacobian(NutRidgeMove):
    def _propose(self, coords, random):
        q, factors = super()._propose(coords, random)
        return q, np.where(np.isfinite(factors), 0.0, factors)


def _ks_pvalues(sampler):
    x = sampler.get_last_sample().coords
    return [stats.kstest(x[:, i], stats.norm(0.0, SD[i]).cdf).pvalue for i in (0, 1, 2)]


def test_ridge_move_leaves_the_target_invariant():
    sampler = _run(NutRidgeMove(1, 2, [0]))
    assert 0.2 < np.mean(sampler.acceptance_fraction) < 0.9  # it does move
    assert min(_ks_pvalues(sampler)) > 0.01


def test_the_invariance_check_sees_a_missing_jacobian():
    # the same check on the move without its Jacobian: the marginals drift away
    assert min(_ks_pvalues(_run(_WithoutJacobian(1, 2, [0])))) < 1e-6


def test_ridge_move_keeps_the_apparent_inertance_of_every_b():
    move = NutRidgeMove(2, 3, [0, 1])
    coords = np.log([[800.0, 20000.0, 4e5, 2.2e6], [900.0, 15000.0, 1e7, 1e6]])
    q, factors = move._propose(coords, np.random.RandomState(0))

    def inv_app(x):
        return np.exp(-x[:, :2]) - (np.exp(x[:, 2]) / np.exp(2 * x[:, 3]))[:, None]

    assert np.all(q[:, 2] != coords[:, 2])
    np.testing.assert_array_equal(q[:, 3], coords[:, 3])  # c_n does not move
    np.testing.assert_allclose(inv_app(q), inv_app(coords), rtol=1e-9)
    np.testing.assert_allclose(factors, np.sum(q[:, :2] - coords[:, :2], axis=1))


def test_ridge_indices_and_default_moves():
    assert ridge_indices(["b", "f_0", "c_n", "k_n"], [True] * 4) == (3, 2, [0])
    assert ridge_indices(["b_A0", "b_B2", "k_n", "c_n", "rho"], [True] * 4 + [False]) == (2, 3, [0, 1])
    assert ridge_indices(["b", "f1_0", "c_f1"], [True] * 3) is None
    assert ridge_indices(["b", "k_n", "c_n"], [True, False, True]) is None

    class Model:
        names = ["b", "k_n", "c_n", "sigma"]
        all_priors = {n: type("P", (), {"log_scale": True})() for n in names}

    moves = default_moves(Model(), 0.25)
    assert isinstance(moves[-1][0], NutRidgeMove) and moves[-1][1] == 0.25
    assert sum(w for _, w in moves) == pytest.approx(1.0)
    assert default_moves(Model(), 0.0) == DEFAULT_MOVES
    with pytest.raises(ValueError, match="weight"):
        default_moves(Model(), 1.0)
    with pytest.raises(ValueError, match="0 < min <= max"):
        NutRidgeMove(0, 1, [2], scale_min=2.0, scale_max=1.0)


# A correlated normal in 4 dimensions: a move that ignored the correlation would still
# have to keep it.
COV = 0.9 * np.ones((4, 4)) + 0.1 * np.diag([1.0, 4.0, 9.0, 16.0])


def _run_gaussian(move, steps=40, n=2000):
    rng = np.random.default_rng(3)
    x0 = rng.multivariate_normal(np.zeros(4), COV, size=n)  # exact draws
    inv = np.linalg.inv(COV)
    sampler = emcee.EnsembleSampler(n, 4, lambda x: -0.5 * np.einsum("ij,jk,ik->i", x, inv, x),
                                    moves=[move], vectorize=True)
    sampler.random_state = np.random.RandomState(4).get_state()
    sampler.run_mcmc(x0, steps)
    x = sampler.get_last_sample().coords
    sd = np.sqrt(np.diag(COV))
    diff_sd = np.sqrt(COV[0, 0] + COV[3, 3] - 2 * COV[0, 3])
    p = [stats.kstest(x[:, i], stats.norm(0.0, sd[i]).cdf).pvalue for i in range(4)]
    p.append(stats.kstest(x[:, 0] - x[:, 3], stats.norm(0.0, diff_sd).cdf).pvalue)  # the correlation
    return sampler, min(p)


# A proposal that fits the target badly (off centre, too narrow in one direction, no
# correlation): the acceptance ratio, not the proposal, must make the draws the target's.
_OFF = dict(mean=np.array([0.5, -0.5, 0.0, 1.0]), cov=np.diag([1.0, 0.5, 9.0, 4.0]))


class _WithoutHastings(IndependenceMove):
    def _propose(self, coords, random):
        q, _ = super()._propose(coords, random)
        return q, np.zeros(len(q))


@pytest.mark.parametrize("dof, wide", [(10.0, 0.2), (np.inf, 0.0)])
def test_independence_move_leaves_the_target_invariant(dof, wide):
    sampler, p = _run_gaussian(IndependenceMove(**_OFF, dof=dof, wide=wide))
    assert 0.05 < np.mean(sampler.acceptance_fraction) < 0.9  # it does move
    assert p > 0.01


def test_the_invariance_check_sees_a_missing_hastings_factor():
    assert _run_gaussian(_WithoutHastings(**_OFF))[1] < 1e-6


def test_independence_move_fitted_to_the_targets_draws_is_accepted_often():
    rng = np.random.default_rng(6)
    move = IndependenceMove.fit(rng.multivariate_normal(np.zeros(4), COV, size=20000), dof=np.inf, scale=1.0,
                                wide=0.0)
    np.testing.assert_allclose(move.chol @ move.chol.T, COV, atol=0.05)
    sampler, p = _run_gaussian(move, steps=10)
    assert np.mean(sampler.acceptance_fraction) > 0.9  # the proposal is the target
    assert p > 0.01


def test_independence_move_log_density_is_the_t_the_normal_and_their_mixtures():
    cov = np.array([[2.0, 0.3], [0.3, 0.5]])
    x = np.random.default_rng(7).normal(0.0, 3.0, size=(6, 2))
    for dof, law in ((np.inf, lambda c: stats.multivariate_normal([0.0, 0.0], c)),
                     (4.0, lambda c: stats.multivariate_t([0.0, 0.0], c, df=4.0))):
        move = IndependenceMove(np.zeros(2), cov, dof=dof, scale=1.0, wide=0.0)
        got = move.log_density(x)
        ref = law(cov).logpdf(x)
        np.testing.assert_allclose(got - got[0], ref - ref[0], rtol=1e-10)
        # the defensive mixture: 0.7 of the fitted law, 0.3 of it 2.5 times wider
        move = IndependenceMove(np.zeros(2), cov, dof=dof, scale=1.0, wide=0.3, wide_scale=2.5)
        got = move.log_density(x)
        ref = np.log(0.7 * law(cov).pdf(x) + 0.3 * law(2.5**2 * cov).pdf(x))
        np.testing.assert_allclose(got - got[0], ref - ref[0], rtol=1e-10)


@pytest.mark.parametrize("dof", [4.0, np.inf])
def test_independence_move_draws_from_the_law_its_density_describes(dof):
    # one dimension: the draws against the exact CDF of the defensive mixture, 0.7 of the
    # fitted t (scale 1.1 x sd 2) and 0.3 of it 2.5 times wider
    move = IndependenceMove(np.array([1.0]), np.array([[4.0]]), dof=dof, scale=1.1, wide=0.3, wide_scale=2.5)
    q, _ = move._propose(np.zeros((40000, 1)), np.random.RandomState(9))
    law = stats.norm if np.isinf(dof) else stats.t(dof)
    s = 1.1 * 2.0

    def cdf(x):
        return 0.7 * law.cdf((x - 1.0) / s) + 0.3 * law.cdf((x - 1.0) / (2.5 * s))

    assert stats.kstest(q[:, 0], cdf).pvalue > 0.01
    # and the same check tells a wide part drawn too rarely (0.2 where the density says 0.3)
    rarely = IndependenceMove(np.array([1.0]), np.array([[4.0]]), dof=dof, scale=1.1, wide=0.2, wide_scale=2.5)
    q, _ = rarely._propose(np.zeros((40000, 1)), np.random.RandomState(9))
    assert stats.kstest(q[:, 0], cdf).pvalue < 1e-4


def test_independence_move_draws_its_wide_part_as_often_as_it_says():
    move = IndependenceMove(np.zeros(3), np.eye(3), dof=np.inf, scale=1.0, wide=0.25, wide_scale=10.0)
    q, _ = move._propose(np.zeros((20000, 3)), np.random.RandomState(8))
    far = np.linalg.norm(q, axis=1) > 5.0  # beyond 5 sd of the fitted part: the wide part's draws
    assert far.mean() == pytest.approx(0.25 * stats.chi2(3).sf(0.25), abs=0.01)


def test_independence_move_refuses_what_defines_no_proposal():
    assert IndependenceMove.fit(np.ones((50, 3))) is None  # walkers on one point
    assert IndependenceMove.fit(np.random.default_rng(0).normal(size=(3, 3))) is None  # too few draws
    assert IndependenceMove.fit(np.full((10, 2), np.nan)) is None
    with pytest.raises(ValueError, match="do not match"):
        IndependenceMove(np.zeros(3), np.eye(2))
    with pytest.raises(ValueError, match="positive"):
        IndependenceMove(np.zeros(2), np.eye(2), dof=0.0)
    with pytest.raises(ValueError, match="wide part"):
        IndependenceMove(np.zeros(2), np.eye(2), wide=1.0)
    with pytest.raises(np.linalg.LinAlgError):
        IndependenceMove(np.zeros(2), -np.eye(2))
    # one t only: the fit gives a single mean and factor
    draws = np.random.default_rng(0).normal(size=(100, 2))
    fitted = IndependenceMove.fit(draws)
    assert fitted.mean.shape == (2,) and fitted.chol.shape == (2, 2)


# A normal-scores map far from the identity (fitted to log-normal draws): the t lives in
# its scores, so the proposal in x is skewed; the Jacobian must enter its density.
_SCORES = NormalScores.fit(np.random.default_rng(12).lognormal(0.0, 0.7, size=(5000, 4)) - 1.0, knots=100)


class _WithoutScoresJacobian(IndependenceMove):
    def log_density(self, x):
        return self._log_density(self.scores.forward(x)[0])


@pytest.mark.parametrize("dof, wide", [(10.0, 0.2), (np.inf, 0.0)])
def test_a_proposal_in_normal_scores_leaves_the_target_invariant(dof, wide):
    sampler, p = _run_gaussian(IndependenceMove(np.zeros(4), np.eye(4), dof=dof, wide=wide, scores=_SCORES))
    assert 0.05 < np.mean(sampler.acceptance_fraction) < 0.9
    # the smallest of 5 KS p-values of exact draws: below 0.001 about 0.5 % of the time,
    # against < 1e-6 without the Hastings factor or the map's Jacobian (below)
    assert p > 0.001


def test_a_proposal_in_normal_scores_without_its_jacobian_is_caught():
    assert _run_gaussian(_WithoutScoresJacobian(np.zeros(4), np.eye(4), scores=_SCORES))[1] < 1e-6


def test_normal_scores_draws_follow_their_density():
    # one dimension: the CDF of the density, integrated numerically, against the draws
    ns = NormalScores.fit(np.random.default_rng(13).gamma(2.0, size=(4000, 1)), knots=40)
    move = IndependenceMove(np.array([0.2]), np.array([[1.5]]), dof=5.0, scale=1.0, wide=0.3, wide_scale=2.0,
                            scores=ns)
    q, _ = move._propose(np.zeros((40000, 1)), np.random.RandomState(14))
    grid = np.linspace(q.min() - 1.0, q.max() + 1.0, 400_001)
    dens = np.exp(move.log_density(grid[:, None]))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(grid))])
    cdf /= cdf[-1]
    assert stats.kstest(q[:, 0], lambda v: np.interp(v, grid, cdf)).pvalue > 0.01
    # and the same check tells a density without the map's Jacobian
    bad = np.exp(_WithoutScoresJacobian(np.array([0.2]), np.array([[1.5]]), dof=5.0, scale=1.0, wide=0.3,
                                        wide_scale=2.0, scores=ns).log_density(grid[:, None]))
    cdf_bad = np.concatenate([[0.0], np.cumsum(0.5 * (bad[1:] + bad[:-1]) * np.diff(grid))])
    cdf_bad /= cdf_bad[-1]
    assert stats.kstest(q[:, 0], lambda v: np.interp(v, grid, cdf_bad)).pvalue < 1e-4


def test_fit_in_normal_scores_follows_a_skewed_target():
    # a law whose copula is normal and whose marginals are not (log-normal, logit-normal,
    # sinh-normal: skewed, bounded, heavy-tailed): proposals fitted in its normal scores
    # are accepted far more often than a t fitted to it in x
    cov = np.array([[1.0, 0.8, 0.5], [0.8, 1.0, 0.6], [0.5, 0.6, 1.0]])
    law = stats.multivariate_normal(np.zeros(3), cov)

    def to_x(z):
        return np.column_stack([np.exp(z[:, 0]), 1.0 / (1.0 + np.exp(-2.0 * z[:, 1])), np.sinh(z[:, 2])])

    def log_target(x):  # law's density carried to x by the Jacobian of x -> z
        z = np.column_stack([np.log(x[:, 0]), 0.5 * np.log(x[:, 1] / (1.0 - x[:, 1])), np.arcsinh(x[:, 2])])
        return law.logpdf(z) - np.log(x[:, 0]) - np.log(2.0 * x[:, 1] * (1.0 - x[:, 1])) - np.log(np.cosh(z[:, 2]))

    draws = to_x(law.rvs(size=40000, random_state=15))
    plain = IndependenceMove.fit(draws[:20000], dof=np.inf, scale=1.0, wide=0.0)
    scored = IndependenceMove.fit(draws[:20000], knots=200, dof=np.inf, scale=1.0, wide=0.0)
    assert plain.scores is None and scored.scores is not None

    def acceptance(move):
        x = draws[20000:]
        y, _ = move._propose(np.zeros((20000, 3)), np.random.RandomState(16))
        with np.errstate(invalid="ignore", divide="ignore"):  # proposals outside the law's support
            lwx, lwy = log_target(x) - move.log_density(x), log_target(y) - move.log_density(y)
        return np.mean(np.exp(np.minimum(0.0, np.nan_to_num(lwy - lwx, nan=-np.inf))))

    assert acceptance(scored) > 0.8 > 0.5 > acceptance(plain)  # measured: 0.89 and 0.23
    # too few draws for a map (40): the t in x
    assert IndependenceMove.fit(draws[:30], knots=200).scores is None
    with pytest.raises(ValueError, match="coordinates"):
        IndependenceMove(np.zeros(3), np.eye(3), scores=_SCORES)


class _BlockWithoutJacobian(BlockMove):
    def _propose(self, coords, random):
        q, factors = super()._propose(coords, random)
        return q, factors - self.scores.forward(np.asarray(coords))[1] + self.scores.forward(q)[1]


class _BlockWithoutHastings(BlockMove):
    def _propose(self, coords, random):
        q, _ = super()._propose(coords, random)
        return q, np.zeros(len(q))


@pytest.mark.parametrize("sizes, wide", [((1, 2, 3), 0.1), ((4,), 0.0)])
def test_block_move_leaves_the_target_invariant(sizes, wide):
    # the normal in scores is off the target (the map is fitted to log-normal draws)
    sampler, p = _run_gaussian(BlockMove(np.full(4, 0.3), np.diag([1.0, 2.0, 0.5, 1.0]), _SCORES, sizes=sizes,
                                         wide=wide), steps=30)
    assert 0.05 < np.mean(sampler.acceptance_fraction) < 0.95
    assert p > 0.001  # as for the proposal in normal scores: the smallest of 5 p-values


def test_correlated_block_move_leaves_the_target_invariant():
    # the fitted normal's correlations (not the target's) choose the blocks
    cov = np.array([[1.0, 0.0, 0.8, 0.0], [0.0, 2.0, 0.0, -0.9], [0.8, 0.0, 1.0, 0.0], [0.0, -0.9, 0.0, 1.0]])
    sampler, p = _run_gaussian(BlockMove(np.full(4, 0.3), cov, _SCORES, sizes=(1, 2, 3), partners="correlated"),
                               steps=30)
    assert 0.05 < np.mean(sampler.acceptance_fraction) < 0.95
    assert p > 0.001


def test_correlated_blocks_are_a_coordinate_and_its_most_correlated_partners():
    # pairs (0, 2) and (1, 3) tied, 3 weakly to 0: a block of two is always a tied pair,
    # a block of three adds the next most correlated; the random blocks seldom tie the pair
    cov = np.array([[1.0, 0.0, 0.8, 0.2], [0.0, 1.0, 0.0, -0.7], [0.8, 0.0, 1.0, 0.0], [0.2, -0.7, 0.0, 1.0]])
    zk = ndtri((np.arange(50) + 0.5) / 50)
    scores = NormalScores(np.column_stack([zk] * 4), zk)
    x = np.random.default_rng(41).multivariate_normal(np.zeros(4), cov, size=4000)
    moved = {}
    for partners in ("random", "correlated"):
        move = BlockMove(np.zeros(4), cov, scores, sizes=(2,), partners=partners)
        q, _ = move._propose(x, np.random.RandomState(43))
        moved[partners] = {tuple(np.flatnonzero(row)) for row in q != x}, (q != x)
    assert moved["correlated"][0] == {(0, 2), (1, 3)}
    assert len(moved["random"][0]) == 6  # every pair of four
    np.testing.assert_array_equal(BlockMove(np.zeros(4), cov, scores, partners="correlated").neighbours[:, :3],
                                  [[0, 2, 3], [1, 3, 0], [2, 0, 1], [3, 1, 0]])
    with pytest.raises(ValueError, match="partners"):
        BlockMove(np.zeros(4), cov, scores, partners="nearest")


@pytest.mark.parametrize("partners", ["random", "correlated"])
@pytest.mark.parametrize("broken", [_BlockWithoutJacobian, _BlockWithoutHastings])
def test_the_invariance_check_sees_a_block_move_without_its_factors(broken, partners):
    cov = np.array([[1.0, 0.0, 0.8, 0.0], [0.0, 2.0, 0.0, -0.9], [0.8, 0.0, 1.0, 0.0], [0.0, -0.9, 0.0, 1.0]])
    move = broken(np.full(4, 0.3), cov if partners == "correlated" else np.diag([1.0, 2.0, 0.5, 1.0]), _SCORES,
                  partners=partners)
    assert _run_gaussian(move, steps=30)[1] < 1e-6


def test_block_move_changes_only_its_block_and_follows_the_conditional():
    # a correlated normal target and the identity as the map: a one-coordinate block's
    # proposal (scale 1, no wide part) is then the target's conditional, accepted always
    cov = np.array([[1.0, 0.9], [0.9, 1.0]])
    zk = ndtri((np.arange(50) + 0.5) / 50)
    move = BlockMove([0.0, 0.0], cov, NormalScores(np.column_stack([zk, zk]), zk), sizes=(1,), scale=1.0, wide=0.0)
    x = np.random.default_rng(18).multivariate_normal([0.0, 0.0], cov, size=4000)
    q, factors = move._propose(x, np.random.RandomState(19))
    changed = q != x
    assert np.all(changed.sum(axis=1) == 1)
    # each coordinate moved about half the time, its new value from the conditional N(0.9 x_other, 0.19)
    assert changed[:, 0].mean() == pytest.approx(0.5, abs=0.03)
    rows = changed[:, 0]
    assert stats.kstest((q[rows, 0] - 0.9 * x[rows, 1]) / np.sqrt(0.19), "norm").pvalue > 0.001
    log_p = stats.multivariate_normal([0.0, 0.0], cov).logpdf
    np.testing.assert_allclose(log_p(q) - log_p(x) + factors, 0.0, atol=1e-9)
    # fitted to draws, the map is near the identity and the proposal near the conditional
    draws = np.random.default_rng(17).multivariate_normal([0.0, 0.0], cov, size=20000)
    fitted = BlockMove.fit(draws, knots=200, sizes=(1,), scale=1.0, wide=0.0)
    q, factors = fitted._propose(x, np.random.RandomState(19))
    assert np.median(np.abs(log_p(q) - log_p(x) + factors)) < 0.2


def test_block_moves_of_every_size_are_the_conditional_law_at_once():
    # a correlated 4-d normal target and the identity as the map: with scale 1 and no wide
    # part each walker's block proposal is the target's conditional given its rest, so the
    # Metropolis-Hastings ratio is exactly one whatever the block, in the batched proposal
    cov = np.array([[1.0, 0.5, 0.1, 0.0], [0.5, 2.0, 0.3, 0.2], [0.1, 0.3, 0.5, 0.1], [0.0, 0.2, 0.1, 1.0]])
    zk = ndtri((np.arange(50) + 0.5) / 50)
    move = BlockMove(np.zeros(4), cov, NormalScores(np.column_stack([zk] * 4), zk), sizes=(1, 2, 3), scale=1.0,
                     wide=0.0)
    x = np.random.default_rng(29).multivariate_normal(np.zeros(4), cov, size=6000)
    q, factors = move._propose(x, np.random.RandomState(31))
    log_p = stats.multivariate_normal(np.zeros(4), cov).logpdf
    np.testing.assert_allclose(log_p(q) - log_p(x) + factors, 0.0, atol=1e-9)
    moved = (q != x).sum(axis=1)
    assert set(np.unique(moved)) == {1, 2, 3}
    np.testing.assert_allclose(np.bincount(moved)[1:] / len(x), 1 / 3, atol=0.03)
    # every coordinate is in a block equally often: 2 of 4 on average
    np.testing.assert_allclose((q != x).mean(axis=0), 0.5, atol=0.03)
    # the same random state, the same proposals
    again = move._propose(x, np.random.RandomState(31))
    np.testing.assert_array_equal(q, again[0])
    np.testing.assert_array_equal(factors, again[1])


def test_block_move_refuses_what_defines_none():
    assert BlockMove.fit(np.ones((100, 3)), knots=50) is None
    assert BlockMove.fit(np.zeros((2, 3)), knots=50) is None
    with pytest.raises(ValueError, match="normal-scores map or the knots"):
        BlockMove.fit(np.random.default_rng(0).normal(size=(100, 3)))


def test_block_move_fitted_in_a_given_map_is_the_one_fitted_with_its_knots():
    draws = np.random.default_rng(23).lognormal(size=(4000, 3))
    scores = NormalScores.fit(draws, 100)
    given, own = BlockMove.fit(draws, scores=scores), BlockMove.fit(draws, knots=100)
    assert given.scores is scores
    np.testing.assert_array_equal(given.mean, own.mean)
    np.testing.assert_array_equal(given.precision, own.precision)
    with pytest.raises(ValueError, match="block sizes"):
        BlockMove(np.zeros(4), np.eye(4), _SCORES, sizes=(5,))
    with pytest.raises(ValueError, match="do not match"):
        BlockMove(np.zeros(3), np.eye(3), _SCORES)
