"""The normal-scores map: its draws' scores are standard normal, it is one to one with
the Jacobian its density uses (beyond the knots too), and it is defined where draws
repeat values."""

import numpy as np
import pytest
from scipy import stats

from bayes_inerter.inference.sampling.marginals import NormalScores


def _skewed(n=20000, seed=0):
    rng = np.random.default_rng(seed)
    # a log-normal, a bounded (beta) and a heavy-tailed (t3) marginal, the first two correlated
    a = rng.lognormal(0.0, 0.8, size=n)
    return np.column_stack([a, stats.beta(2, 8).ppf(stats.norm.cdf(np.log(a) / 0.8)) + 0.01 * rng.normal(size=n),
                            rng.standard_t(3, size=n)])


def test_the_draws_scores_are_standard_normal():
    x = _skewed()
    ns = NormalScores.fit(x)
    z, _ = ns.forward(_skewed(seed=1))  # fresh draws of the same law
    for i in range(3):
        assert stats.kstest(z[:, i], "norm").statistic < 0.02
    assert np.corrcoef(z[:, 0], z[:, 1])[0, 1] > 0.9  # the dependence is kept for the t to fit


def test_the_map_is_one_to_one_inside_and_beyond_the_knots():
    ns = NormalScores.fit(_skewed(), knots=50)
    lo, hi = ns.x_knots[0], ns.x_knots[-1]
    span = hi - lo
    x = np.vstack([np.random.default_rng(2).uniform(lo - span, hi + span, size=(500, 3)), ns.x_knots])
    z, _ = ns.forward(x)
    np.testing.assert_allclose(ns.inverse(z), x, rtol=1e-12, atol=1e-12 * np.max(np.abs(x)))
    assert np.all(np.diff(ns.forward(np.sort(x, axis=0))[0], axis=0) >= 0)  # increasing
    # tails beyond the knots: straight lines, so the scores keep growing
    far = ns.forward(np.vstack([lo - 10 * span, hi + 10 * span]))[0]
    assert np.all(far[0] < -4.0) and np.all(far[1] > 4.0)


def test_the_log_jacobian_is_the_derivative_of_the_map():
    ns = NormalScores.fit(_skewed(), knots=50)
    rng = np.random.default_rng(3)
    lo, hi = ns.x_knots[0], ns.x_knots[-1]
    x = rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo), size=(200, 3))
    _, log_jac = ns.forward(x)
    h = 1e-7 * (hi - lo)
    fd = np.zeros(len(x))
    for i in range(3):
        step = np.zeros(3)
        step[i] = h[i]
        fd += np.log((ns.forward(x + step)[0][:, i] - ns.forward(x - step)[0][:, i]) / (2 * h[i]))
    # finite differences that straddle a knot see two slopes: compare where they do not
    assert np.mean(np.abs(fd - log_jac) < 1e-6) > 0.95


def test_repeated_values_still_give_a_strictly_increasing_map():
    rng = np.random.default_rng(4)
    x = rng.normal(size=(1000, 2))
    x[:600, 0] = 0.3  # a walker that stayed put: 60 % of one coordinate's draws equal
    ns = NormalScores.fit(x)
    assert np.all(np.diff(ns.x_knots, axis=0) > 0)
    z, log_jac = ns.forward(x)
    assert np.all(np.isfinite(z)) and np.all(np.isfinite(log_jac))
    np.testing.assert_allclose(ns.inverse(z), x, atol=1e-9)


def test_knots_are_capped_by_the_draws():
    assert len(NormalScores.fit(_skewed(n=500), knots=200).z_knots) == 50  # a knot per 10 draws


def test_the_map_refuses_what_defines_none():
    with pytest.raises(ValueError, match="too few"):
        NormalScores.fit(np.zeros((39, 2)))
    with pytest.raises(ValueError, match="finite"):
        NormalScores.fit(np.full((100, 2), np.nan))
    with pytest.raises(ValueError, match="knots"):
        NormalScores.fit(np.zeros((100, 2)), knots=3)
    with pytest.raises(ValueError, match="increasing"):
        NormalScores(np.zeros((5, 2)), np.arange(5.0))
    with pytest.raises(ValueError, match="k >= 4"):
        NormalScores(np.zeros((3, 2)), np.arange(3.0))


def _forward_column_by_column(scores, x):
    """The map written out a coordinate at a time, as it was before it ran on all at
    once: the reference the vectorised map must equal bit for bit."""
    xk, zk = scores.x_knots, scores.z_knots
    j0 = max(1, len(zk) // 10)
    lo = (zk[j0] - zk[0]) / (xk[j0] - xk[0])
    hi = (zk[-1] - zk[-1 - j0]) / (xk[-1] - xk[-1 - j0])
    z = np.empty_like(x)
    log_jac = np.zeros(len(x))
    for i in range(xk.shape[1]):
        slopes = np.diff(zk) / np.diff(xk[:, i])
        j = np.clip(np.searchsorted(xk[:, i], x[:, i], side="right") - 1, 0, len(zk) - 2)
        s = slopes[j]
        zi = zk[j] + s * (x[:, i] - xk[j, i])
        below, above = x[:, i] < xk[0, i], x[:, i] > xk[-1, i]
        zi = np.where(below, zk[0] + lo[i] * (x[:, i] - xk[0, i]), zi)
        z[:, i] = np.where(above, zk[-1] + hi[i] * (x[:, i] - xk[-1, i]), zi)
        log_jac += np.log(np.where(below, lo[i], np.where(above, hi[i], s)))
    return z, log_jac


def test_the_map_is_the_column_by_column_map_bit_for_bit():
    """The sampler's chains depend on the map's last digits: on all coordinates at once
    it gives what a coordinate at a time gives, inside, on and beyond the knots, on
    ties and on NaN."""
    rng = np.random.default_rng(3)
    for trial in range(40):
        d = int(rng.integers(1, 14))
        draws = rng.standard_normal((int(rng.integers(40, 2000)), d)) * rng.gamma(1.0, 3.0, size=d)
        if trial % 4 == 0:
            draws[:30, 0] = draws[0, 0]
        scores = NormalScores.fit(draws, int(rng.integers(4, 220)))
        x = draws[rng.integers(0, len(draws), 13)] + rng.standard_normal((13, d)) * (0.1, 5.0)[trial % 2]
        x[1] = scores.x_knots[int(rng.integers(0, len(scores.x_knots)))]
        x[2, 0] = np.nan
        got, expected = scores.forward(x), _forward_column_by_column(scores, x)
        assert np.array_equal(got[0], expected[0], equal_nan=True)
        assert np.array_equal(got[1], expected[1], equal_nan=True)


def test_the_inverse_is_np_interps_column_by_column_bit_for_bit():
    """The inverse on all coordinates at once gives what ``np.interp`` a coordinate at a
    time gives, between, on and beyond the knots, on the last knot and on NaN."""
    rng = np.random.default_rng(4)
    for trial in range(40):
        d = int(rng.integers(1, 14))
        draws = rng.standard_normal((int(rng.integers(40, 2000)), d)) * rng.gamma(1.0, 3.0, size=d)
        scores = NormalScores.fit(draws, int(rng.integers(4, 220)))
        xk, zk = scores.x_knots, scores.z_knots
        z = rng.standard_normal((13, d)) * (0.5, 3.0)[trial % 2]
        z[0] = zk[rng.integers(0, len(zk), d)]
        z[1] = zk[-1]
        z[2, 0] = np.nan
        j0 = max(1, len(zk) // 10)
        lo = (zk[j0] - zk[0]) / (xk[j0] - xk[0])
        hi = (zk[-1] - zk[-1 - j0]) / (xk[-1] - xk[-1 - j0])
        expected = np.empty_like(z)
        for i in range(d):
            xi = np.interp(z[:, i], zk, xk[:, i])
            xi = np.where(z[:, i] < zk[0], xk[0, i] + (z[:, i] - zk[0]) / lo[i], xi)
            expected[:, i] = np.where(z[:, i] > zk[-1], xk[-1, i] + (z[:, i] - zk[-1]) / hi[i], xi)
        assert np.array_equal(scores.inverse(z), expected, equal_nan=True)
